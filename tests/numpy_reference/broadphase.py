"""Broad phase: the pairs of bodies whose bounding boxes overlap.

The first, cheap half of detecting a collision (COURSE.md 5): it proposes
every pair that may touch, and the narrow phase decides. A uniform grid hashes every axis-aligned bounding box (AABB) by the cell of
its centre; only bodies in the same or neighbouring cells are compared, so
the cost follows the number of bodies and of near neighbours instead of n².
Everything is numpy sorts, searchsorted and index arithmetic, no loop over
bodies or pairs:

- the cell edge is the largest AABB extent among the "small" bodies (those
  at most SMALL_FACTOR × the median extent), so two small boxes that overlap
  have centres in the same or adjacent cells; each cell is compared with
  itself and its 13 "forward" neighbours, which reports every pair once;
- the other bodies (a long static slab, a fast body's swept box) are
  "large": they are swept along the axis where the boxes spread most
  (sort-and-sweep), against the small bodies and against each other;
- candidates are expanded and tested in blocks of GRID_BLOCK bodies, so the
  work arrays stay small;
- candidate_pairs then keeps pairs whose bounding spheres also overlap and
  sorts them by (min, max) index, so the whole step stays deterministic.

Planes are infinite and skip the grid: every dynamic body is tested against
every plane by its lowest point along the plane normal.
"""
import numpy as np

from physics_core import quaternion as qt
from physics_core.shapes import BOX, PLANE, SPHERE

SMALL_FACTOR = 4.0     # a body more than this × the median AABB extent is "large"
MAX_CELLS = 2 ** 20    # grid cells per axis; a wider scene gets a coarser grid
GRID_BLOCK = 1024      # bodies whose candidate pairs are expanded and tested together
DENSE_CELLS_PER_BODY = 64   # up to this many grid cells per body, index cells by a dense table

# Own cell and the 13 neighbours that come after it in (x, y, z) order.
_FORWARD = np.array([(dx, dy, dz) for dx in (-1, 0, 1) for dy in (-1, 0, 1) for dz in (-1, 0, 1)
                     if (dx, dy, dz) >= (0, 0, 0)])


def aabb_half_extents(model, quat) -> np.ndarray:
    """(n, 3) half sizes of each body's world AABB; zero for planes.

    A box with body axes R and half extents h spans |R| h about its centre
    (the projection of the box on each world axis)."""
    out = np.zeros((model.n, 3))
    st = model.shape_type
    sphere = st == SPHERE
    out[sphere] = model.radius[sphere, None]
    box = np.flatnonzero(st == BOX)
    if len(box):
        R = qt.to_matrix(quat[box])
        out[box] = np.einsum("kij,kj->ki", np.abs(R), model.half_extents[box])
    return out


def bounding_radius(model) -> np.ndarray:
    """(n,) radius of the sphere about the centre that holds the body (0 for planes)."""
    r = np.where(model.shape_type == SPHERE, model.radius, np.linalg.norm(model.half_extents, axis=1))
    return np.where(model.shape_type == PLANE, 0.0, r)


def overlapping_pairs(lo, hi, centre=None, reach=None):
    """All pairs (i, j), i < j, of boxes [lo, hi] (each (m, 3)) that overlap
    (touching counts), as two int64 arrays in a deterministic order (a
    function of the input only; candidate_pairs sorts them).

    With `centre` (m, 3) and `reach` (m,), a pair must also have
    |centre_i - centre_j| <= reach_i + reach_j (bounding spheres); that
    cheaper test runs first."""
    lo = np.asarray(lo, dtype=float)
    hi = np.asarray(hi, dtype=float)
    m = len(lo)
    if m < 2:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    # one contiguous row per quantity: 1-D gathers of a row beat gathers of (m, 3) rows
    cols = np.empty((10 if centre is not None else 6, m))
    cols[_LO] = lo.T
    cols[_HI] = hi.T
    if centre is not None:
        cols[_C] = np.asarray(centre, dtype=float).T
        cols[_R] = reach
    size = (hi - lo).max(axis=1)
    small = size <= SMALL_FACTOR * np.median(size)
    cell = float(size[small].max())
    parts = [_grid_pairs(np.flatnonzero(small), cols, cell)]
    if not small.all():
        parts.append(_large_pairs(np.flatnonzero(~small), np.flatnonzero(small), cols, cell))
    i = np.concatenate([p[0] for p in parts])
    j = np.concatenate([p[1] for p in parts])
    return np.minimum(i, j), np.maximum(i, j)


_LO, _HI, _C, _R = slice(0, 3), slice(3, 6), slice(6, 9), 9


