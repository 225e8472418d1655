"""Broad phase: the pairs of bodies whose bounding boxes overlap.

A uniform grid hashes every axis-aligned bounding box (AABB) into the cells
it covers; only bodies sharing a cell are compared, so the cost follows the
number of bodies and of near neighbours instead of n². Everything is numpy
sorts and index arithmetic, no loop over bodies or pairs:

- the cell size is the 90th percentile of the boxes' largest extent, so a
  typical body covers 1–2 cells per axis;
- bodies spanning more than `MAX_SPAN` cells on an axis (a long static slab,
  a fast body's swept box) are "large": each is tested against every body
  in one vectorised comparison instead of filling many cells;
- a pair sharing several cells is reported once, by the cell holding the
  lower corner of the intersection of the two boxes;
- pairs come out sorted by (i, j), so the whole step stays deterministic.

Planes are infinite and skip the grid: every dynamic body is tested against
every plane by its lowest point along the plane normal.
"""
import numpy as np

from .. import quaternion as qt
from ..shapes import BOX, PLANE, SPHERE

MAX_SPAN = 4          # cells per axis before a body is handled as "large"
CELL_QUANTILE = 0.9   # cell size = this quantile of the AABBs' largest extent


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


def overlapping_pairs(lo, hi):
    """All pairs (i, j), i < j, of boxes [lo, hi] (each (m, 3)) that overlap
    (touching counts), as two int64 arrays sorted by (i, j)."""
    lo = np.asarray(lo, dtype=float)
    hi = np.asarray(hi, dtype=float)
    m = len(lo)
    if m < 2:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    size = (hi - lo).max(axis=1)
    cell = float(np.quantile(size, CELL_QUANTILE))
    if not np.isfinite(cell) or cell <= 0.0:
        cell = max(float(size.max()), 1e-9) if np.isfinite(size.max()) else 1.0
    c_lo = np.floor(lo / cell).astype(np.int64)
    c_hi = np.floor(hi / cell).astype(np.int64)
    span = c_hi - c_lo + 1
    large = (span > MAX_SPAN).any(axis=1)
    parts = [_grid_pairs(np.flatnonzero(~large), lo, hi, c_lo, span, cell)]
    if large.any():
        parts.append(_large_pairs(np.flatnonzero(large), large, lo, hi))
    i = np.concatenate([p[0] for p in parts])
    j = np.concatenate([p[1] for p in parts])
    order = np.argsort(i * m + j, kind="stable")
    return i[order], j[order]


def _grid_pairs(small, lo, hi, c_lo, span, cell):
    """Pairs among the `small` bodies that share a grid cell (each pair once)."""
    empty = (np.zeros(0, np.int64), np.zeros(0, np.int64))
    if len(small) < 2:
        return empty
    sp = span[small]
    count = sp.prod(axis=1)
    body = np.repeat(small, count)
    # offset of each entry inside its body's block of cells, as (ox, oy, oz)
    first = np.cumsum(count) - count
    local = np.arange(len(body)) - np.repeat(first, count)
    sy = np.repeat(sp[:, 1], count)
    sz = np.repeat(sp[:, 2], count)
    cz = c_lo[body, 2] + local % sz
    rest = local // sz
    cy = c_lo[body, 1] + rest % sy
    cx = c_lo[body, 0] + rest // sy
    cells = np.stack([cx, cy, cz], axis=1)
    key = _cell_key(cells)
    order = np.argsort(key, kind="stable")      # stable: bodies ascending inside a cell
    key, body, cells = key[order], body[order], cells[order]
    # each entry pairs with the later entries of its cell
    new_group = np.empty(len(key), bool)
    new_group[0] = True
    new_group[1:] = key[1:] != key[:-1]
    starts = np.flatnonzero(new_group)
    ends = np.append(starts[1:], len(key))
    group_end = np.repeat(ends, ends - starts)
    partners = group_end - np.arange(len(key)) - 1
    total = int(partners.sum())
    if total == 0:
        return empty
    p = np.repeat(np.arange(len(key)), partners)
    q = p + 1 + (np.arange(total) - np.repeat(np.cumsum(partners) - partners, partners))
    i, j = body[p], body[q]
    # report the pair only in the cell holding the lower corner of the overlap
    corner = np.floor(np.maximum(lo[i], lo[j]) / cell).astype(np.int64)
    keep = (corner == cells[p]).all(axis=1)
    keep &= (lo[i] <= hi[j]).all(axis=1) & (lo[j] <= hi[i]).all(axis=1)
    return i[keep], j[keep]


def _cell_key(cells):
    """One int64 per cell coordinate triple (dense when the grid is small)."""
    c = cells - cells.min(axis=0)
    dims = c.max(axis=0) + 1
    if float(dims[0]) * float(dims[1]) * float(dims[2]) < 2.0 ** 62:
        return (c[:, 0] * dims[1] + c[:, 1]) * dims[2] + c[:, 2]
    return np.unique(c, axis=0, return_inverse=True)[1].reshape(-1).astype(np.int64)


def _large_pairs(big, large, lo, hi):
    """Each large body against every body, in one (len(big), m) comparison."""
    hit = ((lo[big, None, :] <= hi[None, :, :]) & (lo[None, :, :] <= hi[big, None, :])).all(axis=2)
    r, j = np.nonzero(hit)
    i = big[r]
    # drop self pairs; a large–large pair is kept once, from its lower index
    keep = (i != j) & ~(large[j] & (j < i))
    i, j = i[keep], j[keep]
    return np.minimum(i, j), np.maximum(i, j)


def plane_pairs(model, pos, quat, margin: float = 0.0, bodies=None):
    """(plane, body) pairs where a dynamic body's lowest point along the plane
    normal lies less than `margin` above the plane (n·x = offset, solid below).

    The lowest point of a sphere is r below its centre along the normal; of a
    box, Σ h_k |n·axis_k| below it (the box's support in direction -n)."""
    planes = np.flatnonzero(model.shape_type == PLANE)
    if bodies is None:
        bodies = np.flatnonzero(~model.is_static & (model.shape_type != PLANE))
    if len(planes) == 0 or len(bodies) == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    n = model.plane_normal[planes]                                  # (P, 3)
    height = pos[bodies] @ n.T - model.plane_offset[planes]         # (B, P)
    reach = support_along(model, quat, bodies, n)                   # (B, P)
    b, p = np.nonzero(height - reach < margin)
    order = np.lexsort((bodies[b], planes[p]))
    return planes[p][order], bodies[b][order]


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
    (static body, or the lower index, first), sorted by (min, max) index."""
    pos = np.asarray(pos, dtype=float)
    solid = np.flatnonzero(model.shape_type != PLANE)
    half = aabb_half_extents(model, quat)[solid] + 0.5 * margin
    i, j = overlapping_pairs(pos[solid] - half, pos[solid] + half)
    i, j = solid[i], solid[j]
    static = model.is_static
    keep = ~(static[i] & static[j])
    i, j = i[keep], j[keep]
    flip = static[j] & ~static[i]
    a = np.where(flip, j, i)
    b = np.where(flip, i, j)
    pa, pb = plane_pairs(model, pos, quat, margin)
    a = np.concatenate([a, pa])
    b = np.concatenate([b, pb])
    order = np.argsort(np.minimum(a, b) * model.n + np.maximum(a, b), kind="stable")
    return a[order], b[order]
