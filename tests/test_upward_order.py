"""The shock sweep's manifold order (shock_propagation._upward_order): the
manifolds between two support layers, by (higher layer, the body in it),
key order within, so that a layer's manifolds come in one run per body
they hold up. Made by two counting sorts; checked against the stable
argsort of the rank higher × (n + 1) + upper body, on random layers and
contact graphs (Hypothesis), with unreached bodies and manifolds within
one layer left out. A manifold with one body unreached (no breadth-first
search gives one) is left out too, not indexed by its layer.
"""
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from physics_core.collision import shock_propagation as SP
from physics_core.collision.contact_layout import BODY_A, BODY_B, ICOL
from physics_core.collision.manifold_friction import FIRST, MICOL
from physics_core.collision.scratch import empty_store


def _reference(I, MI, layer):
    n = len(layer)
    la, lb = layer[I[MI[:, FIRST], BODY_A]], layer[I[MI[:, FIRST], BODY_B]]
    top, lo = np.maximum(la, lb), np.minimum(la, lb)
    upper = np.where(la > lb, I[MI[:, FIRST], BODY_A], I[MI[:, FIRST], BODY_B])
    rank = np.where((lo == SP.UNREACHED) | (lo == top), SP.UNREACHED, top * (n + 1) + upper)
    order = np.argsort(rank, kind="mergesort")
    order = order[rank[order] != SP.UNREACHED]
    return order, top[order], upper[order]


@settings(max_examples=300, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), n=st.integers(2, 60), manifolds=st.integers(0, 120),
       unreached=st.floats(0.0, 0.5))
def test_upward_order_is_the_stable_sort_by_layers(seed, n, manifolds, unreached):
    rng = np.random.default_rng(seed)
    layer = rng.integers(0, max(1, n // 3), n).astype(np.int64)
    layer[rng.random(n) < unreached] = SP.UNREACHED
    I = np.zeros((manifolds, ICOL), np.int64)
    I[:, BODY_A] = rng.integers(0, n, manifolds)
    # as breadth-first layers have it: a body touching a reached one is reached
    for group in (layer == SP.UNREACHED, layer != SP.UNREACHED):
        members = np.flatnonzero(group)
        pick = group[I[:, BODY_A]]
        I[pick, BODY_B] = rng.choice(members, pick.sum()) if pick.any() else []
    MI = np.zeros((manifolds, MICOL), np.int64)
    MI[:, FIRST] = np.arange(manifolds)
    order, tops, uppers = SP._upward_order(I, MI, layer, empty_store())
    want_order, want_tops, want_uppers = _reference(I, MI, layer)
    assert np.array_equal(order, want_order)
    assert np.array_equal(tops, want_tops)
    assert np.array_equal(uppers, want_uppers)


def test_a_manifold_with_one_body_unreached_is_left_out():
    """Not made by support_layers, but a counting sort indexed by UNREACHED
    would write far outside its table."""
    layer = np.array([0, 1, SP.UNREACHED, 2], np.int64)
    I = np.array([[0, 1, 0], [1, 2, 0], [3, 1, 0]], np.int64)
    MI = np.zeros((3, MICOL), np.int64)
    MI[:, FIRST] = np.arange(3)
    order, tops, uppers = SP._upward_order(I, MI, layer, empty_store())
    assert order.tolist() == [0, 2] and tops.tolist() == [1, 2] and uppers.tolist() == [1, 3]
