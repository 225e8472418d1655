"""Compiled collision detection (collision/detection.py and its kernels)
against the numpy detector it replaced, tests/numpy_reference (COURSE.md 5: contact point,
normal, depth): the same rows — keys, a and b exactly, point, normal and
depth within 1e-12 m — on the scene files, random scenes, a 2,500-box
scene and a 1,000-sphere pile; the same pairs as broadphase.candidate_pairs;
the same signed depths as narrowphase.signed_depth; and bit-identical
results from call to call."""
import glob
import math
import os
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import physics_core
from physics_core import quaternion as qt
from numpy_reference.broadphase import candidate_pairs as numpy_pairs
from physics_core.collision.detection import Detector, signed_depths
from physics_core.collision.geometry import Geometry
from physics_core.collision.broad_phase import candidate_pairs
from numpy_reference.narrowphase import collide, signed_depth
from random_fields import jiggled, mixed_scene
from physics_core.scene_loader import build_model
from physics_core.shapes import PLANE

TOL = 1e-12
FIELDS = ("a", "b", "key", "point", "normal", "depth")
SCENES = sorted(glob.glob(os.path.join(os.path.dirname(__file__), "..", "scenes", "*.yaml")))


def model_of(bodies):
    with warnings.catch_warnings():          # friction fallbacks of the default material
        warnings.simplefilter("ignore", UserWarning)
        return build_model({"dt": 0.01, "bodies": bodies})


def assert_same_contacts(model, pos, quat, margin):
    """The compiled rows are the numpy rows; returns both manifolds."""
    ref = collide(model, np.asarray(pos, float), np.asarray(quat, float), float(margin), None)
    got = Detector(model).detect(pos, quat, margin)
    assert len(got) == len(ref)
    for f in ("a", "b", "key"):
        assert getattr(got, f).dtype == np.int64
        assert np.array_equal(getattr(got, f), getattr(ref, f)), f
    for f in ("point", "normal", "depth"):
        np.testing.assert_allclose(getattr(got, f), getattr(ref, f), rtol=0, atol=TOL, err_msg=f)
    assert np.all(np.diff(got.key) > 0), "sorted by key, keys unique"
    return ref, got


# ---- scene files ----------------------------------------------------------------------

@pytest.mark.parametrize("path", SCENES, ids=[os.path.basename(p) for p in SCENES])
@pytest.mark.parametrize("margin", [0.0, 0.001])
def test_every_scene_file_gives_the_numpy_contacts(path, margin):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        world = physics_core.load_scene(path)
    model, pos, quat = world.model, world.state.pos, world.state.quat
    assert_same_contacts(model, pos, quat, margin)
    rng = np.random.default_rng(len(path))
    for _ in range(5):          # and near the start pose, where resting contacts come and go
        p, q = jiggled(pos, quat, model.is_static, rng, 0.003, 0.01)
        assert_same_contacts(model, p, q, margin)


# ---- random scenes ----------------------------------------------------------------------

AXES = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
TURNS = tuple((math.cos(a / 2), *(math.sin(a / 2) * np.array(ax))) for ax in AXES
              for a in (math.pi / 4, math.pi / 2))      # 45° and 90° about x, y, z
unit = st.floats(-1.0, 1.0, allow_nan=False)
orientations = st.one_of(
    st.just((1.0, 0.0, 0.0, 0.0)),                     # axis-aligned: exact ties everywhere
    st.sampled_from(TURNS),
    st.tuples(unit, unit, unit, unit).filter(lambda v: np.linalg.norm(v) > 0.1))
coordinate = st.one_of(st.floats(-1.0, 1.0), st.sampled_from(np.arange(-1.0, 1.01, 0.25).tolist()))
size = st.one_of(st.floats(0.05, 0.6), st.sampled_from([0.25, 0.5]))
# (shape, sizes, position, orientation, scale, static roll: 0 = static, about one in seven)
bodies = st.tuples(st.sampled_from(["sphere", "box"]), st.tuples(size, size, size),
                   st.tuples(coordinate, coordinate, coordinate), orientations,
                   st.sampled_from([1.0, 1.0, 1.0, 4.0]), st.integers(0, 6))
plane_normals = st.one_of(st.just((0.0, 0.0, 1.0)), st.just((1.0, 0.0, 1.0)),
                          st.tuples(unit, unit, unit).filter(lambda v: np.linalg.norm(v) > 0.1))
planes = st.lists(st.tuples(plane_normals, st.floats(-1.0, 0.5)), max_size=2)


