"""Compiled collision detection: broad phase, then every pair's kernel, in
one jitted call (COURSE.md 5: for each pair that touches, the contact
point, the normal that separates the bodies, and the depth).

`Detector(model).detect(pos, quat, margin)` returns what
manifold.detect(model, pos, quat, margin) returns, under the Manifold
contract (manifold.py): rows with depth > -margin, `a` static or the lower
index, normal from a to b, key = pair_id * SLOTS + slot, sorted by key,
keys unique. The pairs come from broad_phase.py sorted by pair id and each kernel
writes its rows in slot order, so the rows come out sorted. Rows go to a
buffer that doubles when full; the kept ones are copied out at the end.

`signed_depth(i, j, kind, dims, pa, qa, pb, qb, scratch)` is the compiled
narrowphase.signed_depth of one pair at given poses, for other @njit code
(a continuous-collision search); `depth_scratch()` makes its scratch.

Hot loops here call kernels with few arrays, keep their branches on
scalars and never reassign an array variable: numba then emits
reference-count updates that can cost more than a sphere pair's arithmetic.
"""
import numpy as np
from numba import njit

from ..borrowed import borrow, keep_alive
from ..errors import NonFiniteStateError
from .box_pair import WS_ROWS, box_box, separation, workspace
from .geometry import BOX, PLANE, Geometry
from .broad_phase import candidate_pairs, scratch_pairs
from .grid import finite_poses
from .manifold import SLOTS, Manifold
from .scratch import take, take_ints, take_rows
from .shape_pairs import (DEPTH, NORMAL_COL, POINT, ROW, SLOT, box_sphere, plane_box, plane_sphere,
                          sphere_sphere)

MAX_ROWS_PER_PAIR = 4
SPHERE_SPHERE, PLANE_SPHERE, PLANE_BOX, BOX_SPHERE, BOX_BOX, NO_KERNEL = range(6)
# by kind[a] * 3 + kind[b] (SPHERE 0, BOX 1, PLANE 2): the kernel, and whether
# it takes the pair the other way round (its first body is b)
_KERNEL = (SPHERE_SPHERE, BOX_SPHERE, PLANE_SPHERE, BOX_SPHERE, BOX_BOX, PLANE_BOX,
           PLANE_SPHERE, PLANE_BOX, NO_KERNEL)
_SWAPPED = (False, True, True, False, False, True, False, False, False)


@njit(cache=True)
def grow_rows(rows, row_pair, k):
    """Row buffers twice as long, holding the first k rows."""
    bigger = np.empty((2 * len(rows), ROW))
    bigger[:k] = rows[:k]
    pair = np.empty(2 * len(rows), np.int64)
    pair[:k] = row_pair[:k]
    return bigger, pair


@njit(cache=True)
def run_kernel(kernel, f, s, dims, pos, quat, margin, ws, rows, k):
    """Rows of kernel `kernel` for bodies f, s (its order) from row k; the count."""
    count = 0
    if kernel == SPHERE_SPHERE:
        count = sphere_sphere(f, s, dims, pos, quat, margin, ws, rows, k)
    elif kernel == PLANE_SPHERE:
        count = plane_sphere(f, s, dims, pos, quat, margin, ws, rows, k)
    elif kernel == PLANE_BOX:
        count = plane_box(f, s, dims, pos, quat, margin, ws, rows, k)
    elif kernel == BOX_SPHERE:
        count = box_sphere(f, s, dims, pos, quat, margin, ws, rows, k)
    elif kernel == BOX_BOX:
        count = box_box(f, s, dims, pos, quat, margin, ws, rows, k)
    return count


@njit(cache=True)
def flip_normals(rows, k, count):
    """Rows k..k+count: normal from the kernel's first body to its second → the other way."""
    for r in range(k, k + count):
        for m in range(NORMAL_COL, NORMAL_COL + 3):
            rows[r, m] = -rows[r, m]


@njit(cache=True)
def pair_rows(a, b, kind, dims, pos, quat, margin, ws, rows, k):
    """Rows of pair (a, b) from row k with the normal from a towards b; the
    count. Not cut at the margin (single-row kinds always give one row)."""
    code = kind[a] * 3 + kind[b]
    swapped = _SWAPPED[code]
    f, s = (b, a) if swapped else (a, b)
    count = run_kernel(_KERNEL[code], f, s, dims, pos, quat, margin, ws, rows, k)
    if swapped:
        flip_normals(rows, k, count)
    return count


@njit(cache=True)
def narrow_rows(pairs, kind, dims, pos, quat, margin, cap):
    """(rows, row_pair, k): every pair's rows, in pair order, with its pair's index."""
    rows = np.empty((max(cap, 16), ROW))
    return fill_rows(pairs, kind, dims, pos, quat, margin, workspace(), rows,
                     np.empty(len(rows), np.int64))


