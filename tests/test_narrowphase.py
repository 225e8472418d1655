"""Narrow phase: contact point, normal (a → b) and depth for each shape pair,
against hand-computed answers (COURSE.md 5)."""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from physics_core import quaternion as qt
from physics_core.collision.manifold import SLOTS, Manifold, detect
from numpy_reference.narrow_box import AXIS_TOL, box_box_separation
from physics_core.scene_loader import build_model

TOL = 1e-9


def sphere(name, r, pos, static=False):
    b = {"name": name, "shape": {"type": "sphere", "radius": r},
         "position": [float(x) for x in pos]}
    if static:
        b["static"] = True
    else:
        b["mass"] = 1.0
    return b


def box(name, half, pos, quat=(1.0, 0.0, 0.0, 0.0), static=False):
    b = {"name": name, "shape": {"type": "box", "half_extents": [float(x) for x in half]},
         "position": [float(x) for x in pos], "orientation": [float(x) for x in quat]}
    if static:
        b["static"] = True
    else:
        b["mass"] = 1.0
    return b


def plane(name="ground", normal=(0.0, 0.0, 1.0), offset=0.0):
    return {"name": name, "shape": {"type": "plane", "normal": [float(x) for x in normal],
                                    "offset": float(offset)}}


def run(*bodies, margin=0.0):
    model = build_model({"dt": 0.01, "bodies": list(bodies)})
    m = detect(model, np.array(model.initial["pos"]), np.array(model.initial["quat"]), margin)
    assert np.all(np.isfinite(m.point)) and np.all(np.isfinite(m.normal)) and np.all(np.isfinite(m.depth))
    if len(m):
        np.testing.assert_allclose(np.linalg.norm(m.normal, axis=1), 1.0, atol=1e-12)
        assert np.all(np.diff(m.key) > 0), "keys sorted and unique"
    return model, m


