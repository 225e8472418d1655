"""The broad phase's entry points: the pairs of bodies that may touch
(COURSE.md 5), from the grid and plane tests of grid.py, with the solid
pairs kept between the step's substeps (kept_pairs.py).

`candidate_pairs(kind, dims, is_static, reach, pos, quat, margin)` gives
the pairs (k, 2) in the Manifold order, sorted by pair id (grid.py's
docstring); `scratch_pairs(..., store)` the same for the step loop, in
the substep's scratch, reusing the pairs the last substeps kept.
"""
import numpy as np
from numba import njit

from ..borrowed import borrow, keep_alive
from .geometry import PLANE
from .grid import (COLS, _classify, _grid_pairs, _large_pairs, _plane_pairs, reserve, solid_table,
                   sort_into, sort_pairs)
from .kept_pairs import fat_table, keep, kept_table, pair_table, passing, skin_of
from .scratch import KEPT, PAIR_GUESS, empty_store, take, take_int_rows, take_ints, take_rows


@njit(cache=True)
def candidate_pairs(kind, dims, is_static, reach, pos, quat, margin):
    """(k, 2) int64 pairs (a, b) in Manifold order, sorted by pair id; the
    poses must be finite (grid.finite_poses)."""
    bodies = np.flatnonzero(~is_static & (kind != PLANE))
    found = find_pairs(kind, dims, is_static, reach, pos, quat, margin,
                       np.flatnonzero(kind != PLANE), np.flatnonzero(kind == PLANE), bodies,
                       np.empty(len(bodies)), np.empty((max(16, 4 * len(kind)), 2), np.int64),
                       empty_store())
    return sort_pairs(found[0], found[1], len(kind))


@njit(cache=True, inline="always")
def find_pairs(kind, dims, is_static, reach, pos, quat, margin, solid, planes, bodies, gaps, pairs,
               store):
    """(pairs, k): the unsorted candidate pairs in `pairs` (grown if short, a
    new array then); solid, planes, bodies: the solid bodies, the planes,
    the dynamic solid bodies; gaps: scratch of len(bodies); store: the
    scratch of the tables made on the way and the kept pairs (scratch.py;
    empty_store() makes the tables new arrays and keeps nothing)."""
    k = 0
    if len(solid) >= 2:
        cols = solid_table(kind, dims, reach, pos, quat, margin, solid,
                           take_rows(store, len(solid), COLS))
        kept = store[2]
        table, holds = kept_table(kept, store[1], cols, margin)
        if not holds:
            table = _grid_table(cols, solid, len(kind), is_static, margin, pairs, kept, store)
        pairs = reserve(pairs, len(table))
        k = passing(cols, table, pairs, 0)
    return _plane_pairs(kind, dims, pos, quat, margin, planes, bodies, gaps, pairs, k)


@njit(cache=True)
def _grid_table(cols, solid, n, is_static, margin, pairs, kept, store):
    """The grid run on the solid table's boxes grown by the skin: its pairs
    as a kept_pairs table (k, PAIR) in scratch, kept in `kept` for the next
    substeps. The bodies are sorted into small and large by their own
    boxes and the cell grown by the skin on each side: it still holds every
    small body's grown box."""
    small, large, cell = _classify(cols, store)
    skin = skin_of(cols, cell)
    fat = fat_table(cols, skin, take_rows(store, len(cols), COLS))
    cell += 2.0 * skin
    k = 0
    if len(small) >= 2:
        pairs, k = _grid_pairs(fat, solid, small, cell, is_static, pairs, k, store)
    if len(large):
        pairs, k = _large_pairs(fat, solid, large, small, cell, is_static, pairs, k)
    table = pair_table(pairs, k, solid, n, store)
    keep(kept, store[1], fat, skin, table, margin)
    return table


@njit(cache=True, inline="always")
def scratch_pairs(kind, dims, is_static, reach, pos, quat, margin, store):
    """candidate_pairs for the step loop, in a view of the scratch store
    (scratch.py) valid until the next substep's detection."""
    n = len(kind)
    solid, planes, bodies = _body_lists(kind, is_static, store)
    counts = store[1]
    room = take_int_rows(store, max(16, 4 * n, counts[PAIR_GUESS]), 2)
    found = find_pairs(kind, dims, is_static, reach, pos, quat, margin, solid, planes, bodies,
                       take(store, len(bodies)), room, store)
    pairs, k = borrow(found)
    # room for as many next time, and for the kept pairs the grid finds
    counts[PAIR_GUESS] = max(k, counts[KEPT]) + k // 8
    start = take_ints(store, n + 2)
    start[:] = 0
    out = sort_into(pairs, k, start, take_int_rows(store, k, 2))
    keep_alive(found)
    return out


@njit(cache=True, inline="always")
def _body_lists(kind, is_static, store):
    """(solid, planes, dynamic solid) body indices, ascending, in scratch views."""
    n = len(kind)
    solid, planes, bodies = take_ints(store, n), take_ints(store, n), take_ints(store, n)
    s = p = d = 0
    for i in range(n):
        if kind[i] == PLANE:
            planes[p] = i
            p += 1
        else:
            solid[s] = i
            s += 1
            if not is_static[i]:
                bodies[d] = i
                d += 1
    return solid[:s], planes[:p], bodies[:d]