def _filter(cols, p, q):
    """The index pairs (p, q) into `cols` whose bounding spheres (when
    `cols` has them) and boxes overlap. In place where it can: the arrays
    are as long as the candidate list."""
    if len(cols) > 6:
        d2 = np.zeros(len(p))
        for k in (6, 7, 8):
            d = cols[k].take(p)
            d -= cols[k].take(q)
            d *= d
            d2 += d
        r = cols[_R].take(p)
        r += cols[_R].take(q)
        r *= r
        keep = d2 <= r
        p, q = p[keep], q[keep]
    keep = np.ones(len(p), bool)
    for k in range(3):
        keep &= cols[k].take(p) <= cols[3 + k].take(q)
        keep &= cols[k].take(q) <= cols[3 + k].take(p)
    return p[keep], q[keep]


def _grid_pairs(small, cols, cell):
    """Pairs among the `small` bodies, by the grid of their centres."""
    empty = (np.zeros(0, np.int64), np.zeros(0, np.int64))
    if len(small) < 2:
        return empty
    centre = 0.5 * (cols[_LO].take(small, axis=1) + cols[_HI].take(small, axis=1)).T
    spread = centre.max(axis=0) - centre.min(axis=0)
    cell = max(cell, float(spread.max()) / MAX_CELLS, 1e-300)
    c = np.floor(centre / cell).astype(np.int64)
    c -= c.min(axis=0) - 1                       # one empty cell of padding on each side:
    dims = c.max(axis=0) + 2                     # neighbour keys never wrap round an axis
    stride = np.array([dims[1] * dims[2], dims[2], 1])
    key = c @ stride
    order = np.argsort(key, kind="stable")
    key = key[order]
    body = small[order]
    # [start, end) of each forward neighbour cell in the sorted keys
    nkey = key[:, None] + _FORWARD @ stride      # (s, 14)
    cells = int(dims.prod())
    if cells <= DENSE_CELLS_PER_BODY * len(key) + 2 ** 16:
        # a table of where each cell starts in the sorted keys (counting sort)
        first = np.zeros(cells + 1, np.int64)
        np.cumsum(np.bincount(key, minlength=cells), out=first[1:])
        start, end = first.take(nkey), first.take(nkey + 1)
    else:
        start = np.empty_like(nkey)
        end = np.empty_like(nkey)
        for k in range(nkey.shape[1]):          # 14 columns, each already sorted
            start[:, k] = np.searchsorted(key, nkey[:, k], side="left")
            end[:, k] = np.searchsorted(key, nkey[:, k], side="right")
    start[:, 0] = np.arange(len(key)) + 1        # own cell: only the later entries
    count = end - start
    # candidates index the cell-sorted copy, which keeps neighbours close in memory
    sorted_cols = cols.take(body, axis=1)
    ps, qs = [], []
    # blocks of bodies keep the candidate arrays small (cache-sized, reused
    # allocations); the loop runs over blocks, not over bodies or pairs
    for r0 in range(0, len(key), GRID_BLOCK):
        flat = count[r0:r0 + GRID_BLOCK].ravel()
        total = int(flat.sum())
        if total == 0:
            continue
        q = np.repeat(start[r0:r0 + GRID_BLOCK].ravel() - (np.cumsum(flat) - flat), flat)
        q += np.arange(total)
        p = np.repeat(np.arange(r0, r0 + len(flat) // _FORWARD.shape[0]).repeat(_FORWARD.shape[0]), flat)
        p, q = _filter(sorted_cols, p, q)
        ps.append(p)
        qs.append(q)
    if not ps:
        return empty
    return body.take(np.concatenate(ps)), body.take(np.concatenate(qs))


def _expand(start, stop):
    """Flattened index ranges [start_k, stop_k): (owner k of each, index)."""
    count = np.maximum(stop - start, 0)
    total = int(count.sum())
    owner = np.repeat(np.arange(len(start)), count)
    return owner, np.repeat(start - (np.cumsum(count) - count), count) + np.arange(total)


def _large_pairs(big, small, cols, cell):
    """Large bodies, by sort-and-sweep along the axis where the boxes spread
    most: against the small bodies sorted by their lower bound (a small body
    overlapping [lo, hi] starts in [lo - cell, hi]), and against each other
    (j after i in lower-bound order overlaps i on that axis iff lo_j <= hi_i)."""
    axis = int(np.argmax(np.var(cols[_LO] + cols[_HI], axis=1)))
    lo_big, hi_big = cols[axis].take(big), cols[3 + axis].take(big)
    sweep = cols[axis].take(small)
    order = np.argsort(sweep, kind="stable")
    sweep, sorted_small = sweep[order], small[order]
    owner, q = _expand(np.searchsorted(sweep, lo_big - cell, side="left"),
                       np.searchsorted(sweep, hi_big, side="right"))
    i, j = big.take(owner), sorted_small.take(q)
    order = np.argsort(lo_big, kind="stable")
    sorted_big, lo_sorted = big[order], lo_big[order]
    owner, q = _expand(np.arange(1, len(big) + 1),
                       np.searchsorted(lo_sorted, hi_big[order], side="right"))
    i = np.concatenate([i, sorted_big.take(owner)])
    j = np.concatenate([j, sorted_big.take(q)])
    return _filter(cols, i, j)


def plane_pairs(model, pos, quat, margin: float = 0.0, bodies=None, rows=None):
    """(plane, body) pairs where a dynamic body's lowest point along the plane
    normal lies less than `margin` above the plane (n·x = offset, solid below).

    The lowest point of a sphere is r below its centre along the normal; of a
    box, Σ h_k |n·axis_k| below it (the box's support in direction -n)."""
    planes, bodies, gap = plane_clearance(model, pos, quat, bodies, rows)
    if gap is None:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    b, p = np.nonzero(gap < margin)
    order = np.lexsort((bodies[b], planes[p]))
    return planes[p][order], bodies[b][order]


def plane_clearance(model, pos, quat, bodies=None, rows=None):
    """(planes, bodies, gap): gap (B, P) is the height of each dynamic body's
    lowest point above each plane (None when there is no plane or body).
    plane_pairs and the kept pair list (pair_cache.py) both test this one
    array, so they agree to the last bit."""
    rows = rows or ModelRows(model)
    planes = rows.planes
    own = bodies is None
    if own:
        bodies = rows.plane_bodies
    if len(planes) == 0 or len(bodies) == 0:
        return planes, bodies, None
    n = rows.plane_normal                                           # (P, 3)
    height = pos[bodies] @ n.T - rows.plane_offset                  # (B, P)
    if own and not rows.plane_box_bodies:
        # spheres only: the support is the radius whatever the orientation
        return planes, bodies, height - rows.plane_support
    return planes, bodies, height - support_along(model, quat, bodies, n)


def support_along(model, quat, bodies, directions):
    """(B, D) extent of each body from its centre along each unit direction."""
    out = np.repeat(model.radius[bodies, None], len(directions), axis=1)
    box = model.shape_type[bodies] == BOX
    if box.any():
        R = qt.to_matrix(quat[bodies[box]])                         # (b, 3, 3) columns = axes
        proj = np.abs(np.einsum("kij,di->kdj", R, directions))      # |d·axis_j|
        out[box] = np.einsum("kdj,kj->kd", proj, model.half_extents[bodies[box]])
    return out


def candidate_pairs(model, pos, quat, margin: float = 0.0):
    """Pairs that may be within `margin` of touching, in the Manifold order
    (static body, or the lower index, first), sorted by (min, max) index.

    Solid pairs need overlapping margin-grown AABBs and bounding spheres
    (|c_a - c_b| <= R_a + R_b + margin); static–static pairs are dropped."""
    rows = ModelRows(model)
    return sorted_pairs(model, *solid_pairs(model, pos, quat, margin, rows),
                        *plane_pairs(model, pos, quat, margin, rows=rows))[:2]


def solid_columns(model, pos, quat, margin, rows):
    """(lo, hi, centre, reach) of the solid bodies' margin-grown AABBs and bounding spheres."""
    solid = rows.solid
    half = aabb_half_extents(model, quat)[solid] + 0.5 * margin
    p = np.asarray(pos, dtype=float)[solid]
    return p - half, p + half, p, rows.radius[solid] + 0.5 * margin


def solid_pairs(model, pos, quat, margin, rows, local=False):
    """(a, b) solid pairs in the Manifold order, static–static dropped, unsorted.
    With `local`, also the two indices of each pair into the solid bodies."""
    solid = rows.solid
    i, j = overlapping_pairs(*solid_columns(model, pos, quat, margin, rows))
    a, b = solid.take(i), solid.take(j)
    static = model.is_static
    keep = ~(static.take(a) & static.take(b))
    a, b = a[keep], b[keep]
    flip = static.take(b) & ~static.take(a)
    a, b = np.where(flip, b, a), np.where(flip, a, b)
    return (a, b, i[keep], j[keep]) if local else (a, b)


def sorted_pairs(model, a, b, pa, pb):
    """Solid pairs (a, b) and plane pairs (pa, pb) as one list sorted by (min, max)
    index: (a, b, order), order indexing the concatenation [solid, plane]."""
    if len(pa):
        a = np.concatenate([a, pa])
        b = np.concatenate([b, pb])
    order = np.argsort(np.minimum(a, b) * model.n + np.maximum(a, b), kind="stable")
    return a[order], b[order], order


class ModelRows:
    """Per-model constants of the broad phase (a Model is frozen): the pair
    cache computes them once, a one-off call each time."""

    def __init__(self, model):
        st = model.shape_type
        self.solid = np.flatnonzero(st != PLANE)
        self.planes = np.flatnonzero(st == PLANE)
        self.plane_bodies = np.flatnonzero(~model.is_static & (st != PLANE))
        self.radius = bounding_radius(model)
        self.box = np.flatnonzero(st == BOX)
        self.plane_normal = model.plane_normal[self.planes]
        self.plane_offset = model.plane_offset[self.planes]
        self.plane_box_bodies = bool(np.any(st[self.plane_bodies] == BOX))
        self.plane_support = np.repeat(model.radius[self.plane_bodies, None], len(self.planes), axis=1)