@njit(cache=True, inline="always")
def fill_rows(pairs, kind, dims, pos, quat, margin, ws, rows, row_pair):
    """narrow_rows into the given buffers (ws: any contents; every kernel writes
    a workspace entry before it reads it). The buffers grow between
    chunks of pairs that surely fit, never inside the loop over pairs: a numba
    array variable reassigned in a loop costs reference-count updates on every
    iteration (about 3× a sphere pair)."""
    k = p = 0
    while p < len(pairs):
        if k + MAX_ROWS_PER_PAIR > len(rows):
            rows, row_pair = grow_rows(rows, row_pair, k)
        stop = min(len(pairs), p + (len(rows) - k) // MAX_ROWS_PER_PAIR)
        k = chunk_rows(pairs, p, stop, kind, dims, pos, quat, margin, ws, rows, row_pair, k)
        p = stop
    return rows, row_pair, k


@njit(cache=True)
def chunk_rows(pairs, start, stop, kind, dims, pos, quat, margin, ws, rows, row_pair, k):
    """Rows of pairs start..stop from row k on (room for MAX_ROWS_PER_PAIR
    each); returns the new row count. The kernel dispatch is written out:
    see the module notes."""
    for p in range(start, stop):
        code = kind[pairs[p, 0]] * 3 + kind[pairs[p, 1]]
        kernel, swapped = _KERNEL[code], _SWAPPED[code]
        f, s = (pairs[p, 1], pairs[p, 0]) if swapped else (pairs[p, 0], pairs[p, 1])
        if kernel == SPHERE_SPHERE:
            count = sphere_sphere(f, s, dims, pos, quat, margin, ws, rows, k)
        elif kernel == PLANE_SPHERE:
            count = plane_sphere(f, s, dims, pos, quat, margin, ws, rows, k)
        elif kernel == BOX_SPHERE:
            count = box_sphere(f, s, dims, pos, quat, margin, ws, rows, k)
        elif kernel == BOX_BOX:
            count = box_box(f, s, dims, pos, quat, margin, ws, rows, k)
        else:
            count = run_kernel(kernel, f, s, dims, pos, quat, margin, ws, rows, k)
        if swapped:
            flip_normals(rows, k, count)
        for r in range(k, k + count):
            row_pair[r] = p
        k += count
    return k


@njit(cache=True, inline="always")
def kept_count(rows, k, margin):
    """How many of the first k rows have depth > -margin."""
    kept = 0
    for r in range(k):
        kept += rows[r, DEPTH] > -margin
    return kept


@njit(cache=True)
def manifold_arrays(rows, row_pair, k, pairs, margin, n):
    """(a, b, point, normal, depth, key) of the rows with depth > -margin."""
    kept = kept_count(rows, k, margin)
    out = (np.empty(kept, np.int64), np.empty(kept, np.int64), np.empty((kept, 3)),
           np.empty((kept, 3)), np.empty(kept), np.empty(kept, np.int64))
    fill_manifold(rows, row_pair, k, pairs, margin, n, borrow(out))
    return out


@njit(cache=True, inline="always")
def fill_manifold(rows, row_pair, k, pairs, margin, n, out):
    """manifold_arrays into out = (a, b, point, normal, depth, key), sized to the kept rows."""
    a, b, point, normal, depth, key = out
    w = 0
    for r in range(k):
        if rows[r, DEPTH] > -margin:
            i, j = pairs[row_pair[r], 0], pairs[row_pair[r], 1]
            a[w], b[w] = i, j
            key[w] = (min(i, j) * n + max(i, j)) * SLOTS + np.int64(rows[r, SLOT])
            point[w, 0], point[w, 1], point[w, 2] = rows[r, POINT], rows[r, POINT + 1], rows[r, POINT + 2]
            normal[w, 0], normal[w, 1], normal[w, 2] = (rows[r, NORMAL_COL], rows[r, NORMAL_COL + 1],
                                                        rows[r, NORMAL_COL + 2])
            depth[w] = rows[r, DEPTH]
            w += 1


@njit(cache=True)
def detect_arrays(kind, dims, is_static, reach, pos, quat, margin, cap):
    """(a, b, point, normal, depth, key) of every contact with depth > -margin,
    sorted by key, and the number of rows computed (-1, and no rows, when a
    pose is not finite); `cap` is a first guess of that number."""
    if not finite_poses(kind, pos, quat):
        pairs = np.zeros((0, 2), np.int64)
        rows, row_pair, k = narrow_rows(pairs, kind, dims, pos, quat, margin, 0)
        return manifold_arrays(rows, row_pair, k, pairs, margin, len(kind)), -1
    pairs_owned = candidate_pairs(kind, dims, is_static, reach, pos, quat, margin)
    pairs = borrow(pairs_owned)                   # physics_core/borrowed.py
    found = narrow_rows(pairs, kind, dims, pos, quat, margin, cap)
    rows, row_pair, k = borrow(found)
    out = manifold_arrays(rows, row_pair, k, pairs, margin, len(kind))
    keep_alive(found)
    keep_alive(pairs_owned)
    return out, k


@njit(cache=True, inline="always")
def detect_scratch(kind, dims, is_static, reach, pos, quat, margin, cap, store):
    """detect_arrays for the step loop: the same contacts, in views of the
    scratch store (scratch.py), valid until the next substep's detection."""
    if not finite_poses(kind, pos, quat):
        return _scratch_contacts(store, 0), -1
    pairs = scratch_pairs(kind, dims, is_static, reach, pos, quat, margin, store)
    rows = take_rows(store, max(cap, 16), ROW)
    # left as the scratch holds it: a box pair writes every workspace entry it
    # reads (tests/test_detection_kernels.py fills it with NaN), and zeroing
    # its 528 numbers was about 2 % of a one-sphere step
    ws = take_rows(store, WS_ROWS, 8)
    found = fill_rows(pairs, kind, dims, pos, quat, margin, ws, rows,
                      take_ints(store, len(rows)))
    rows, row_pair, k = borrow(found)
    out = _scratch_contacts(store, kept_count(rows, k, margin))
    fill_manifold(rows, row_pair, k, pairs, margin, len(kind), out)
    keep_alive(found)
    return out, k


@njit(cache=True, inline="always")
def _scratch_contacts(store, kept):
    """(a, b, point, normal, depth, key) views of `kept` rows."""
    return (take_ints(store, kept), take_ints(store, kept),
            take_rows(store, kept, 3), take_rows(store, kept, 3),
            take(store, kept), take_ints(store, kept))


class Detector:
    """Collision detection for one model (a Model is frozen): the shape data
    packed once (geometry.py), then one compiled call per `detect`."""

    def __init__(self, model):
        self.geometry = Geometry.from_model(model)
        self.n = model.n
        self._cap = 16      # rows computed by the last call: the next call's first buffer size

    def detect(self, pos, quat, margin: float = 0.0) -> Manifold:
        """manifold.detect(model, pos, quat, margin), compiled (same contract,
        same rows). A non-finite position of a solid body or orientation of a
        box raises NonFiniteStateError naming the bodies (the numpy broad
        phase fails on them too; the grid needs finite centres)."""
        g = self.geometry
        pos, quat = _plain(pos), _plain(quat)
        (a, b, point, normal, depth, key), k = detect_arrays(g.kind, g.dims, g.is_static, g.reach,
                                                             pos, quat, float(margin), self._cap)
        if k < 0:
            self._raise_non_finite(pos, quat)
        self._cap = k + k // 8 + MAX_ROWS_PER_PAIR
        return Manifold(a=a, b=b, point=point, normal=normal, depth=depth, key=key)

    def _raise_non_finite(self, pos, quat):
        g = self.geometry
        bad = (((g.kind != PLANE) & ~np.isfinite(pos).all(axis=1))
               | ((g.kind == BOX) & ~np.isfinite(quat).all(axis=1)))
        bodies = np.flatnonzero(bad)
        raise NonFiniteStateError(f"collision detection: non-finite pose of bodies {bodies.tolist()}",
                                  stage="detect", bodies=bodies)


def _plain(x):
    """x as a writable C-contiguous float64 array (a copy only when it is not
    one): every call then has the one compiled signature (numba compiles a
    read-only or strided array as another type)."""
    if type(x) is np.ndarray and x.dtype == np.float64 and x.flags.c_contiguous and x.flags.writeable:
        return x
    return np.array(x, dtype=np.float64, order="C")


# ---- one pair's signed depth, for other compiled code ---------------------------------

@njit(cache=True)
def depth_scratch():
    """Scratch for signed_depth: (box workspace, kinds (2,), dims (2, 8),
    positions (2, 3), orientations (2, 4), rows)."""
    return (workspace(), np.zeros(2, np.int64), np.zeros((2, 8)), np.zeros((2, 3)), np.zeros((2, 4)),
            np.zeros((MAX_ROWS_PER_PAIR, ROW)))


@njit(cache=True)
def signed_depth(i, j, kind, dims, pa, qa, pb, qb, scratch):
    """How far bodies i and j overlap at poses (pa, qa), (pb, qb): > 0
    overlapping, <= 0 apart (narrowphase.signed_depth). The sign is exact;
    for separated boxes the magnitude is a lower bound of the gap (the
    largest separating-axis distance); -inf for a pair no kernel handles."""
    ws, k2, d2, p2, q2, rows = scratch
    k2[0], k2[1] = kind[i], kind[j]
    d2[0], d2[1] = dims[i], dims[j]
    p2[0], p2[1] = pa, pb
    q2[0], q2[1] = qa, qb
    if kind[i] == BOX and kind[j] == BOX:
        return -separation(0, 1, d2, p2, q2, ws)
    count = pair_rows(0, 1, k2, d2, p2, q2, np.inf, ws, rows, 0)
    out = -np.inf
    for r in range(count):      # np.maximum: a NaN depth gives NaN
        d = rows[r, DEPTH]
        out = d if (d != d or d > out) else out
    return out


@njit(cache=True)
def signed_depths(kind, dims, a, b, pa, qa, pb, qb):
    """(k,) signed_depth of pairs (a[r], b[r]) at the poses of row r."""
    scratch = depth_scratch()
    out = np.empty(len(a))
    for r in range(len(a)):
        out[r] = signed_depth(a[r], b[r], kind, dims, pa[r], qa[r], pb[r], qb[r], scratch)
    return out
