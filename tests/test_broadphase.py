"""Broad phase: the grid finds exactly the pairs a brute-force O(n²) test finds."""
import itertools
from types import SimpleNamespace

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from physics_core import quaternion as qt
from numpy_reference.broadphase import (aabb_half_extents, bounding_radius, candidate_pairs,
                                               overlapping_pairs, plane_pairs)
from physics_core.collision.manifold import detect
from physics_core.shapes import BOX, PLANE, SPHERE


def make_model(shape_type, radius=None, half=None, static=None, normal=None, offset=None):
    """The fields of a Model that collision detection reads."""
    n = len(shape_type)
    st_ = np.asarray(shape_type)
    return SimpleNamespace(
        n=n, shape_type=st_,
        radius=np.zeros(n) if radius is None else np.asarray(radius, float),
        half_extents=np.zeros((n, 3)) if half is None else np.asarray(half, float),
        is_static=(st_ == PLANE) if static is None else np.asarray(static, bool) | (st_ == PLANE),
        plane_normal=np.tile([0.0, 0.0, 1.0], (n, 1)) if normal is None else np.asarray(normal, float),
        plane_offset=np.zeros(n) if offset is None else np.asarray(offset, float))


def brute_overlaps(lo, hi, centre=None, reach=None):
    out = set()
    for i, j in itertools.combinations(range(len(lo)), 2):
        if np.all(lo[i] <= hi[j]) and np.all(lo[j] <= hi[i]):
            if centre is None or np.sum((centre[i] - centre[j]) ** 2) <= (reach[i] + reach[j]) ** 2:
                out.add((i, j))
    return out


def random_scene(rng, n, spread, planes=1, static_fraction=0.2, big_fraction=0.05):
    kinds = rng.choice([SPHERE, BOX], size=n)
    kinds[:planes] = PLANE
    size = rng.uniform(0.05, 0.5, n)
    big = rng.random(n) < big_fraction
    size[big] *= 20.0
    half = np.stack([size * rng.uniform(0.2, 1.0, n) for _ in range(3)], axis=1)
    normal = rng.normal(size=(n, 3))
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    model = make_model(kinds, radius=size, half=half, static=rng.random(n) < static_fraction,
                       normal=normal, offset=rng.uniform(-spread, 0.0, n))
    pos = rng.uniform(-spread, spread, (n, 3))
    quat = qt.normalize(rng.normal(size=(n, 4)))
    return model, pos, quat


def brute_candidates(model, pos, quat, margin):
    half = aabb_half_extents(model, quat) + 0.5 * margin
    reach = bounding_radius(model) + 0.5 * margin
    out = set()
    for i, j in itertools.combinations(range(model.n), 2):
        ti, tj = model.shape_type[i], model.shape_type[j]
        if model.is_static[i] and model.is_static[j]:
            continue
        if PLANE in (ti, tj):
            p, b = (i, j) if ti == PLANE else (j, i)
            n = model.plane_normal[p]
            R = qt.to_matrix(quat[b:b + 1])[0]
            low = model.radius[b] if model.shape_type[b] == SPHERE else np.abs(R.T @ n) @ model.half_extents[b]
            if n @ pos[b] - model.plane_offset[p] - low < margin:
                out.add((p, b))
            continue
        if (np.all(pos[i] - half[i] <= pos[j] + half[j]) and np.all(pos[j] - half[j] <= pos[i] + half[i])
                and np.sum((pos[i] - pos[j]) ** 2) <= (reach[i] + reach[j]) ** 2):
            a, b = (j, i) if model.is_static[j] and not model.is_static[i] else (i, j)
            out.add((a, b))
    return out


@settings(max_examples=200, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), n=st.integers(0, 60), spread=st.floats(0.1, 20.0),
       big=st.floats(0.0, 0.7), spheres=st.booleans())
def test_overlapping_pairs_match_brute_force(seed, n, spread, big, spheres):
    rng = np.random.default_rng(seed)
    centre = rng.uniform(-spread, spread, (n, 3))
    half = rng.uniform(0.01, 1.0, (n, 3)) * np.where(rng.random((n, 1)) < big, 10.0, 1.0)
    lo, hi = centre - half, centre + half
    reach = np.linalg.norm(half, axis=1) * rng.uniform(0.5, 1.0, n) if spheres else None
    i, j = overlapping_pairs(lo, hi, centre if spheres else None, reach)
    assert np.all(i < j)
    got = set(zip(i.tolist(), j.tolist()))
    assert len(got) == len(i), "each pair once"
    assert got == brute_overlaps(lo, hi, centre if spheres else None, reach)


@settings(max_examples=100, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), n=st.integers(1, 50), spread=st.floats(0.5, 10.0),
       margin=st.sampled_from([0.0, 0.01, 0.2]), planes=st.integers(0, 3))
