"""The broad phase's grid, sweep and plane tests (COURSE.md 5: the cheap
first half of detecting a collision; the narrow phase decides), run by
broad_phase.py, whose `candidate_pairs(kind, dims, is_static, reach, pos,
quat, margin)` gives the pairs the numpy reference broadphase.candidate_pairs
gives, in the Manifold order (static body, else the lower index, as `a`;
static–static pairs never appear), sorted by pair id min(a, b) n + max(a, b):

- solid pairs need overlapping margin-grown AABBs and bounding spheres
  (|c_a - c_b| <= R_a + R_b + margin), tested with broadphase._filter's
  operations in its order, so every pair gets the same yes or no;
- candidates come from a dense uniform grid over the AABB centres, filled
  by counting sort. The cell edge is the largest extent among the "small"
  bodies (<= SMALL_FACTOR × the median), so two small bodies that overlap
  sit in the same or adjacent cells; each cell is compared with itself and
  its 13 forward neighbours, which meets every pair once. A scene far wider
  than its bodies (more than DENSE_CELLS_PER_BODY cells per body) indexes
  its occupied cells by sorted keys instead of a dense table;
- the other, "large" bodies (a long slab) are swept along the axis where
  the boxes spread most against the small bodies and each other, so a pile
  never costs O(n²);
- planes skip the grid: each dynamic body is tested against each plane by
  its lowest point along the normal, with the numpy version's arithmetic
  (its matmul's fused multiply-adds, `plane_height`).

Hot loops store pairs themselves, call only scalar helpers and never
reassign an array variable: numba then emits reference-count updates that
cost more than the test itself.
"""
import math

import numpy as np
from numba import njit

from .geometry import (BOX, HALF, NORMAL, OFFSET, PLANE, RADIUS, dot_lanes, dot_seq, fma,
                       quat_matrix)
from .scratch import take, take_bools, take_int_rows, take_ints, take_rows

SMALL_FACTOR = 4.0          # a body more than this × the median AABB extent is "large"
MAX_CELLS = 2 ** 20         # grid cells per axis at most; a wider scene gets a coarser grid
                            # (both as in broadphase.py, the numpy reference)
DENSE_CELLS_PER_BODY = 16   # up to this many cells per body (+ DENSE_SPARE), a dense cell table
DENSE_SPARE = 4096
CELL_SLACK = 1e-9           # the cell edge grows by this much (relative) and by a few ulps of the
                            # coordinates, so rounding never puts touching bodies two cells apart
LO, HI, CEN, REACH = 0, 3, 6, 9   # columns of the solid table: AABB lo, hi, centre, bounding radius
COLS = 10
FORWARD_CELLS = 14          # a cell and its 13 forward neighbours: the cells one body is tested in


@njit(cache=True)
def box_half_extent(quat, dims, b):
    """World AABB half sizes |R| h of box b (broadphase.aabb_half_extents)."""
    R = quat_matrix(quat[b, 0], quat[b, 1], quat[b, 2], quat[b, 3])
    h0, h1, h2 = dims[b, HALF], dims[b, HALF + 1], dims[b, HALF + 2]
    return (dot_lanes(abs(R[0]), abs(R[1]), abs(R[2]), h0, h1, h2),
            dot_lanes(abs(R[3]), abs(R[4]), abs(R[5]), h0, h1, h2),
            dot_lanes(abs(R[6]), abs(R[7]), abs(R[8]), h0, h1, h2))


@njit(cache=True)
def solid_table(kind, dims, reach, pos, quat, margin, solid, cols):
    """cols (m, COLS): margin-grown AABB, centre and bounding radius of each
    solid (non-plane) body (broadphase.solid_columns)."""
    grow = 0.5 * margin
    for r in range(len(solid)):
        b = solid[r]
        rad = dims[b, RADIUS]
        half = box_half_extent(quat, dims, b) if kind[b] == BOX else (rad, rad, rad)
        for a in range(3):
            h = half[a] + grow
            cols[r, LO + a] = pos[b, a] - h
            cols[r, HI + a] = pos[b, a] + h
            cols[r, CEN + a] = pos[b, a]
        cols[r, REACH] = reach[b] + grow
    return cols


