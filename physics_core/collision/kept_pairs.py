"""The broad phase's pairs kept from one substep to the next (a Verlet list;
Box2D and Bullet keep "fat" AABBs for the same reason).

When the grid runs, it runs on fat boxes: every solid body's margin-grown
AABB grown by a skin s (SKIN × the grid's cell, the largest extent of the
bodies it sorts into cells) on each side, and its bounding radius r grown
to (r + s)(1 + SPARE). What it finds is kept with those boxes and the
centres: the pairs that pass grid.overlaps on the fat table. While every
body's box lies inside its fat box and its centre within s of the kept
one, two bodies that pass the test now passed it on the fat table: their
boxes overlap now, so their fat boxes overlapped; their centres were at
most 2 s further apart, which the fat radii add. So the kept pairs hold
every pair the grid would find now, and a substep tests only them, with
the grid's own test on this substep's table: the pairs are exactly a
fresh grid's, and so is everything after them. The box containment is a
comparison of stored numbers; the distances' rounding (a few parts in
1e16 of each) is covered by SPARE (s is also at least LEAST_SKIN of the
largest bounding radius). A body outside its bounds, a change of margin or
of the number of solid bodies runs the grid again.

Kept in the store's third buffer (scratch.py), which outlives the substep:
the margin the boxes were grown by, the number of solid bodies m and the
skin (HEAD numbers), then m rows of BOX numbers (the fat box's lo (3) and
hi (3), the centre (3)), then the pairs as int64 rows of PAIR (body a,
body b in the Manifold order, and their rows in the solid table).
counts[KEPT] is how many pairs are kept (-1: none, the grid must run),
counts[KEPT_NEED] the buffer's size the last run needed (open_arena grows
the buffer to it).

In the benchmark's piles of falling spheres (benchmarks.pile_compare) the
grid runs in 28 of the first 240 substeps of the pile of 10 and in 106 of
the pile of 1,000; a pile at rest keeps its pairs.
"""
from numba import njit

from .grid import CEN, HI, LO, REACH, overlaps
from .scratch import KEPT, KEPT_NEED, int_rows_at, take_int_rows, take_ints

SKIN = 0.1              # the fat box's skin, a fraction of the grid's cell
LEAST_SKIN = 1e-9       # the skin at least, a fraction of the largest bounding radius
SPARE = 2.0 ** -20      # the fat radii's relative spare, far above the distances' rounding
MARGIN_AT, M_AT, SKIN_AT, HEAD = 0, 1, 2, 3
BOX = 9                 # numbers a body's fat box takes: lo (3), hi (3), centre (3)
PAIR = 4                # int64 columns of a kept pair: a, b, row of a, row of b


@njit(cache=True)
def kept_table(kept, counts, cols, margin):
    """(the kept pairs (k, PAIR), a view of `kept`; whether they hold every
    pair now: every row of the solid table `cols` lies inside its kept fat
    box, grown by this margin)."""
    k, m = counts[KEPT], len(cols)
    if (k < 0 or len(kept) < HEAD + BOX * m + PAIR * k or kept[MARGIN_AT] != margin
            or kept[M_AT] != m):
        return int_rows_at(kept, 0, 0, PAIR), False
    inside = True
    skin2 = kept[SKIN_AT] * kept[SKIN_AT]
    for r in range(m):
        at = HEAD + BOX * r
        moved = 0.0
        for a in range(3):          # `&`, no branch: the loop runs through
            inside &= (kept[at + a] <= cols[r, LO + a]) & (cols[r, HI + a] <= kept[at + 3 + a])
            d = cols[r, CEN + a] - kept[at + 6 + a]
            moved += d * d
        inside &= moved <= skin2
    return int_rows_at(kept, HEAD + BOX * m, k, PAIR), inside


@njit(cache=True)
def fat_table(cols, skin, fat):
    """fat (m, COLS): cols' boxes grown by `skin` on each side, bounding radii
    r grown to (r + skin)(1 + SPARE), same centres."""
    for r in range(len(cols)):
        for a in range(3):
            fat[r, LO + a] = cols[r, LO + a] - skin
            fat[r, HI + a] = cols[r, HI + a] + skin
            fat[r, CEN + a] = cols[r, CEN + a]
        fat[r, REACH] = (cols[r, REACH] + skin) * (1.0 + SPARE)
    return fat


@njit(cache=True)
def skin_of(cols, cell):
    """SKIN × the grid's cell (the largest extent of a small body), at least
    LEAST_SKIN × the largest bounding radius."""
    largest = 0.0
    for r in range(len(cols)):
        largest = max(largest, cols[r, REACH])
    return max(SKIN * cell, LEAST_SKIN * largest)


@njit(cache=True)
def pair_table(pairs, k, solid, n, store):
    """(k, PAIR) in scratch: pairs[:k] (body ids) with their rows in the solid
    table (solid: the solid bodies' ids, ascending)."""
    row = take_ints(store, n)
    for r in range(len(solid)):
        row[solid[r]] = r
    table = take_int_rows(store, k, PAIR)
    for p in range(k):
        a, b = pairs[p, 0], pairs[p, 1]
        table[p, 0], table[p, 1], table[p, 2], table[p, 3] = a, b, row[a], row[b]
    return table


@njit(cache=True)
def keep(kept, counts, fat, skin, table, margin):
    """Keep `table` with the fat table it was found on, if the buffer holds
    them; else ask open_arena for the room (nothing kept until then)."""
    m, k = len(fat), len(table)
    need = HEAD + BOX * m + PAIR * k
    counts[KEPT_NEED] = need
    if need > len(kept):
        counts[KEPT] = -1
        return
    kept[MARGIN_AT], kept[M_AT], kept[SKIN_AT] = margin, m, skin
    for r in range(m):
        at = HEAD + BOX * r
        for a in range(3):
            kept[at + a], kept[at + 3 + a] = fat[r, LO + a], fat[r, HI + a]
            kept[at + 6 + a] = fat[r, CEN + a]
    out = int_rows_at(kept, HEAD + BOX * m, k, PAIR)
    out[:] = table
    counts[KEPT] = k


@njit(cache=True)
def passing(cols, table, pairs, k):
    """The pairs of `table` that pass grid.overlaps on this substep's solid
    table, stored in `pairs` from row k (room for all of them); the new count."""
    for p in range(len(table)):
        if overlaps(cols, table[p, 2], table[p, 3]):
            pairs[k, 0], pairs[k, 1] = table[p, 0], table[p, 1]
            k += 1
    return k