def scene_bodies(solids, flat):
    out = [{"name": f"ground{k}", "shape": {"type": "plane", "normal": list(n), "offset": off}}
           for k, (n, off) in enumerate(flat)]
    for k, (kind, dims, p, q, scale, static_roll) in enumerate(solids):
        b = {"name": f"b{k}", "position": list(p),
             "orientation": (np.array(q) / np.linalg.norm(q)).tolist()}
        if kind == "sphere":
            b["shape"] = {"type": "sphere", "radius": dims[0] * scale}
        else:
            b["shape"] = {"type": "box", "half_extents": [d * scale for d in dims]}
        if static_roll == 0:
            b["static"] = True
        else:
            b["mass"] = 1.0
        out.append(b)
    return out


@settings(max_examples=250, deadline=None)
@given(solids=st.lists(bodies, min_size=1, max_size=24), flat=planes,
       margin=st.sampled_from([0.0, 0.001]))
def test_random_scenes_give_the_numpy_contacts(solids, flat, margin):
    """Spheres and boxes of mixed sizes (some 4× larger: the grid's large-body
    sweep), overlapping and apart, axis-aligned, at 45°/90° or turned at
    random, with up to two planes."""
    model = model_of(scene_bodies(solids, flat))
    assert_same_contacts(model, np.array(model.initial["pos"]), np.array(model.initial["quat"]), margin)


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), n=st.integers(2, 40), margin=st.sampled_from([0.0, 0.001]))
def test_stacks_touching_face_to_face_give_the_numpy_contacts(seed, n, margin):
    """Boxes and spheres in columns exactly touching, or a hair apart or into
    each other: the ties and near-ties of resting contact."""
    rng = np.random.default_rng(seed)
    h = 0.25
    gap = rng.choice([0.0, 1e-4, -1e-4, -2e-3])
    solids = []
    for k in range(n):
        col, layer = divmod(k, 4)
        p = ((col % 3) * (2 * h + gap), (col // 3) * (2 * h + gap), h + layer * (2 * h + gap))
        q = TURNS[rng.integers(len(TURNS))] if rng.random() < 0.2 else (1.0, 0.0, 0.0, 0.0)
        solids.append(("box" if rng.random() < 0.7 else "sphere", (h, h, h), p, q, 1.0, 1))
    model = model_of(scene_bodies(solids, [((0.0, 0.0, 1.0), float(gap))]))
    assert_same_contacts(model, np.array(model.initial["pos"]), np.array(model.initial["quat"]), margin)


# ---- large scenes ---------------------------------------------------------------------

def box_scene(n, seed):
    """n boxes in an 8 m cube at random orientations, the first ten 30× larger, over a plane."""
    rng = np.random.default_rng(seed)
    half = rng.uniform(0.02, 0.15, (n, 3))
    half[:10] *= 30.0
    out = [{"name": "ground", "shape": {"type": "plane", "normal": [0.0, 0.0, 1.0], "offset": -4.0}}]
    for k in range(n):
        out.append({"name": f"b{k}", "shape": {"type": "box", "half_extents": half[k].tolist()}, "mass": 1.0,
                    "position": rng.uniform(-4, 4, 3).tolist(),
                    "orientation": qt.normalize(rng.normal(size=4)).tolist()})
    return model_of(out)


def sphere_pile(side, r=0.1, overlap=0.002):
    """side³ spheres in a cubic lattice, neighbours overlapping by `overlap`,
    the bottom layer `overlap` into the plane z = 0, each shifted by up to 1 mm."""
    rng = np.random.default_rng(side)
    g = np.stack(np.meshgrid(*[np.arange(side)] * 3, indexing="ij"), -1).reshape(-1, 3)
    pos = g * (2 * r - overlap) + [0.0, 0.0, r - overlap]
    pos[:, :2] += rng.uniform(-1e-3, 1e-3, (len(pos), 2))
    out = [{"name": "ground", "shape": {"type": "plane", "normal": [0.0, 0.0, 1.0], "offset": 0.0}}]
    out += [{"name": f"s{k}", "shape": {"type": "sphere", "radius": r}, "mass": 1.0, "position": p.tolist()}
            for k, p in enumerate(pos)]
    return model_of(out)


@pytest.mark.parametrize("margin", [0.0, 0.001])
def test_2500_random_boxes_give_the_numpy_contacts(margin):
    model = box_scene(2500, seed=11)
    ref, _ = assert_same_contacts(model, np.array(model.initial["pos"]), np.array(model.initial["quat"]), margin)
    assert len(ref) > 1000


@pytest.mark.parametrize("margin", [0.0, 0.001])
def test_1000_sphere_pile_gives_the_numpy_contacts(margin):
    model = sphere_pile(10)
    ref, _ = assert_same_contacts(model, np.array(model.initial["pos"]), np.array(model.initial["quat"]), margin)
    assert np.sum(ref.a == 0) == 100 and len(ref) >= 100 + 3 * 100 * 9


def test_bodies_far_apart_and_a_huge_spread_give_the_numpy_contacts():
    """More cells than the dense table allows (occupied cells by sorted key),
    and a spread that coarsens the grid."""
    rng = np.random.default_rng(1)
    far = [(p, 0.1) for p in rng.uniform(-5e3, 5e3, (40, 3))] + [((0, 0, 0), 0.1), ((0.15, 0, 0), 0.1)]
    huge = [((0, 0, 0), 0.06), ((0.1, 0, 0), 0.06), ((1e9, 0, 0), 0.06), ((1e9, 0.1, 0), 0.06),
            ((-1e9, 5, 5), 0.06)]
    for spheres in (far, huge):
        model = model_of([{"name": f"s{k}", "shape": {"type": "sphere", "radius": r}, "mass": 1.0,
                           "position": [float(x) for x in p]} for k, (p, r) in enumerate(spheres)])
        ref, _ = assert_same_contacts(model, np.array(model.initial["pos"]), np.array(model.initial["quat"]), 0.0)
        assert len(ref) >= 1


def test_no_pairs_gives_an_empty_manifold():
    ground = {"name": "ground", "shape": {"type": "plane"}}
    ball = {"name": "s", "shape": {"type": "sphere", "radius": 0.1}, "mass": 1.0, "position": [0, 0, 5]}
    for bodies in ([ground], [ball], [ground, ball]):
        model = model_of(bodies)
        m = Detector(model).detect(np.array(model.initial["pos"]).reshape(-1, 3),
                                   np.array(model.initial["quat"]).reshape(-1, 4), 0.001)
        assert len(m) == 0 and m.point.shape == (0, 3) and m.key.dtype == np.int64


def test_a_non_finite_pose_is_reported_not_propagated():
    from physics_core.errors import NonFiniteStateError
    model = sphere_pile(3)
    pos, quat = np.array(model.initial["pos"]), np.array(model.initial["quat"])
    det = Detector(model)
    for bad in (np.nan, np.inf):
        p = pos.copy()
        p[5, 1] = bad
        with pytest.raises(NonFiniteStateError) as err:
            det.detect(p, quat, 0.001)
        assert err.value.bodies == (5,)
    assert len(det.detect(pos, quat, 0.001)) > 0     # and the detector still works


# ---- broad phase ----------------------------------------------------------------------

@settings(max_examples=100, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), n=st.integers(1, 80), spread=st.floats(0.3, 10.0),
       margin=st.sampled_from([0.0, 0.01, 0.2]), n_planes=st.integers(0, 3), big=st.sampled_from([0.0, 0.05, 0.3]))
def test_grid_pairs_are_the_numpy_broad_phase_pairs(seed, n, spread, margin, n_planes, big):
    """Same (a, b) pairs in the same order, with static bodies, large bodies
    and tilted planes."""
    rng = np.random.default_rng(seed)
    model, pos, quat = mixed_scene(rng, n + n_planes, spread, n_planes, big)
    g = Geometry.from_model(model)
    pairs = candidate_pairs(g.kind, g.dims, g.is_static, g.reach, pos, quat, margin)
    a, b = numpy_pairs(model, pos, quat, margin)
    assert np.array_equal(pairs[:, 0], a) and np.array_equal(pairs[:, 1], b)
    assert_same_contacts(model, pos, quat, margin)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), clusters=st.integers(2, 6), per=st.integers(2, 30),
       margin=st.sampled_from([0.0, 0.01, 0.2]))