@njit(cache=True, inline="always")
def overlaps(cols, p, q):
    """Rows p, q pass broadphase._filter: bounding spheres, then boxes (touching counts)."""
    d = cols[p, CEN] - cols[q, CEN]
    d2 = d * d
    d = cols[p, CEN + 1] - cols[q, CEN + 1]
    d2 += d * d
    d = cols[p, CEN + 2] - cols[q, CEN + 2]
    d2 += d * d
    r = cols[p, REACH] + cols[q, REACH]
    # `&`, not `and`: numba lowers an `and` chain over array reads to many
    # blocks that cost several times the comparisons
    ok = d2 <= r * r
    for a in range(3):
        ok &= (cols[p, LO + a] <= cols[q, HI + a]) & (cols[q, LO + a] <= cols[p, HI + a])
    return ok


# ---- the pair list: (a, b) rows in Manifold order, grown by doubling -------------------

@njit(cache=True, inline="always")
def reserve(pairs, need):
    """`pairs` with room for `need` rows: the same array, or a copy at least twice as long."""
    out = pairs
    if need > len(pairs):
        out = np.empty((max(need, 2 * len(pairs)), 2), np.int64)
        out[:len(pairs)] = pairs
    return out


@njit(cache=True)
def manifold_order(i, j, static_i, static_j):
    """(a, b, keep) for bodies i, j: a static body first, else the lower
    index; keep is 0 for a static–static pair (never reported)."""
    lo, hi, static_lo, static_hi = (i, j, static_i, static_j) if i < j else (j, i, static_j, static_i)
    if static_hi and not static_lo:
        lo, hi = hi, lo
    return lo, hi, 0 if (static_i and static_j) else 1


@njit(cache=True)
def sort_pairs(pairs, k, n):
    """Rows 0..k of `pairs` sorted by pair id min n + max (a new array)."""
    return sort_into(pairs, k, np.zeros(n + 2, np.int64), np.empty((k, 2), np.int64))


@njit(cache=True, inline="always")
def sort_into(pairs, k, start, out):
    """sort_pairs into `out` (k, 2): a counting sort on the lower index
    (`start`: n + 2 zeros), then insertion sort within each (short) run."""
    n = len(start) - 2
    for r in range(k):
        start[min(pairs[r, 0], pairs[r, 1]) + 2] += 1
    for i in range(n + 1):
        start[i + 1] += start[i]
    for r in range(k):
        lo = min(pairs[r, 0], pairs[r, 1])
        at = start[lo + 1]
        start[lo + 1] += 1
        out[at, 0], out[at, 1] = pairs[r, 0], pairs[r, 1]
    for lo in range(n):
        if start[lo + 1] - start[lo] > 1:
            _sort_run(out, start[lo], start[lo + 1])
    return out


@njit(cache=True)
def _sort_run(out, s, e):
    """Insertion sort of rows s..e (one lower index) by the higher index."""
    for r in range(s + 1, e):
        a, b = out[r, 0], out[r, 1]
        key = max(a, b)
        t = r - 1
        while t >= s and max(out[t, 0], out[t, 1]) > key:
            out[t + 1, 0], out[t + 1, 1] = out[t, 0], out[t, 1]
            t -= 1
        out[t + 1, 0], out[t + 1, 1] = a, b


# ---- the grid ---------------------------------------------------------------------------

@njit(cache=True)
def _classify(cols, store):
    """(small rows, large rows, cell edge): small bodies are at most
    SMALL_FACTOR × the median AABB extent; the cell is the largest small extent."""
    m = len(cols)
    size = take(store, m)
    for r in range(m):
        size[r] = max(cols[r, HI] - cols[r, LO], cols[r, HI + 1] - cols[r, LO + 1],
                      cols[r, HI + 2] - cols[r, LO + 2])
    limit = SMALL_FACTOR * median(size, take(store, m))
    small, large = take_ints(store, m), take_ints(store, m)
    s = g = 0
    for r in range(m):
        if size[r] <= limit:
            small[s] = r
            s += 1
        else:
            large[g] = r
            g += 1
    small, large = small[:s], large[:g]
    cell = 0.0
    for r in small:
        cell = max(cell, size[r])
    return small, large, cell


