"""Narrow phase: contact points, normals and depths for candidate pairs.

Each shape-pair kind has a kernel vectorised over all pairs of that kind
(COURSE.md 5: point, normal that separates the bodies, depth). A kernel
gets the two bodies in its own shape order ("first", "second") with one
pose per pair, and returns rows (pair row, slot, point, normal from first
to second, depth). `contacts` runs the kernels over a mixed list of pairs,
flipping the normal where the pair's `a` is the kernel's "second" body, so
every row keeps the Manifold convention (normal from a towards b).

Planes are world-fixed half-spaces n·x <= offset (their pose is not used).
Box–box lives in narrow_box.py.
"""
import numpy as np

from physics_core import quaternion as qt
from physics_core.shapes import BOX, PLANE, SPHERE
from .broadphase import candidate_pairs
from physics_core.collision.manifold import Manifold, pair_key

try:        # the C entry point of np.einsum, without the Python dispatch layer
    from numpy._core.multiarray import c_einsum as _einsum
except ImportError:     # pragma: no cover - other numpy layouts
    _einsum = np.einsum
from .narrow_box import box_box, box_box_separation

# Sign pattern of the 8 box vertices: vertex v has x sign from bit 0, y from bit 1, z from bit 2.
BOX_VERTEX_SIGNS = np.array([[1.0 if v & (1 << k) else -1.0 for k in range(3)] for v in range(8)])
BOX_PLANE_POINTS = 4          # deepest box vertices kept against a plane
COINCIDENT_NORMAL = np.array([0.0, 0.0, 1.0])   # sphere–sphere normal when the centres coincide
_TINY = 1e-12


def _one_row(point, normal, depth):
    k = len(depth)
    return np.arange(k), np.zeros(k, np.int64), point, normal, depth


def sphere_sphere(model, f, s, pf, qf, ps, qs, margin=0.0):
    """Normal along the line of centres; depth r_a + r_b - |c_b - c_a|.

    Coincident centres have no line of centres: the normal is then +z
    (COINCIDENT_NORMAL), a fixed choice so the result is never NaN."""
    ra, rb = model.radius[f], model.radius[s]
    d = ps - pf
    dist = np.sqrt(_einsum("ij,ij->i", d, d))
    ok = dist > _TINY
    normal = np.where(ok[:, None], d / np.where(ok, dist, 1.0)[:, None], COINCIDENT_NORMAL)
    depth = ra + rb - dist
    point = 0.5 * ((pf + normal * ra[:, None]) + (ps - normal * rb[:, None]))
    return _one_row(point, normal, depth)


def plane_sphere(model, f, s, pf, qf, ps, qs, margin=0.0):
    """Sphere above plane n·x = offset: height h = n·c - offset, depth r - h,
    normal n (from the plane to the sphere)."""
    n = model.plane_normal[f]
    r = model.radius[s]
    h = _einsum("ij,ij->i", n, ps) - model.plane_offset[f]
    point = ps - n * (0.5 * (r + h))[:, None]     # midway between c - r n and c - h n
    return _one_row(point, n, r - h)          # n: a fresh gather, nothing writes to it


def box_sphere(model, f, s, pf, qf, ps, qs, margin=0.0):
    """Sphere against box, worked in the box frame (normal from box to sphere).

    Outside: the closest box point is the centre clamped to [-h, h]; the
    normal runs from it to the centre, depth r - distance. Inside (centre
    within the box): push out through the face nearest the centre, depth
    r + distance from the centre to that face."""
    h = model.half_extents[f]
    r = model.radius[s]
    c = qt.rotate_inverse(qf, ps - pf)
    q = np.clip(c, -h, h)
    diff = c - q
    dist = np.sqrt(np.einsum("ij,ij->i", diff, diff))
    outside = dist > _TINY
    gap = h - np.abs(c)                       # distance from the centre to each face pair
    axis = np.argmin(gap, axis=1)
    rows = np.arange(len(c))
    side = np.where(c[rows, axis] >= 0.0, 1.0, -1.0)
    n_in = np.zeros_like(c)
    n_in[rows, axis] = side
    face = c.copy()
    face[rows, axis] = side * h[rows, axis]
    n_local = np.where(outside[:, None], diff / np.where(outside, dist, 1.0)[:, None], n_in)
    surface = np.where(outside[:, None], q, face)
    depth = np.where(outside, r - dist, r + gap[rows, axis])
    normal = qt.rotate(qf, n_local)
    box_point = pf + qt.rotate(qf, surface)
    point = 0.5 * (box_point + ps - normal * r[:, None])
    return _one_row(point, normal, depth)


def box_vertices(pos, quat, half):
    """(k, 8, 3) world vertices, ordered as BOX_VERTEX_SIGNS."""
    R = qt.to_matrix(quat)
    local = BOX_VERTEX_SIGNS[None, :, :] * half[:, None, :]
    return pos[:, None, :] + np.einsum("kij,kvj->kvi", R, local)