def test_dense_clusters_far_apart_give_the_numpy_pairs(seed, clusters, per, margin):
    """Clusters of touching bodies kilometres apart: the grid indexes its
    occupied cells by sorted key (more than DENSE_CELLS_PER_BODY cells per
    body), and each body's neighbour cells are searched as runs of keys
    (grid.forward_spans); the pairs are the numpy broad phase's, in order."""
    rng = np.random.default_rng(seed)
    n = clusters * per
    model, _, quat = mixed_scene(rng, n + 1, 0.3, 1, 0.0)
    centres = rng.uniform(-5e3, 5e3, (clusters, 3))
    pos = np.concatenate([[[0.0, 0.0, 0.0]], np.repeat(centres, per, axis=0)
                          + rng.uniform(-0.4, 0.4, (n, 3))])
    g = Geometry.from_model(model)
    pairs = candidate_pairs(g.kind, g.dims, g.is_static, g.reach, pos, quat, margin)
    a, b = numpy_pairs(model, pos, quat, margin)
    assert np.array_equal(pairs[:, 0], a) and np.array_equal(pairs[:, 1], b)


@settings(max_examples=300, deadline=None)
@given(values=st.lists(st.one_of(st.floats(0.0, 1e3), st.sampled_from([0.2, 0.4, 0.2000000001])),
                       min_size=1, max_size=300))