def axis_angle(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    return np.concatenate([[math.cos(angle / 2)], math.sin(angle / 2) * axis])


def rows_sorted(points):
    """Points in a fixed order, to compare sets of contact points."""
    p = np.asarray(points)
    return p[np.lexsort(np.round(p, 9).T[::-1])]


# ---- manifold ---------------------------------------------------------------

def test_empty_and_concat():
    e = Manifold.empty()
    assert len(e) == 0 and e.point.shape == (0, 3) and e.key.dtype == np.int64
    _, m = run(sphere("a", 0.5, (0, 0, 0)), sphere("b", 0.5, (0.9, 0, 0)))
    both = Manifold.concat([m, e, m])
    assert len(both) == 2 and both.point.shape == (2, 3)
    assert len(Manifold.concat([])) == 0


# ---- sphere–sphere -----------------------------------------------------------

def test_sphere_sphere_along_x():
    _, m = run(sphere("a", 0.5, (0, 0, 0)), sphere("b", 0.5, (0.9, 0, 0)))
    assert len(m) == 1 and (m.a[0], m.b[0]) == (0, 1)
    np.testing.assert_allclose(m.normal[0], [1, 0, 0], atol=TOL)
    assert m.depth[0] == pytest.approx(0.1)
    np.testing.assert_allclose(m.point[0], [0.45, 0, 0], atol=TOL)


def test_sphere_sphere_oblique_unequal_radii():
    u = np.array([2.0, -1.0, 2.0]) / 3.0
    c = np.array([1.0, 2.0, 3.0])
    _, m = run(sphere("a", 1.0, c), sphere("b", 0.5, c + 1.2 * u))
    np.testing.assert_allclose(m.normal[0], u, atol=TOL)
    assert m.depth[0] == pytest.approx(0.3)
    # surfaces at 1.0 (a) and 1.2 - 0.5 = 0.7 (b) along u: midway at 0.85
    np.testing.assert_allclose(m.point[0], c + 0.85 * u, atol=TOL)


def test_sphere_sphere_static_body_is_a_and_normal_points_to_b():
    _, m = run(sphere("mover", 0.5, (0.9, 0, 0)), sphere("post", 0.5, (0, 0, 0), static=True))
    assert (m.a[0], m.b[0]) == (1, 0)
    np.testing.assert_allclose(m.normal[0], [1, 0, 0], atol=TOL)


def test_sphere_sphere_coincident_centres_give_plus_z_not_nan():
    _, m = run(sphere("a", 0.3, (1, 1, 1)), sphere("b", 0.2, (1, 1, 1)))
    np.testing.assert_allclose(m.normal[0], [0, 0, 1])
    assert m.depth[0] == pytest.approx(0.5)


def test_sphere_sphere_gap_reported_only_within_margin():
    _, m = run(sphere("a", 0.5, (0, 0, 0)), sphere("b", 0.5, (1.05, 0, 0)), margin=0.1)
    assert len(m) == 1 and m.depth[0] == pytest.approx(-0.05)
    _, m = run(sphere("a", 0.5, (0, 0, 0)), sphere("b", 0.5, (1.05, 0, 0)), margin=0.01)
    assert len(m) == 0


# ---- sphere–plane ------------------------------------------------------------

def test_sphere_plane_ground():
    _, m = run(plane(), sphere("ball", 0.5, (2, 3, 0.4)))
    assert (m.a[0], m.b[0]) == (0, 1)
    np.testing.assert_allclose(m.normal[0], [0, 0, 1], atol=TOL)
    assert m.depth[0] == pytest.approx(0.1)
    np.testing.assert_allclose(m.point[0], [2, 3, -0.05], atol=TOL)


def test_sphere_plane_tilted():
    n = np.array([0.0, 1.0, 1.0]) / math.sqrt(2)
    tangent = np.array([1.0, 0.0, 0.0])
    c = n * (1.0 + 0.3) + 2.0 * tangent        # centre 0.3 above the plane n·x = 1
    _, m = run(sphere("ball", 0.5, c), plane(normal=n, offset=1.0))
    assert (m.a[0], m.b[0]) == (1, 0), "the plane is a"
    np.testing.assert_allclose(m.normal[0], n, atol=TOL)
    assert m.depth[0] == pytest.approx(0.2)
    np.testing.assert_allclose(m.point[0], c - 0.4 * n, atol=TOL)


def test_sphere_plane_speculative_gap():
    _, m = run(plane(), sphere("ball", 0.5, (0, 0, 0.55)), margin=0.1)
    assert m.depth[0] == pytest.approx(-0.05)
    _, m = run(plane(), sphere("ball", 0.5, (0, 0, 0.55)), margin=0.0)
    assert len(m) == 0


# ---- sphere–box --------------------------------------------------------------

HALF = (1.0, 0.5, 0.25)


def test_sphere_box_face():
    _, m = run(box("b", HALF, (0, 0, 0)), sphere("s", 0.2, (0.3, 0.1, 0.4)))
    np.testing.assert_allclose(m.normal[0], [0, 0, 1], atol=TOL)
    assert m.depth[0] == pytest.approx(0.05)
    np.testing.assert_allclose(m.point[0], [0.3, 0.1, 0.225], atol=TOL)


def test_sphere_box_edge_region():
    _, m = run(box("b", HALF, (0, 0, 0)), sphere("s", 0.2, (1.1, 0, 0.35)))
    np.testing.assert_allclose(m.normal[0], np.array([1, 0, 1]) / math.sqrt(2), atol=TOL)
    assert m.depth[0] == pytest.approx(0.2 - 0.1 * math.sqrt(2))


def test_sphere_box_corner_of_rotated_box_sphere_first():
    # box turned 90° about z: world half extents (0.5, 1, 0.25); the sphere is a (index 0)
    q = axis_angle((0, 0, 1), math.pi / 2)
    c = np.array([0.6, 1.05, 0.3]) + np.array([5.0, -2.0, 1.0])
    _, m = run(sphere("s", 0.2, c), box("b", HALF, (5, -2, 1), q))
    d = np.array([0.1, 0.05, 0.05])
    assert (m.a[0], m.b[0]) == (0, 1)
    np.testing.assert_allclose(m.normal[0], -d / np.linalg.norm(d), atol=1e-9)  # sphere → box
    assert m.depth[0] == pytest.approx(0.2 - np.linalg.norm(d))
    corner = np.array([5.5, -1.0, 1.25])
    sphere_surface = c - 0.2 * d / np.linalg.norm(d)
    np.testing.assert_allclose(m.point[0], 0.5 * (corner + sphere_surface), atol=1e-9)


def test_sphere_centre_inside_box_pushes_out_through_nearest_face():
    _, m = run(box("b", HALF, (0, 0, 0)), sphere("s", 0.2, (0.9, 0.1, 0.0)))
    np.testing.assert_allclose(m.normal[0], [1, 0, 0], atol=TOL)
    assert m.depth[0] == pytest.approx(0.2 + 0.1)
    np.testing.assert_allclose(m.point[0], [0.5 * (1.0 + 0.7), 0.1, 0.0], atol=TOL)


def test_sphere_at_box_centre_is_finite():
    _, m = run(box("b", HALF, (0, 0, 0)), sphere("s", 0.1, (0, 0, 0)))
    np.testing.assert_allclose(m.normal[0], [0, 0, 1], atol=TOL)   # nearest face: z (0.25)
    assert m.depth[0] == pytest.approx(0.35)


def test_sphere_inside_rotated_box():
    q = axis_angle((1, 1, 0), 0.7)
    local = np.array([0.1, -0.45, 0.05])           # nearest face: -y, 0.05 away
    c = qt.rotate(q[None], local[None])[0]
    _, m = run(box("b", HALF, (0, 0, 0), q), sphere("s", 0.1, c))
    np.testing.assert_allclose(m.normal[0], qt.rotate(q[None], np.array([[0, -1.0, 0]]))[0], atol=1e-9)
    assert m.depth[0] == pytest.approx(0.15)


# ---- box–plane ---------------------------------------------------------------

def test_box_resting_flat_gives_four_corner_points():
    h = (0.5, 0.3, 0.2)
    _, m = run(plane(), box("crate", h, (1, 2, 0.19)))
    assert len(m) == 4
    np.testing.assert_allclose(m.depth, 0.01, atol=TOL)
    np.testing.assert_allclose(m.normal, np.tile([0, 0, 1.0], (4, 1)))
    expect = [[1 + sx * 0.5, 2 + sy * 0.3, -0.005] for sx in (-1, 1) for sy in (-1, 1)]
    np.testing.assert_allclose(rows_sorted(m.point), rows_sorted(expect), atol=TOL)
    assert sorted(m.key % SLOTS) == [0, 1, 2, 3], "slots are the bottom vertices (z bit clear)"


def test_box_tilted_on_plane_touches_with_one_edge():
    th = 0.3
    h = np.array([0.5, 0.3, 0.2])
    lowest = h[1] * math.sin(th) + h[2] * math.cos(th)   # depth of the lowest edge below the centre
    _, m = run(plane(), box("crate", h, (0, 0, lowest - 0.02), axis_angle((1, 0, 0), th)))
    assert len(m) == 2
    np.testing.assert_allclose(m.depth, 0.02, atol=1e-12)
    np.testing.assert_allclose(sorted(m.point[:, 0]), [-0.5, 0.5], atol=1e-12)
    np.testing.assert_allclose(m.point[:, 2], -0.01, atol=1e-12)


def test_box_on_tilted_plane_keeps_deepest_four():
    n = np.array([1.0, 0.0, 1.0]) / math.sqrt(2)
    q = axis_angle((1, 2, 3), 1.1)
    R = qt.to_matrix(q[None])[0]
    h = np.array([0.4, 0.3, 0.2])
    c = np.array([0.2, 0.1, 0.3])
    verts = np.array([c + R @ (h * s) for s in np.array(np.meshgrid(*[[-1, 1]] * 3)).reshape(3, -1).T])
    height = verts @ n - 0.25
    _, m = run(plane(normal=n, offset=0.25), box("crate", h, c, q))
    expect = np.sort(-height[height < 0])[::-1][:4]
    np.testing.assert_allclose(np.sort(m.depth)[::-1], expect, atol=1e-12)
    np.testing.assert_allclose(m.normal, np.tile(n, (len(m), 1)), atol=1e-12)


def test_box_plane_margin():
    _, m = run(plane(), box("crate", (0.5, 0.3, 0.2), (0, 0, 0.2)), margin=0.01)
    assert len(m) == 4 and np.allclose(m.depth, 0.0)
    _, m = run(plane(), box("crate", (0.5, 0.3, 0.2), (0, 0, 0.22)), margin=0.01)
    assert len(m) == 0


# ---- box–box -----------------------------------------------------------------

def test_box_face_stack_gives_four_corners():
    _, m = run(box("low", (0.5, 0.5, 0.5), (0, 0, 0.5)), box("up", (0.5, 0.5, 0.5), (0, 0, 1.49)))
    assert len(m) == 4
    np.testing.assert_allclose(m.normal, np.tile([0, 0, 1.0], (4, 1)), atol=TOL)
    np.testing.assert_allclose(m.depth, 0.01, atol=TOL)
    expect = [[sx * 0.5, sy * 0.5, 0.995] for sx in (-1, 1) for sy in (-1, 1)]
    np.testing.assert_allclose(rows_sorted(m.point), rows_sorted(expect), atol=TOL)


def test_box_offset_stack_gives_corners_of_the_overlap():
    _, m = run(box("low", (0.5, 0.5, 0.5), (0, 0, 0.5)), box("up", (0.4, 0.35, 0.2), (0.6, 0.3, 1.18)))
    # overlap rectangle x ∈ [0.2, 0.5], y ∈ [-0.05, 0.5]
    expect = [[x, y, 0.99] for x in (0.2, 0.5) for y in (-0.05, 0.5)]
    assert len(m) == 4
    np.testing.assert_allclose(rows_sorted(m.point), rows_sorted(expect), atol=1e-9)
    np.testing.assert_allclose(m.depth, 0.02, atol=1e-9)


def test_small_box_turned_on_big_box_gives_its_own_corners():
    q = axis_angle((0, 0, 1), math.pi / 4)
    _, m = run(box("big", (1, 1, 0.5), (0, 0, 0.5)), box("small", (0.3, 0.3, 0.3), (0, 0, 1.29), q))
    d = 0.3 * math.sqrt(2)
    expect = [[d, 0, 0.995], [-d, 0, 0.995], [0, d, 0.995], [0, -d, 0.995]]
    assert len(m) == 4
    np.testing.assert_allclose(rows_sorted(m.point), rows_sorted(expect), atol=1e-9)


def test_box_box_normal_from_a_to_b_sideways():
    # b on the -x side of a: the normal points along -x
    _, m = run(box("a", (0.5, 0.5, 0.5), (0, 0, 0)), box("b", (0.5, 0.5, 0.5), (-0.99, 0.2, 0)))
    assert len(m) == 4
    np.testing.assert_allclose(m.normal, np.tile([-1.0, 0, 0], (4, 1)), atol=TOL)
    np.testing.assert_allclose(m.depth, 0.01, atol=TOL)
    np.testing.assert_allclose(m.point[:, 0], -0.495, atol=TOL)


def test_box_box_static_reference_on_b_side():
    # the static box has the higher index: it becomes a; normal from it to the mover
    _, m = run(box("mover", (0.2, 0.2, 0.2), (0, 0, 0.69)), box("table", (1, 1, 0.5), (0, 0, 0), static=True))
    assert np.all(m.a == 1) and np.all(m.b == 0) and len(m) == 4
    np.testing.assert_allclose(m.normal, np.tile([0, 0, 1.0], (4, 1)), atol=TOL)
    np.testing.assert_allclose(m.depth, 0.01, atol=TOL)


def test_edge_edge_crossing_gives_one_point():
    # a: unit cube turned 45° about x (top edge along x at z = √2/2);
    # b: unit cube turned 45° about y (bottom edge along y), 0.02 lower than touching
    r = math.sqrt(0.5)
    top = 2 * r - 0.02
    _, m = run(box("a", (0.5, 0.5, 0.5), (0, 0, 0), axis_angle((1, 0, 0), math.pi / 4)),
               box("b", (0.5, 0.5, 0.5), (0.1, -0.05, top), axis_angle((0, 1, 0), math.pi / 4)))
    assert len(m) == 1
    np.testing.assert_allclose(m.normal[0], [0, 0, 1], atol=1e-9)
    assert m.depth[0] == pytest.approx(0.02)
    np.testing.assert_allclose(m.point[0], [0.1, 0.0, r - 0.01], atol=1e-9)


def test_tilted_box_on_box_prefers_the_face_over_equal_edge_axes():
    th = 0.2
    low = r = 0.5 * (math.sin(th) + math.cos(th))
    _, m = run(box("low", (1, 1, 0.5), (0, 0, 0)),
               box("up", (0.5, 0.5, 0.5), (0, 0, 0.5 + low - 0.01), axis_angle((1, 0, 0), th)))
    assert len(m) == 2
    np.testing.assert_allclose(m.normal, np.tile([0, 0, 1.0], (2, 1)), atol=1e-12)
    np.testing.assert_allclose(m.depth, 0.01, atol=1e-12)
    y = -0.5 * math.cos(th) + 0.5 * math.sin(th)
    np.testing.assert_allclose(rows_sorted(m.point), [[-0.5, y, 0.495], [0.5, y, 0.495]], atol=1e-12)
    assert r > 0


@pytest.mark.parametrize("angle", [0.0, 1e-12, 1e-9, 1e-6, 1e-4])
def test_nearly_parallel_boxes_are_finite_and_give_four_points(angle):
    q = axis_angle((0.3, 0.2, 1.0), angle)
    _, m = run(box("low", (0.5, 0.5, 0.5), (0, 0, 0)), box("up", (0.5, 0.5, 0.5), (0.1, 0.05, 0.99), q))
    assert len(m) == 4
    np.testing.assert_allclose(m.normal, np.tile([0, 0, 1.0], (4, 1)), atol=1e-3)
    np.testing.assert_allclose(m.depth, 0.01, atol=1e-3)


def test_box_box_margin_speculative_face():
    _, m = run(box("a", (0.5, 0.5, 0.5), (0, 0, 0)), box("b", (0.5, 0.5, 0.5), (0, 0, 1.03)), margin=0.05)
    assert len(m) == 4 and np.allclose(m.depth, -0.03)
    _, m = run(box("a", (0.5, 0.5, 0.5), (0, 0, 0)), box("b", (0.5, 0.5, 0.5), (0, 0, 1.03)), margin=0.02)
    assert len(m) == 0


def _distance_to_box(p, c, q, h):
    local = qt.rotate_inverse(q[None], (p - c)[None])[0]
    return np.linalg.norm(local - np.clip(local, -h, h))


unit = st.floats(-1.0, 1.0, allow_nan=False)
quats = st.tuples(unit, unit, unit, unit).filter(lambda v: np.linalg.norm(v) > 0.1)


@settings(max_examples=300, deadline=None)
@given(qa=quats, qb=quats,
       ha=st.tuples(*[st.floats(0.05, 1.0)] * 3), hb=st.tuples(*[st.floats(0.05, 1.0)] * 3),
       d=st.tuples(*[st.floats(-1.5, 1.5)] * 3))
def test_random_box_pairs_are_consistent(qa, qb, ha, hb, d):
    """Physical consistency on random boxes: contacts exist exactly when the
    boxes overlap; each point lies within depth/2 of both surfaces; no row is
    deeper than the penetration; moving b along the normal by the penetration
    separates the pair (the normal points from a to b). The axis choice may
    keep a face whose separation is within 2 AXIS_TOL × the smallest half
    extent of the best one, to stay steady; the bounds allow for that."""
    qa = qt.normalize(np.array(qa))
    qb = qt.normalize(np.array(qb))
    ha, hb, d = np.array(ha), np.array(hb), np.array(d)
    model, m = run(box("a", ha, (0, 0, 0), qa), box("b", hb, d, qb))
    sep = box_box_separation(ha[None], np.zeros((1, 3)), qa[None], hb[None], d[None], qb[None])[0]
    if sep > 1e-9:
        assert len(m) == 0
        return
    if sep < -1e-6:
        assert len(m) >= 1
    if not len(m):
        return
    assert len(m) <= 4
    slack = 2 * AXIS_TOL * min(ha.min(), hb.min()) + 1e-9
    assert np.all(m.depth <= -sep + slack)
    for p, depth in zip(m.point, m.depth):
        assert _distance_to_box(p, np.zeros(3), qa, ha) <= 0.5 * depth + 1e-7
        assert _distance_to_box(p, d, qb, hb) <= 0.5 * depth + 1e-7
    moved = d + m.normal[0] * (-sep + slack)
    assert box_box_separation(ha[None], np.zeros((1, 3)), qa[None], hb[None], moved[None], qb[None])[0] > 0


def test_batched_pairs_match_pairs_one_at_a_time():
    """Many mixed pairs in one call give the same rows as each pair alone
    (the kernels are vectorised over pairs, nothing may leak between rows)."""
    from numpy_reference.narrowphase import contacts
    rng = np.random.default_rng(3)
    bodies = [plane()]
    for k in range(40):
        pos = rng.uniform(-1.2, 1.2, 3)
        q = qt.normalize(rng.normal(size=4))
        if k % 2:
            bodies.append(box(f"b{k}", rng.uniform(0.1, 0.6, 3), pos, q))
        else:
            bodies.append(sphere(f"s{k}", rng.uniform(0.1, 0.6), pos))
    model = build_model({"dt": 0.01, "bodies": bodies})
    pos, quat = np.array(model.initial["pos"]), np.array(model.initial["quat"])
    a, b = np.triu_indices(model.n, k=1)
    batch = contacts(model, a, b, pos[a], quat[a], pos[b], quat[b], 0.05)
    assert len(batch) > 50
    for i, j in zip(a, b):
        one = contacts(model, [i], [j], pos[[i]], quat[[i]], pos[[j]], quat[[j]], 0.05)
        rows = np.flatnonzero((batch.a == i) & (batch.b == j))
        assert len(rows) == len(one)
        order = np.argsort(batch.key[rows])
        np.testing.assert_allclose(batch.point[rows][order], one.point[np.argsort(one.key)], atol=1e-12)
        np.testing.assert_allclose(batch.depth[rows][order], one.depth[np.argsort(one.key)], atol=1e-12)
        np.testing.assert_allclose(batch.normal[rows][order], one.normal[np.argsort(one.key)], atol=1e-12)


def test_coincident_boxes_are_finite():
    q = axis_angle((1, 2, 3), 0.4)
    _, m = run(box("a", (0.5, 0.3, 0.2), (1, 1, 1), q), box("b", (0.5, 0.3, 0.2), (1, 1, 1), q))
    assert 1 <= len(m) <= 4
    np.testing.assert_allclose(m.depth, 0.4, atol=1e-9)     # out through the thinnest axis (2 × 0.2)


def test_sphere_centre_on_a_box_corner_is_finite():
    _, m = run(box("b", HALF, (0, 0, 0)), sphere("s", 0.1, HALF))
    assert len(m) == 1 and m.depth[0] == pytest.approx(0.1)
    assert abs(np.linalg.norm(m.normal[0]) - 1.0) < 1e-12


def test_crossed_bars_meet_edge_to_edge_at_right_angles():
    # two long bars, one along x and one along y, each turned 45° about its own
    # long axis so that their edges cross: a single contact point
    r = math.sqrt(2) * 0.1
    _, m = run(box("x_bar", (2.0, 0.1, 0.1), (0, 0, 0), axis_angle((1, 0, 0), math.pi / 4)),
               box("y_bar", (0.1, 2.0, 0.1), (0, 0, 2 * r - 0.01), axis_angle((0, 1, 0), math.pi / 4)))
    assert len(m) == 1
    np.testing.assert_allclose(m.normal[0], [0, 0, 1], atol=1e-9)
    assert m.depth[0] == pytest.approx(0.01)
    np.testing.assert_allclose(m.point[0], [0, 0, r - 0.005], atol=1e-9)


def _keys_after_jiggle(bodies, seed, steps=20, scale=1e-5):
    """The set of keys of each detect() while every dynamic body shifts and turns
    slightly, as a resting stack does from step to step."""
    model = build_model({"dt": 0.01, "bodies": bodies})
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(steps):
        pos = np.array(model.initial["pos"]) + rng.normal(0, scale, (model.n, 3)) * ~model.is_static[:, None]
        turn = qt.from_rotation_vector(rng.normal(0, scale, (model.n, 3)) * ~model.is_static[:, None])
        quat = qt.normalize(qt.multiply(turn, np.array(model.initial["quat"])))
        out.append(tuple(detect(model, pos, quat, 0.01).key.tolist()))
    return out


def test_keys_stay_put_for_a_resting_stack():
    keys = _keys_after_jiggle([plane(), box("low", (0.5, 0.5, 0.5), (0, 0, 0.499)),
                               box("up", (0.5, 0.5, 0.5), (0.01, 0, 1.498)),
                               box("top", (0.2, 0.3, 0.2), (0, 0, 2.197), axis_angle((0, 0, 1), 0.5))], 5)
    assert len(set(keys)) == 1 and len(keys[0]) == 12


def test_box_pairs_in_blocks_match_one_block(monkeypatch):
    from numpy_reference import narrow_box
    rng = np.random.default_rng(9)
    bodies = [box(f"b{k}", rng.uniform(0.1, 0.5, 3), rng.uniform(-1, 1, 3), qt.normalize(rng.normal(size=4)))
              for k in range(30)]
    model = build_model({"dt": 0.01, "bodies": bodies})
    pos, quat = np.array(model.initial["pos"]), np.array(model.initial["quat"])
    whole = detect(model, pos, quat, 0.02)
    monkeypatch.setattr(narrow_box, "BOX_BLOCK", 7)
    blocks = detect(model, pos, quat, 0.02)
    assert len(whole) > 40
    for f in ("a", "b", "point", "normal", "depth", "key"):
        assert np.array_equal(getattr(whole, f), getattr(blocks, f))