def plane_box(model, f, s, pf, qf, ps, qs, margin=0.0):
    """Box vertices less than `margin` above the plane, the deepest
    BOX_PLANE_POINTS of them; slot = vertex number, so a resting box keeps
    its keys. Point midway between the vertex and its projection on the plane."""
    n = model.plane_normal[f]
    verts = box_vertices(ps, qs, model.half_extents[s])
    height = np.einsum("kvi,ki->kv", verts, n) - model.plane_offset[f][:, None]
    depth = -height
    ranked = np.where(depth > -margin, depth, -np.inf)
    order = np.argsort(-ranked, axis=1, kind="stable")[:, :BOX_PLANE_POINTS]
    keep = np.take_along_axis(ranked, order, axis=1) > -np.inf
    row, col = np.nonzero(keep)
    vertex = order[row, col]
    h = height[row, vertex]
    point = verts[row, vertex] - n[row] * (0.5 * h)[:, None]
    return row, vertex.astype(np.int64), point, n[row], -h


KERNELS = (   # (first shape, second shape, kernel, uses orientations)
    (SPHERE, SPHERE, sphere_sphere, False),
    (PLANE, SPHERE, plane_sphere, False),
    (PLANE, BOX, plane_box, True),
    (BOX, SPHERE, box_sphere, True),
    (BOX, BOX, box_box, True),
)


def _kind_rows(ta, tb, first, second):
    """Pairs of this kind in kernel order, then those stored the other way round."""
    direct = np.flatnonzero((ta == first) & (tb == second))
    if first == second:
        return direct, np.zeros(0, np.int64)
    return direct, np.flatnonzero((ta == second) & (tb == first))


def _gather(direct, swapped, x, y):
    """x's rows `direct`, then y's rows `swapped` (the kernel's "first" side)."""
    if len(swapped) == 0:
        return x.take(direct, axis=0)
    return np.concatenate([x.take(direct, axis=0), y.take(swapped, axis=0)])


def _kernel_rows(model, a, b, margin, pos=None, quat=None, pair_poses=None):
    """(pair, slot, point, normal a→b, depth) over every kernel, grouped by kind.

    Poses come either per body (pos, quat indexed by body) or per pair
    (pair_poses = (pa, qa, pb, qb), one row per pair)."""
    ta, tb = model.shape_type.take(a), model.shape_type.take(b)
    if len(a):
        # one kind of pair only (spheres on a floor, a box pile): no grouping
        code = ta * _CODES + tb
        one = _ONE_KIND.get(int(code[0]))
        if one is not None and (code == code[0]).all():
            return _one_kind(model, a, b, margin, pos, quat, pair_poses, *one)
    parts = []
    for first, second, kernel, turns in KERNELS:
        direct, swapped = _kind_rows(ta, tb, first, second)
        if len(direct) + len(swapped) == 0:
            continue
        f, s = _gather(direct, swapped, a, b), _gather(direct, swapped, b, a)
        if pair_poses is None:
            pf, ps, qf, qs = _body_poses(f, s, pos, quat, turns)
        else:
            pa, qa, pb, qb = pair_poses
            pf, ps = _gather(direct, swapped, pa, pb), _gather(direct, swapped, pb, pa)
            qf = qs = None
            if turns:
                qf, qs = _gather(direct, swapped, qa, qb), _gather(direct, swapped, qb, qa)
        row, slot, point, normal, depth = kernel(model, f, s, pf, qf, ps, qs, margin)
        if len(swapped):
            normal = np.where((row >= len(direct))[:, None], -normal, normal)
        idx = direct if len(swapped) == 0 else np.concatenate([direct, swapped])
        parts.append((idx.take(row), slot, point, normal, depth))
    if not parts:
        z = np.zeros(0, np.int64)
        return z, z, np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0)
    if len(parts) == 1:
        return parts[0]
    return tuple(np.concatenate(col) for col in zip(*parts))


def _body_poses(f, s, pos, quat, turns):
    """Positions of the pairs' bodies f and s, and their orientations when
    the kernel turns them (else None)."""
    pf, ps = pos.take(f, axis=0), pos.take(s, axis=0)
    if not turns:
        return pf, ps, None, None
    return pf, ps, quat.take(f, axis=0), quat.take(s, axis=0)


_CODES = 8      # shape codes are below this
# pair kind code -> (kernel, uses orientations, stored the other way round)
_ONE_KIND = {}
for _first, _second, _kernel, _turns in KERNELS:
    _ONE_KIND[_first * _CODES + _second] = (_kernel, _turns, False)
    _ONE_KIND.setdefault(_second * _CODES + _first, (_kernel, _turns, True))