def test_candidate_pairs_match_brute_force(seed, n, spread, margin, planes):
    rng = np.random.default_rng(seed)
    model, pos, quat = random_scene(rng, n + planes, spread, planes=planes)
    a, b = candidate_pairs(model, pos, quat, margin)
    got = list(zip(a.tolist(), b.tolist()))
    assert len(set(got)) == len(got)
    assert set(got) == brute_candidates(model, pos, quat, margin)
    pid = np.minimum(a, b) * model.n + np.maximum(a, b)
    assert np.all(np.diff(pid) > 0), "sorted by (min, max)"
    both_dynamic = ~model.is_static[a] & ~model.is_static[b]
    assert np.all(a[both_dynamic] < b[both_dynamic])
    assert not np.any(model.is_static[b] & ~model.is_static[a]), "a static body is always a"


def test_plane_pairs_only_dynamic_bodies_near_the_plane():
    model = make_model([PLANE, SPHERE, SPHERE, BOX, BOX], radius=[0, 0.5, 0.5, 0, 0],
                       half=[[0, 0, 0], [0, 0, 0], [0, 0, 0], [0.5, 0.5, 0.5], [0.5, 0.5, 0.5]],
                       static=[True, False, True, False, False])
    pos = np.array([[0, 0, 0], [0, 0, 0.45], [0, 0, 0.2], [2, 0, 0.55], [4, 0, 0.4]], float)
    quat = np.tile([1.0, 0, 0, 0], (5, 1))
    p, b = plane_pairs(model, pos, quat, margin=0.0)
    assert b.tolist() == [1, 4] and p.tolist() == [0, 0]     # the static sphere is skipped
    p, b = plane_pairs(model, pos, quat, margin=0.1)
    assert b.tolist() == [1, 3, 4]


def test_far_apart_bodies_use_the_sparse_path():
    # a few bodies spread over 10 km: far more cells than bodies (searchsorted path)
    rng = np.random.default_rng(1)
    centre = np.concatenate([rng.uniform(-5e3, 5e3, (40, 3)), np.array([[0, 0, 0], [0.15, 0, 0]])])
    half = np.full((42, 3), 0.1)
    i, j = overlapping_pairs(centre - half, centre + half)
    assert set(zip(i.tolist(), j.tolist())) == brute_overlaps(centre - half, centre + half)
    assert (40, 41) in set(zip(i.tolist(), j.tolist()))


def test_huge_spread_coarsens_the_grid_but_stays_exact():
    centre = np.array([[0, 0, 0], [0.1, 0, 0], [1e9, 0, 0], [1e9, 0.1, 0], [-1e9, 5, 5]], float)
    half = np.full((5, 3), 0.06)
    i, j = overlapping_pairs(centre - half, centre + half)
    assert list(zip(i.tolist(), j.tolist())) == [(0, 1), (2, 3)] or \
        set(zip(i.tolist(), j.tolist())) == {(0, 1), (2, 3)}


def sphere_pile(side, r=0.1, overlap=0.002):
    """side³ spheres in a cubic grid, neighbours overlapping by `overlap`,
    the bottom layer sinking `overlap` into the plane z = 0."""
    n = side ** 3
    g = np.stack(np.meshgrid(*[np.arange(side)] * 3, indexing="ij"), -1).reshape(-1, 3)
    pos = np.concatenate([[[0.0, 0.0, 0.0]], g * (2 * r - overlap) + [0, 0, r - overlap]])
    model = make_model([PLANE] + [SPHERE] * n, radius=[0.0] + [r] * n)
    return model, pos, np.tile([1.0, 0, 0, 0], (n + 1, 1))


def test_sphere_pile_contact_count():
    side = 8
    model, pos, quat = sphere_pile(side)
    m = detect(model, pos, quat)
    plane = m.a == 0
    assert plane.sum() == side * side
    assert (~plane).sum() == 3 * side * side * (side - 1)     # face neighbours only
    np.testing.assert_allclose(m.depth, 0.002, atol=1e-12)


def test_detect_is_deterministic():
    rng = np.random.default_rng(7)
    model, pos, quat = random_scene(rng, 300, 3.0, planes=2)
    m1, m2 = detect(model, pos, quat, 0.05), detect(model, pos, quat, 0.05)
    for f in ("a", "b", "point", "normal", "depth", "key"):
        assert np.array_equal(getattr(m1, f), getattr(m2, f))
    assert np.all(np.diff(m1.key) > 0)
    assert np.all(np.isfinite(m1.point)) and np.all(np.isfinite(m1.normal))


def test_thousands_of_boxes_match_brute_force():
    """More bodies than one grid block, mixed sizes, with a few large ones."""
    rng = np.random.default_rng(11)
    n = 2500
    centre = rng.uniform(-4, 4, (n, 3))
    half = rng.uniform(0.02, 0.15, (n, 3))
    half[:10] *= 30.0
    lo, hi = centre - half, centre + half
    i, j = overlapping_pairs(lo, hi)
    hit = np.all((lo[:, None, :] <= hi[None, :, :]) & (lo[None, :, :] <= hi[:, None, :]), axis=2)
    bi, bj = np.nonzero(np.triu(hit, k=1))
    assert sorted(zip(i.tolist(), j.tolist())) == sorted(zip(bi.tolist(), bj.tolist()))
