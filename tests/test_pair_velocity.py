"""The contact solve carries a manifold's two bodies' velocities as one value
(physics_core/collision/pair_velocity.py) and must do exactly what the
array forms do (contact_build.row_velocity, sequential_impulses.apply_impulse)
on the contact rows and on the friction anchors' table, which has the rows'
column layout: the same operations in the same order, so the same bits.
Random rows and velocities, compared with == (no tolerance)."""
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from physics_core.collision.contact_build import row_velocity
from physics_core.collision.contact_layout import NCOL
from physics_core.collision.manifold_friction import MCOL
from physics_core.collision.pair_velocity import load_pair, pair_impulse, pair_velocity, store_pair
from physics_core.collision.sequential_impulses import apply_impulse

SEEDS = st.integers(0, 2 ** 32 - 1)
TABLES = st.sampled_from([NCOL, MCOL])      # the contact rows, the anchors


def _case(seed, columns):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 6))
    a, b = (int(i) for i in rng.choice(n, 2, replace=False))
    table = rng.normal(size=(3, columns)) * 10.0 ** rng.integers(-3, 4, size=(3, columns))
    vel, omega = rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
    return rng, table, a, b, vel, omega


@settings(max_examples=120, deadline=None)
@given(seed=SEEDS, columns=TABLES)
def test_pair_velocity_is_row_velocity_bit_for_bit(seed, columns):
    _, T, a, b, vel, omega = _case(seed, columns)
    p = load_pair(vel, omega, a, b)
    for k in range(len(T)):
        for r in range(3):
            assert pair_velocity(T, k, r, p) == row_velocity(T, k, r, a, b, vel, omega)


@settings(max_examples=120, deadline=None)
@given(seed=SEEDS, columns=TABLES)
def test_pair_impulses_are_apply_impulse_bit_for_bit(seed, columns):
    """A sequence of impulses on several entries: the pair stored once at
    the end equals the arrays updated entry by entry."""
    rng, T, a, b, vel, omega = _case(seed, columns)
    v_rows, w_rows = vel.copy(), omega.copy()
    p = load_pair(vel, omega, a, b)
    for _ in range(6):
        k, r, lam = int(rng.integers(3)), int(rng.integers(3)), float(rng.normal())
        apply_impulse(T, k, r, lam, a, b, v_rows, w_rows)
        p = pair_impulse(T, k, r, lam, p)
    store_pair(vel, omega, a, b, p)
    np.testing.assert_array_equal(vel, v_rows)
    np.testing.assert_array_equal(omega, w_rows)