def _one_kind(model, a, b, margin, pos, quat, pair_poses, kernel, turns, swapped):
    """_kernel_rows when every pair is of one kind: the kernel runs on the pairs as given."""
    f, s = (b, a) if swapped else (a, b)
    if pair_poses is None:
        pf, ps, qf, qs = _body_poses(f, s, pos, quat, turns)
    else:
        pa, qa, pb, qb = pair_poses
        pf, ps, qf, qs = (pb, pa, qb, qa) if swapped else (pa, pb, qa, qb)
    row, slot, point, normal, depth = kernel(model, f, s, pf, qf, ps, qs, margin)
    return row, slot, point, (-normal if swapped else normal), depth


def _manifold(model, a, b, rows) -> Manifold:
    pair, slot, point, normal, depth = rows
    a, b = a.take(pair), b.take(pair)
    return Manifold(a=a, b=b, point=point, normal=normal, depth=depth,
                    key=pair_key(a, b, model.n, slot))


def contacts(model, a, b, pa, qa, pb, qb, margin: float = 0.0) -> Manifold:
    """Contact rows for pairs (a[i], b[i]) at poses (pa, qa) and (pb, qb).

    Rows are grouped by kind, unfiltered (depth may be below -margin for
    single-point kinds) and unsorted; `collide` filters and sorts."""
    a = np.asarray(a, dtype=np.int64)
    b = np.asarray(b, dtype=np.int64)
    return _manifold(model, a, b, _kernel_rows(model, a, b, margin, pair_poses=(pa, qa, pb, qb)))


def collide(model, pos, quat, margin: float = 0.0, pairs=None) -> Manifold:
    """Broad phase, then every kernel; rows with depth > -margin, sorted by key.
    `pairs`: a pair_cache.PairCache to take the broad phase from (same pairs)."""
    if pairs is None:
        a, b = candidate_pairs(model, pos, quat, margin)
    else:
        a, b = pairs.pairs(model, pos, quat, margin)
    if len(a) == 0:
        return Manifold.empty()
    if pairs is not None and pairs.plane_sphere:
        memo = pairs.memo
        if memo is None or memo.a is not a or memo.b is not b:
            memo = pairs.memo = PairMemo(model, a, b)
        m = _plane_sphere_rows(memo, pos, margin)
        if m is not None:
            return m
    rows = _kernel_rows(model, a, b, margin, pos=pos, quat=quat)
    near = rows[4] > -margin
    if not near.all():
        keep = np.flatnonzero(near)
        rows = tuple(c.take(keep, axis=0) for c in rows)
    m = _manifold(model, a, b, rows)
    # pairs come sorted; rows need a sort only when several kinds or slots interleave
    return m if np.all(m.key[1:] > m.key[:-1]) else m.sorted_by_key()


class PairMemo:
    """What the narrow phase derives from a kept pair list of planes under
    spheres alone (pair_cache.py hands back the very same arrays while its
    list holds): the pairs' plane normals, offsets, radii, keys and order.
    Nothing here is written to after it is made."""

    def __init__(self, model, a, b):
        self.a, self.b = a, b
        self.n = model.plane_normal[a]
        self.offset = model.plane_offset[a]
        self.radius = model.radius[b]
        self.key = pair_key(a, b, model.n, 0)
        self.key_sorted = bool(np.all(self.key[1:] > self.key[:-1]))


def _plane_sphere_rows(memo, pos, margin):
    """collide's result when every kept pair is plane–sphere and every one is
    within the margin (else None): plane_sphere's arithmetic, the gathers and
    keys from the memo."""
    ps = pos.take(memo.b, axis=0)
    r = memo.radius
    h = _einsum("ij,ij->i", memo.n, ps) - memo.offset
    depth = r - h
    if not (depth > -margin).all() or not memo.key_sorted:
        return None
    n = memo.n.copy()
    point = ps - n * (0.5 * (r + h))[:, None]
    return Manifold(a=memo.a, b=memo.b, point=point, normal=n, depth=depth, key=memo.key)


def signed_depth(model, a, b, pa, qa, pb, qb) -> np.ndarray:
    """(k,) how far each pair overlaps at the given poses: > 0 overlapping,
    <= 0 apart. The sign is exact; for separated box pairs the magnitude is
    a lower bound of the gap (the largest separating-axis distance)."""
    a = np.asarray(a, dtype=np.int64)
    b = np.asarray(b, dtype=np.int64)
    out = np.full(len(a), -np.inf)
    ta, tb = model.shape_type[a], model.shape_type[b]
    bb = (ta == BOX) & (tb == BOX)
    if bb.any():
        out[bb] = -box_box_separation(model.half_extents[a[bb]], pa[bb], qa[bb],
                                      model.half_extents[b[bb]], pb[bb], qb[bb])
    rest = np.flatnonzero(~bb)
    if len(rest):
        # the deepest contact row of each pair, with no margin cut
        pair, _, _, _, depth = _kernel_rows(model, a[rest], b[rest], np.inf,
                                            pair_poses=(pa[rest], qa[rest], pb[rest], qb[rest]))
        np.maximum.at(out, rest[pair], depth)
    return out