@njit(cache=True)
def median(values, work):
    """np.median of finite `values`, without its temporary array: the middle
    order statistics selected in `work` (a scratch copy, reordered). The
    same number: the middle value, or the two middle ones' (a + b) / 2."""
    m = len(values)
    for i in range(m):
        work[i] = values[i]
    h = m // 2
    b = _select(work, h)
    if m % 2:
        return b
    a = work[0]                          # the largest of work[:h], all <= b now
    for i in range(1, h):
        a = max(a, work[i])
    return (a + b) / 2


@njit(cache=True)
def _select(x, k):
    """x[k] after reordering x so that x[:k] <= x[k] <= x[k + 1:] (Hoare's
    quickselect, middle pivot: equal values split evenly, so a scene of
    equal bodies costs O(m))."""
    lo, hi = 0, len(x) - 1
    while lo < hi:
        pivot = x[(lo + hi) // 2]
        i, j = lo, hi
        while i <= j:
            while x[i] < pivot:
                i += 1
            while x[j] > pivot:
                j -= 1
            if i <= j:
                x[i], x[j] = x[j], x[i]
                i += 1
                j -= 1
        if k <= j:
            hi = j
        elif k >= i:
            lo = i
        else:
            return x[k]
    return x[k]


@njit(cache=True)
def _cell_edge(cols, rows, cell, store):
    """(edge, origin (3,), dims (3,)): the grid cell edge, grown by the slack and
    coarsened so no axis has more than MAX_CELLS cells; one empty cell of
    padding on each side so neighbour keys never wrap round an axis. The
    centres are finite (finite_poses), so the maxima below are numpy's."""
    lo, hi = take(store, 3), take(store, 3)
    lo[:] = np.inf
    hi[:] = -np.inf
    for r in rows:
        for a in range(3):
            lo[a] = min(lo[a], cols[r, CEN + a])
            hi[a] = max(hi[a], cols[r, CEN + a])
    scale = spread = 0.0
    for a in range(3):
        scale = max(scale, abs(lo[a]), abs(hi[a]))
        spread = max(spread, hi[a] - lo[a])
    edge = cell * (1.0 + CELL_SLACK) + 8e-16 * scale
    edge = max(edge, spread / MAX_CELLS, 1e-300)
    dims = take_ints(store, 3)
    for a in range(3):
        dims[a] = _cell_index((hi[a] - lo[a]) / edge, MAX_CELLS) + 3
    return edge, lo, dims


@njit(cache=True)
def _cell_index(x, top):
    """floor(x) clamped to [0, top] before the integer conversion (NaN → 0),
    so no input can index outside the cell table."""
    x = x if x > 0.0 else 0.0
    return int(math.floor(x if x < top else top))


@njit(cache=True)
def _cell_keys(cols, rows, edge, origin, dims, keys):
    """keys: linear cell index of each row's centre (x slowest, z fastest)."""
    for s in range(len(rows)):
        key = 0
        for a in range(3):
            c = _cell_index((cols[rows[s], CEN + a] - origin[a]) / edge, dims[a] - 3) + 1
            key = key * dims[a] + c
        keys[s] = key
    return keys


@njit(cache=True)
def forward_spans(dims, out):
    """out (4,): the key of the first cell of each run of three neighbour
    cells after a cell, in (x, y, z) order. Cells (dx, dy, -1..1) have
    consecutive keys (z is fastest), so the 13 forward neighbours are the
    next cell (0, 0, 1) plus four runs of three: (0, 1, ·), (1, -1, ·),
    (1, 0, ·), (1, 1, ·). The rows of a run are one span of the sorted rows."""
    k = 0
    for dx in range(2):
        for dy in range(-1, 2):
            if 3 * dx + dy > 0:                    # (dx, dy) after (0, 0), lexicographically
                out[k] = (dx * dims[1] + dy) * dims[2] - 1
                k += 1
    return out


@njit(cache=True)
def _dense_index(keys, ncell, store):
    """Counting sort of the keys: (order, first) with the rows of cell c at
    order[first[c]:first[c + 1]], in row order within a cell."""
    first = take_ints(store, ncell + 2)
    first[:] = 0
    for key in keys:
        first[key + 2] += 1
    for c in range(ncell + 1):
        first[c + 1] += first[c]
    order = take_ints(store, len(keys))
    for s in range(len(keys)):
        order[first[keys[s] + 1]] = s
        first[keys[s] + 1] += 1
    return order, first


@njit(cache=True)
def _sparse_index(keys, store):
    """(order, first, cells): rows sorted by key; the occupied cells' keys,
    and their rows at order[first[u]:first[u + 1]]. In scratch: the sweep
    reads them once per body and cell, and an owned array there would cost
    reference counts on every read."""
    order = take_ints(store, len(keys))
    order[:] = np.argsort(keys, kind="mergesort")
    cells = take_ints(store, len(keys))
    first = take_ints(store, len(keys) + 1)
    u = 0
    for s in range(len(keys)):
        key = keys[order[s]]
        if u == 0 or cells[u - 1] != key:
            cells[u] = key
            first[u] = s
            u += 1
    first[u] = len(keys)
    return order, first[:u + 1], cells[:u]


# The sweep reads each row's candidate rows as [start, end) spans computed
# beforehand (_row_spans): with the index lookup (dense table or sorted
# occupied keys) inside the sweep's loop, the searches' code stayed in the
# loop though never run on a dense table, and the step's whole broad phase of
# a formed 1,000-sphere pile took 184 µs; with the spans apart, 82 µs.
SPANS = 2 + 2 * 4           # columns of the span table: own cell + next, then four runs of three


@njit(cache=True)
def _row_spans(first, cells, key, runs, spans):
    """spans[s] = [start, end) pairs of the sorted rows that row s is tested
    against: the later rows of its own cell and the next (0, 0, 1) cell,
    then each run of three forward cells (forward_spans). From the dense
    table `first` (rows of cell c at first[c]:first[c + 1]), or, when
    `cells` (the occupied keys, sorted) is not empty, from first[u] of the
    first occupied key at or after each bound: as keys grow with s, each
    bound's position only moves forward (a merge, not a search a bound)."""
    if len(cells) == 0:
        for s in range(len(key)):
            spans[s, 0], spans[s, 1] = s + 1, first[key[s] + 2]
            for c in range(len(runs)):
                k0 = key[s] + runs[c]
                spans[s, 2 + 2 * c], spans[s, 3 + 2 * c] = first[k0], first[k0 + 3]
        return spans
    at = np.zeros(SPANS, np.int64)
    for s in range(len(key)):
        spans[s, 0] = s + 1
        spans[s, 1] = first[_advance(cells, at, 1, key[s] + 2)]
        for c in range(len(runs)):
            k0 = key[s] + runs[c]
            spans[s, 2 + 2 * c] = first[_advance(cells, at, 2 + 2 * c, k0)]
            spans[s, 3 + 2 * c] = first[_advance(cells, at, 3 + 2 * c, k0 + 3)]
    return spans


@njit(cache=True, inline="always")
def _advance(cells, at, j, bound):
    """Move cursor j to the first occupied key >= bound (bounds only grow)."""
    u = at[j]
    while u < len(cells) and cells[u] < bound:
        u += 1
    at[j] = u
    return u


@njit(cache=True)
def _grid_pairs(cols, ids, small, cell, is_static, pairs, k, store):
    """Pairs among the small rows: each body against the later bodies of its
    own cell and every body of its 13 forward neighbour cells."""
    edge, origin, dims = _cell_edge(cols, small, cell, store)
    keys = _cell_keys(cols, small, edge, origin, dims, take_ints(store, len(small)))
    ncell = dims[0] * dims[1] * dims[2]
    if ncell <= DENSE_CELLS_PER_BODY * len(small) + DENSE_SPARE:
        order, first = _dense_index(keys, ncell, store)
        cells = take_ints(store, 0)
    else:
        order, first, cells = _sparse_index(keys, store)
    # the sweep's inputs in cell order (neighbours close in memory), in scratch
    sc, body, static, key = _in_cell_order(cols, ids, small, is_static, keys, order, store)
    runs = forward_spans(dims, take_ints(store, 4))
    spans = _row_spans(first, cells, key, runs, take_int_rows(store, len(key), SPANS))
    return _sweep_cells(sc, body, static, spans, _most_per_cell(first), pairs, k)


@njit(cache=True)
def _in_cell_order(cols, ids, small, is_static, keys, order, store):
    """(cols rows, body, is_static, key) of the small rows taken in `order`."""
    m = len(order)
    sc, body = take_rows(store, m, COLS), take_ints(store, m)
    static, key = take_bools(store, m), take_ints(store, m)
    for s in range(m):
        r = small[order[s]]
        for j in range(COLS):           # a row slice assignment took about 10 ns a row more
            sc[s, j] = cols[r, j]
        body[s] = ids[r]
        static[s] = is_static[body[s]]
        key[s] = keys[order[s]]
    return sc, body, static, key


@njit(cache=True)
def _most_per_cell(first):
    """The largest number of bodies in one cell."""
    most = 0
    for c in range(len(first) - 1):
        most = max(most, first[c + 1] - first[c])
    return most


@njit(cache=True)
def _sweep_cells(sc, body, static, spans, most, pairs, k):
    """The grid's pairs, sorted rows s < t: t in one of s's spans
    (_row_spans; `most`: the most rows of one cell). `pairs` grows between
    chunks of bodies whose pairs surely fit, never inside the loop over
    bodies (an array reassigned in a numba loop costs reference-count
    updates on every iteration)."""
    bound = FORWARD_CELLS * most     # pairs of one body, at most
    s = 0
    while s < len(body):
        pairs = reserve(pairs, k + bound)
        stop = min(len(body), s + (len(pairs) - k) // max(bound, 1))
        k = _sweep_chunk(sc, body, static, spans, s, stop, pairs, k)
        s = stop
    return pairs, k


@njit(cache=True)
def _sweep_chunk(sc, body, static, spans, start, stop, pairs, k):
    """_sweep_cells for sorted rows start..stop; returns the new pair count.
    The spans in order: the rest of s's own cell and the next cell, then
    the runs of three cells (forward_spans), the rows within each in cell
    order."""
    for s in range(start, stop):
        for c in range(0, SPANS, 2):
            for t in range(spans[s, c], spans[s, c + 1]):
                if overlaps(sc, s, t):
                    i, j, keep = manifold_order(body[s], body[t], static[s], static[t])
                    pairs[k, 0], pairs[k, 1] = i, j
                    k += keep
    return k


# ---- large bodies: sort and sweep -------------------------------------------------------

@njit(cache=True)
def _sweep_axis(cols):
    """The axis along which the AABB centres spread most (largest variance)."""
    best, axis = -1.0, 0
    for a in range(3):
        v = np.var(cols[:, LO + a] + cols[:, HI + a])
        if v > best:
            best, axis = v, a
    return axis


@njit(cache=True)
def _large_pairs(cols, ids, large, small, cell, is_static, pairs, k):
    """Large rows against the small rows whose lower bound lies in
    [lo - cell, hi] along the sweep axis (a small body overlapping [lo, hi]
    starts there), and against each other (j after i in lower-bound order
    overlaps i on that axis iff lo_j <= hi_i)."""
    axis = _sweep_axis(cols)
    reach = cell * (1.0 + CELL_SLACK) + 8e-16 * np.abs(cols[:, LO + axis]).max()
    sweep = cols[small, LO + axis]
    order = np.argsort(sweep, kind="mergesort")
    sweep, by_lo = sweep[order], small[order]
    for r in large:
        a = np.searchsorted(sweep, cols[r, LO + axis] - reach, side="left")
        b = np.searchsorted(sweep, cols[r, HI + axis], side="right")
        pairs = reserve(pairs, k + b - a)
        k = _test_rows(cols, ids, is_static, r, by_lo[a:b], pairs, k)
    big = large[np.argsort(cols[large, LO + axis], kind="mergesort")]
    for s in range(len(big)):
        t = s + 1
        while t < len(big) and cols[big[t], LO + axis] <= cols[big[s], HI + axis]:
            t += 1
        pairs = reserve(pairs, k + t - s - 1)
        k = _test_rows(cols, ids, is_static, big[s], big[s + 1:t], pairs, k)
    return pairs, k


@njit(cache=True)
def _test_rows(cols, ids, is_static, r, others, pairs, k):
    """Row r against each of `others`; the pairs that pass are stored from k on."""
    for t in others:
        if overlaps(cols, r, t):
            i, j, keep = manifold_order(ids[r], ids[t], is_static[ids[r]], is_static[ids[t]])
            pairs[k, 0], pairs[k, 1] = i, j
            k += keep
    return k


# ---- planes -------------------------------------------------------------------------------

@njit(cache=True)
def plane_height(x0, x1, x2, n0, n1, n2, mode):
    """n·x as numpy's `pos @ n.T` computes it here (OpenBLAS): mode 0 a plain
    sum (one body, one plane: a dot product), 1 the fused chain from the y
    term (gemv: one body or one plane), 2 the fused chain in order (gemm)."""
    if mode == 0:
        return dot_seq(x0, x1, x2, n0, n1, n2)
    if mode == 1:
        return fma(x2, n2, fma(x0, n0, x1 * n1))
    return fma(x2, n2, fma(x1, n1, x0 * n0))


@njit(cache=True)
def box_support(w, x, y, z, h0, h1, h2, n0, n1, n2):
    """How far a box reaches from its centre along unit n: Σ_j h_j |n·axis_j|
    (broadphase.support_along's einsum orders)."""
    R = quat_matrix(w, x, y, z)
    p0 = abs(dot_seq(R[0], R[3], R[6], n0, n1, n2))
    p1 = abs(dot_seq(R[1], R[4], R[7], n0, n1, n2))
    p2 = abs(dot_seq(R[2], R[5], R[8], n0, n1, n2))
    return dot_lanes(p0, p1, p2, h0, h1, h2)


@njit(cache=True, inline="always")
def _plane_gaps(kind, dims, pos, quat, p, bodies, mode, gaps):
    """gaps[r]: height of body r's lowest point above plane p (n·x = offset)."""
    n0, n1, n2 = dims[p, NORMAL], dims[p, NORMAL + 1], dims[p, NORMAL + 2]
    for r in range(len(bodies)):
        b = bodies[r]
        height = plane_height(pos[b, 0], pos[b, 1], pos[b, 2], n0, n1, n2, mode) - dims[p, OFFSET]
        low = dims[b, RADIUS]
        if kind[b] == BOX:
            low = box_support(quat[b, 0], quat[b, 1], quat[b, 2], quat[b, 3],
                              dims[b, HALF], dims[b, HALF + 1], dims[b, HALF + 2], n0, n1, n2)
        gaps[r] = height - low


@njit(cache=True, inline="always")
def _plane_pairs(kind, dims, pos, quat, margin, planes, bodies, gaps, pairs, k):
    """(plane, body) for each dynamic body (`bodies`) whose lowest point lies
    less than `margin` above a plane n·x = offset (solid below); gaps:
    scratch of len(bodies)."""
    mode = 1 if (len(planes) == 1 or len(bodies) == 1) else 2
    if len(planes) == 1 and len(bodies) == 1:
        mode = 0
    pairs = reserve(pairs, k + len(planes) * len(bodies))
    for p in planes:
        _plane_gaps(kind, dims, pos, quat, p, bodies, mode, gaps)
        for r in range(len(bodies)):
            if gaps[r] < margin:
                pairs[k, 0], pairs[k, 1] = p, bodies[r]
                k += 1
    return pairs, k


@njit(cache=True, inline="always")
def finite_poses(kind, pos, quat):
    """Are the poses detection reads finite: every solid body's position and
    every box's orientation? (The numpy broad phase raises on others; the
    grid needs finite centres.)"""
    ok = True
    for b in range(len(kind)):
        if kind[b] != PLANE:
            ok &= np.isfinite(pos[b, 0]) & np.isfinite(pos[b, 1]) & np.isfinite(pos[b, 2])
        if kind[b] == BOX:
            ok &= (np.isfinite(quat[b, 0]) & np.isfinite(quat[b, 1]) & np.isfinite(quat[b, 2])
                   & np.isfinite(quat[b, 3]))
    return ok