def test_grid_median_is_numpys_median(values):
    """The grid's cell size rests on the median body extent: grid.median
    (selected in scratch, no temporary array) is np.median to the bit, for
    odd and even counts, repeated and sorted values."""
    from physics_core.collision.grid import median
    x = np.array(values)
    for v in (x, np.sort(x), np.sort(x)[::-1].copy()):
        assert median(v, np.empty(len(v))) == np.median(v)


# ---- signed depth (for a continuous-collision search) ----------------------------------

@settings(max_examples=60, deadline=None)
@given(solids=st.lists(bodies, min_size=2, max_size=12), flat=planes, seed=st.integers(0, 2 ** 32 - 1))
def test_signed_depth_is_the_numpy_signed_depth(solids, flat, seed):
    model = model_of(scene_bodies(solids, flat))
    rng = np.random.default_rng(seed)
    a, b = np.triu_indices(model.n, k=1)
    keep = ~((model.shape_type[a] == PLANE) & (model.shape_type[b] == PLANE))
    a, b = a[keep], b[keep]
    pos, quat = np.array(model.initial["pos"]), np.array(model.initial["quat"])
    pa, pb = pos[a] + rng.normal(0, 0.05, (len(a), 3)), pos[b]
    qa, qb = quat[a], qt.normalize(quat[b] + rng.normal(0, 0.05, (len(b), 4)))
    ref = signed_depth(model, a, b, pa, qa, pb, qb)
    g = Geometry.from_model(model)
    got = signed_depths(g.kind, g.dims, a, b, pa, qa, pb, qb)
    finite = np.isfinite(ref)
    assert np.array_equal(np.isfinite(got), finite) and np.all(got[~finite] == ref[~finite])
    np.testing.assert_allclose(got[finite], ref[finite], rtol=0, atol=TOL)


def test_constants_are_the_numpy_detectors():
    from numpy_reference import broadphase, narrow_box
    from physics_core.collision import box_pair, geometry, grid
    assert (grid.SMALL_FACTOR, grid.MAX_CELLS) == (broadphase.SMALL_FACTOR, broadphase.MAX_CELLS)
    assert (box_pair.AXIS_TOL, box_pair.EDGE_EPS) == (narrow_box.AXIS_TOL, narrow_box.EDGE_EPS)
    model = box_scene(50, seed=2)
    assert np.array_equal(Geometry.from_model(model).reach, broadphase.bounding_radius(model))
    assert geometry.Geometry.from_model(model).n == model.n


# ---- determinism --------------------------------------------------------------------------

def test_two_calls_give_the_same_bits():
    model = box_scene(400, seed=3)
    pos, quat = np.array(model.initial["pos"]), np.array(model.initial["quat"])
    det = Detector(model)
    first, second, fresh = det.detect(pos, quat, 0.001), det.detect(pos, quat, 0.001), \
        Detector(model).detect(pos, quat, 0.001)
    assert len(first) > 100
    for f in FIELDS:
        assert np.array_equal(getattr(first, f), getattr(second, f)), f
        assert np.array_equal(getattr(first, f), getattr(fresh, f)), f
        assert getattr(first, f) is not getattr(second, f), "each call owns its arrays"


@settings(max_examples=150, deadline=None)
@given(solids=st.lists(bodies, min_size=2, max_size=16), flat=planes,
       margin=st.sampled_from([0.0, 0.001]))
def test_a_workspace_full_of_nan_gives_the_same_rows_as_a_zeroed_one(solids, flat, margin):
    """The step's detection leaves the box pairs' workspace as its scratch
    holds it (detection.detect_scratch): every kernel must write a workspace
    entry before it reads it. Filled with NaN, any entry read first would
    show in the rows."""
    from physics_core.collision.box_pair import workspace
    from physics_core.collision.detection import fill_rows
    model = model_of(scene_bodies(solids, flat))
    g = Geometry.from_model(model)
    pos, quat = np.array(model.initial["pos"]), np.array(model.initial["quat"])
    pairs = candidate_pairs(g.kind, g.dims, g.is_static, g.reach, pos, quat, margin)
    out = []
    for ws in (workspace(), np.full_like(workspace(), np.nan)):
        rows, _, k = fill_rows(pairs, g.kind, g.dims, pos, quat, margin, ws,
                               np.empty((4 * len(pairs) + 4, 8)), np.empty(4 * len(pairs) + 4, np.int64))
        out.append(rows[:k].tobytes())
    assert out[0] == out[1]
