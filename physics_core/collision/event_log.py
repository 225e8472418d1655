"""Contact events of a step (contact_events.ContactEvents) gathered from plain
arrays by compiled merges over sorted contact keys, with all state in numba
containers so that compiled code (a loop over steps in nopython mode) can
run a whole step's event bookkeeping and keep it between calls.

Semantics (those of events.EventAccumulator, without a ContactRows object):
a contact is identified by its Manifold key (pair and feature). It is
"touching" in a substep when depth >= 0 or λ_n > 0. Over one step: `begin`
if it touches now and did not in the previous step, `persist` if it did,
`end` (zero impulse, last known point) if it touched in the previous step and
not in this one. A contact whose bodies have all gone to sleep (or are
static) is frozen, not ended: it is not reported while they sleep and
continues as `persist` when they wake. Impulses are summed over the
substeps; the friction impulse is the length of the summed tangential
impulse vector; point, normal, depth and bodies are the last substep's; the
normal speed is the largest approach speed seen (before the solve, > 0
closing). When a body is removed, the remembered contacts it had end at the
next finished step (after that step's own events, -1 for the removed body).

State (`new_event_state`): a tuple (ints, flts, counts). `ints` and `flts`
are numba typed lists holding one int64 and one float64 2-D row array;
compiled code grows them by putting larger arrays in the lists, and the
Python-side lists see the replacement (a list is shared by reference, a
tuple of arrays would not be). The arrays are split into four regions of
equal capacity (counts[CAP] rows each); counts also holds how many rows of
each region are in use:

- CUR: the contacts gathered so far in this step, PREV: the ones remembered
  from the last step (touching and frozen); rows (KEY, BODY_A, BODY_B) and
  the float columns below, sorted by key. Substeps merge into CUR in place;
  at the end of the step the frozen contacts are merged in too and CUR and
  PREV swap roles (counts[FLIP]), so nothing else is copied.
- OUT: the last finished step's events (columns O_*), overwritten by the
  next finish; events_output copies them into a ContactEvents.
- GONE: ends of removed bodies' contacts not reported yet (rows as PREV's,
  bodies renumbered, -1 for the removed one), appended to the next finish's
  output.

Calls from Python should not pass the state tuple to a compiled function:
numba types a tuple holding typed lists in Python on every call (~20 µs).
The Python functions here (and EventLog) unpack it and pass the three
containers as separate arguments (~1.5 µs); the `events_*` kernels that take
the tuple are for compiled callers.
"""
import math

import numpy as np
from numba import njit
from numba.typed import List

from ..borrowed import borrow
from ..contact_events import BEGIN, END, PERSIST, ContactEvents
from .manifold import SLOTS
from .warm_cache import remap_keys

# int64 columns of the contact rows
KEY = 0
BODY_A = 1
BODY_B = 2
ICOL = 3

# float64 columns of the contact rows
POINT = 0        # (3) world contact point, last substep's
NORMAL = 3       # (3) unit normal from body a towards body b, last substep's
DEPTH = 6        # penetration, last substep's
IMPULSE = 7      # normal impulse summed over the substeps
FRICTION = 8     # (3) tangential impulse vector summed over the substeps
SPEED = 11       # largest approach speed of the substeps
NCOL = 12

# columns of the output rows (one per event, in the same arrays): int64 ...
O_A, O_B, O_EVENT = 0, 1, 2
# ... and float64
O_POINT, O_NORMAL, O_IMPULSE, O_FRICTION, O_SPEED, O_DEPTH = 0, 3, 6, 7, 8, 9

# the regions of the state's arrays (CUR and PREV: regions FLIP and 1 - FLIP)
OUT, GONE, REGIONS = 2, 3, 4
# the entries of the state's counts
M, P, K, G = 0, 1, 2, 3         # rows in use in CUR, PREV, OUT, GONE
FLIP = 4                        # the region (0 or 1) holding CUR; PREV is the other
CAP = 5                         # rows per region
N_COUNTS = 6


def _empty_events():
    """One ContactEvents without rows, returned by every step without an event
    (a fresh one costs more than the rest of such a step). Its arrays have no
    element to change, so sharing it is safe; they stay writable, as fresh
    ones are (in-place arithmetic on them works as on any empty array)."""
    return ContactEvents.empty()


_EMPTY = _empty_events()


# ---- kernels: one substep's rows into the step's sorted contacts -----------
# _check_rows, _merged_size and _add are inlined into their one caller: a
# compiled function with loops pays an atomic reference-count increment and
# decrement per array argument (numba does not prune them there), which is
# most of what a one-contact call costs; one function level fewer of these
# saves ~0.1 µs a call.

@njit(cache=True, inline="always")
def _touching(depth, impulse, j):
    return depth[j] >= 0.0 or impulse[j] > 0.0


@njit(cache=True, inline="always")
def _max(x, y):
    """max of the summed x and a later substep's y as events.py's np.maximum.at
    takes it: NaN wins, and a tie (0.0 and -0.0) gives y."""
    return x if (x > y or x != x) else y


@njit(cache=True, inline="always")
def _check_rows(key, a, b, point, normal, depth, impulse, friction, speed):
    """The kernels index without bounds checks: refuse columns of unequal lengths."""
    k = len(key)
    if (len(a) != k or len(b) != k or len(depth) != k or len(impulse) != k
            or len(speed) != k):
        raise ValueError("EventLog.add: columns of different lengths")
    if point.shape != (k, 3) or normal.shape != (k, 3) or friction.shape != (k, 3):
        raise ValueError("EventLog.add: point, normal and friction must be (k, 3)")


@njit(cache=True, inline="always")
def _merged_size(key, depth, impulse, acc_i, m):
    """(touching rows, contacts after the merge) of a substep's rows and the m
    gathered ones; raises when the keys are not ascending and unique."""
    i = 0
    touching = 0
    shared = 0
    for j in range(len(key)):
        if j > 0 and key[j] <= key[j - 1]:
            raise ValueError("EventLog.add: keys must be ascending and unique")
        if not _touching(depth, impulse, j):
            continue
        touching += 1
        while i < m and acc_i[i, KEY] < key[j]:
            i += 1
        if i < m and acc_i[i, KEY] == key[j]:
            shared += 1
    return touching, m + touching - shared


@njit(cache=True, inline="always")
def _move(rows_i, rows_f, i, w):
    """Row i to row w of the same arrays."""
    if w == i:
        return
    for c in range(ICOL):
        rows_i[w, c] = rows_i[i, c]
    for c in range(NCOL):
        rows_f[w, c] = rows_f[i, c]


@njit(cache=True, inline="always")
def _put_last(acc_i, acc_f, w, key, a, b, point, normal, depth, j):
    """The columns a contact takes from its last substep (row j)."""
    acc_i[w, KEY] = key[j]
    acc_i[w, BODY_A] = a[j]
    acc_i[w, BODY_B] = b[j]
    for c in range(3):
        acc_f[w, POINT + c] = point[j, c]
        acc_f[w, NORMAL + c] = normal[j, c]
    acc_f[w, DEPTH] = depth[j]


@njit(cache=True, inline="always")
def _start_sums(acc_f, w, impulse, friction, speed, j):
    """The summed columns of a contact first seen in this substep (row j)."""
    acc_f[w, IMPULSE] = impulse[j]
    for c in range(3):
        acc_f[w, FRICTION + c] = friction[j, c]
    acc_f[w, SPEED] = speed[j]


@njit(cache=True, inline="always")
def _add_sums(acc_f, w, i, impulse, friction, speed, j):
    """Gathered row i's sums plus substep row j, into row w (row i is read
    before row w is written: they may be the same row)."""
    acc_f[w, IMPULSE] = acc_f[i, IMPULSE] + impulse[j]
    for c in range(3):
        acc_f[w, FRICTION + c] = acc_f[i, FRICTION + c] + friction[j, c]
    acc_f[w, SPEED] = _max(acc_f[i, SPEED], speed[j])


@njit(cache=True)
def _sums_from_zero(acc_f, size):
    """events.py sums two or more substeps with np.bincount, which starts from
    0.0: a -0.0 impulse comes out as +0.0 then (kept bit-identical here)."""
    for r in range(size):
        acc_f[r, IMPULSE] += 0.0


@njit(cache=True, inline="always")
def _add(key, a, b, point, normal, depth, impulse, friction, speed, acc_i, acc_f, m):
    """Merge a substep's touching rows into the m gathered contacts (rows of
    acc_i, acc_f, which hold at least m + len(key) rows). Returns the new count.

    The merge runs from the back, in place: the write position never passes
    the next gathered row still to read, so no second buffer is needed."""
    _check_rows(key, a, b, point, normal, depth, impulse, friction, speed)
    touching, size = _merged_size(key, depth, impulse, acc_i, m)
    w = size
    i = m - 1
    for j in range(len(key) - 1, -1, -1):
        if not _touching(depth, impulse, j):
            continue
        while i >= 0 and acc_i[i, KEY] > key[j]:
            w -= 1
            _move(acc_i, acc_f, i, w)
            i -= 1
        w -= 1
        # two explicit paths: one call with a chosen row index runs 3× slower
        if i >= 0 and acc_i[i, KEY] == key[j]:
            _add_sums(acc_f, w, i, impulse, friction, speed, j)
            i -= 1
        else:
            _start_sums(acc_f, w, impulse, friction, speed, j)
        _put_last(acc_i, acc_f, w, key, a, b, point, normal, depth, j)
    if m > 0 and touching > 0:
        _sums_from_zero(acc_f, size)
    return size


# ---- kernels: the step's events and the contacts to remember ---------------

@njit(cache=True, inline="always")
def _length(v, i, c):
    """|v[i, c:c+3]|, the squares summed in the order numpy's einsum sums
    three products (two SIMD lanes: x² + z², then + y²), so that lengths are
    bit-identical to events.py's."""
    x, y, z = v[i, c], v[i, c + 1], v[i, c + 2]
    return math.sqrt((x * x + z * z) + y * y)


@njit(cache=True, inline="always")
def _put_event(rows_i, rows_f, j, out_i, out_f, r, event):
    """Output row r: what contact row j's last substep gives (point, normal,
    depth, bodies) and the event."""
    for c in range(3):
        out_f[r, O_POINT + c] = rows_f[j, POINT + c]
        out_f[r, O_NORMAL + c] = rows_f[j, NORMAL + c]
    out_f[r, O_DEPTH] = rows_f[j, DEPTH]
    out_i[r, O_A] = rows_i[j, BODY_A]
    out_i[r, O_B] = rows_i[j, BODY_B]
    out_i[r, O_EVENT] = event


@njit(cache=True)
def _touch_event(cur_i, cur_f, i, out_i, out_f, event):
    """Output row i: this step's touching contact i (its sums included)."""
    _put_event(cur_i, cur_f, i, out_i, out_f, i, event)
    out_f[i, O_IMPULSE] = cur_f[i, IMPULSE]
    out_f[i, O_FRICTION] = _length(cur_f, i, FRICTION)
    out_f[i, O_SPEED] = cur_f[i, SPEED]


@njit(cache=True)
def _end_event(rows_i, rows_f, j, out_i, out_f, r):
    """Output row r: the end of contact row j, with zero impulses and speed."""
    _put_event(rows_i, rows_f, j, out_i, out_f, r, END)
    out_f[r, O_IMPULSE] = 0.0
    out_f[r, O_FRICTION] = 0.0
    out_f[r, O_SPEED] = 0.0


@njit(cache=True, inline="always")
def _moves(moving, rows_i, j):
    """Some body of contact row j is awake and dynamic (else it froze)."""
    return moving[rows_i[j, BODY_A]] or moving[rows_i[j, BODY_B]]


@njit(cache=True)
def _step_events(cur_i, cur_f, m, prev_i, prev_f, p, moving, out_i, out_f):
    """The step's events into output rows: 0..m this step's touching contacts
    in key order (persist if last step had the key, else begin), then the
    ended ones of last step in key order; one merge over both sorted sets,
    no per-contact flags kept. Returns (ends, frozen) counts."""
    i = 0
    ends = 0
    frozen = 0
    for j in range(p):
        k = prev_i[j, KEY]
        while i < m and cur_i[i, KEY] < k:
            _touch_event(cur_i, cur_f, i, out_i, out_f, BEGIN)
            i += 1
        if i < m and cur_i[i, KEY] == k:
            _touch_event(cur_i, cur_f, i, out_i, out_f, PERSIST)
            i += 1
        elif _moves(moving, prev_i, j):
            _end_event(prev_i, prev_f, j, out_i, out_f, m + ends)
            ends += 1
        else:
            frozen += 1
    for r in range(i, m):
        _touch_event(cur_i, cur_f, r, out_i, out_f, BEGIN)
    return ends, frozen


@njit(cache=True, inline="always")
def _copy_row(src_i, src_f, j, dst_i, dst_f, w):
    for c in range(ICOL):
        dst_i[w, c] = src_i[j, c]
    for c in range(NCOL):
        dst_f[w, c] = src_f[j, c]


@njit(cache=True)
def _keep_frozen(cur_i, cur_f, m, prev_i, prev_f, p, moving, frozen):
    """Merge last step's frozen contacts (not touching now, no body moving)
    into this step's m, in place from the back as _add does; cur_i, cur_f
    hold at least m + frozen rows. Which rows froze is decided again as
    _step_events did: the current rows at and below i are not written yet
    (w - i - 1 frozen rows are still to place), so the merge still sees them."""
    w = m + frozen
    i = m - 1
    for j in range(p - 1, -1, -1):
        k = prev_i[j, KEY]
        while i >= 0 and cur_i[i, KEY] > k:
            w -= 1
            _move(cur_i, cur_f, i, w)
            i -= 1
        if (i >= 0 and cur_i[i, KEY] == k) or _moves(moving, prev_i, j):
            continue            # touches again (it is row i) or ended
        w -= 1
        _copy_row(prev_i, prev_f, j, cur_i, cur_f, w)


@njit(cache=True)
def _append_gone(gone_i, gone_f, g, out_i, out_f, r):
    """The ends of removed bodies' contacts into output rows r.. r + g."""
    for q in range(g):
        _end_event(gone_i, gone_f, q, out_i, out_f, r + q)


# ---- kernels on the state's containers ---------------------------------------
# A typed list access costs ~30 ns (calls into numba's C helpers), more than
# a small contact's merge. So each list holds one array, split into four
# regions of equal capacity (CUR, PREV, OUT, GONE: a call reads the list
# once and slices it), and CUR and PREV change roles by flipping
# counts[FLIP], not by writing the list.

@njit(cache=True)
def _make_state(capacity):
    """(ints, flts, counts) with `capacity` rows per region. Built in compiled
    code so that no typed-list method is compiled in Python (numba does not
    cache those)."""
    ints = List()
    flts = List()
    ints.append(np.empty((REGIONS * capacity, ICOL), np.int64))
    flts.append(np.empty((REGIONS * capacity, NCOL)))
    counts = np.zeros(N_COUNTS, np.int64)
    counts[CAP] = capacity
    return ints, flts, counts


@njit(cache=True)
def _grow(ints, flts, counts, need):
    """Replace the arrays by ones of max(need, 2 × capacity) rows per region
    (doubling keeps growth amortized), each region's rows copied. The
    region size is taken from the arrays themselves (counts[CAP] only
    spares the list access in the common no-growth check)."""
    rows_i, rows_f = ints[0], flts[0]
    cap = len(rows_i) // REGIONS
    size = max(need, 2 * cap)
    new_i = np.empty((REGIONS * size, ICOL), np.int64)
    new_f = np.empty((REGIONS * size, NCOL))
    for r in range(REGIONS):
        new_i[r * size:r * size + cap] = rows_i[r * cap:(r + 1) * cap]
        new_f[r * size:r * size + cap] = rows_f[r * cap:(r + 1) * cap]
    ints[0] = new_i
    flts[0] = new_f
    counts[CAP] = size


@njit(cache=True, inline="always")
def _room(ints, flts, counts, need):
    """The state's arrays, grown first if a region holds fewer than `need`
    rows (the capacity is kept in counts: no list access to check it);
    borrowed (physics_core/borrowed.py): the lists keep them, and nothing
    replaces them before the caller is done, so the views sliced from them
    count no references."""
    if need > counts[CAP]:
        _grow(ints, flts, counts, need)
    return borrow((ints[0], flts[0]))


@njit(cache=True, inline="always")
def _region(rows_i, rows_f, r):
    """Views of region r of the state's arrays."""
    cap = len(rows_i) // REGIONS
    return rows_i[r * cap:(r + 1) * cap], rows_f[r * cap:(r + 1) * cap]


@njit(cache=True, inline="always")
def _cur(counts):
    """The region holding CUR now (CUR and PREV swap at every step that keeps rows)."""
    return counts[FLIP]


@njit(cache=True, inline="always")
def _prev(counts):
    return 1 - counts[FLIP]


@njit(cache=True, inline="always")
def _log_add(ints, flts, counts, key, a, b, point, normal, depth, impulse_n, friction, speed):
    """events_add on the unpacked state."""
    k = len(key)
    if k == 0:
        return
    m = counts[M]
    rows_i, rows_f = _room(ints, flts, counts, m + k)
    cur_i, cur_f = _region(rows_i, rows_f, _cur(counts))
    counts[M] = _add(key, a, b, point, normal, depth, impulse_n, friction, speed, cur_i, cur_f, m)


@njit(cache=True, inline="always")
def _log_finish(ints, flts, counts, moving):
    """events_finish on the unpacked state."""
    m, p, g = counts[M], counts[P], counts[G]
    counts[M] = 0
    counts[K] = 0
    if m + p + g == 0:
        return
    rows_i, rows_f = _room(ints, flts, counts, m + p + g)      # CUR needs m + p, OUT m + p + g
    cur_i, cur_f = _region(rows_i, rows_f, _cur(counts))
    prev_i, prev_f = _region(rows_i, rows_f, _prev(counts))
    out_i, out_f = _region(rows_i, rows_f, OUT)
    ends, frozen = _step_events(cur_i, cur_f, m, prev_i, prev_f, p, moving, out_i, out_f)
    if g:
        gone_i, gone_f = _region(rows_i, rows_f, GONE)
        _append_gone(gone_i, gone_f, g, out_i, out_f, m + ends)
    counts[K] = m + ends + g
    counts[G] = 0
    if m == 0 and frozen == p:
        return                  # nothing touches, all (if any) froze: PREV stays as it is
    if frozen:
        _keep_frozen(cur_i, cur_f, m, prev_i, prev_f, p, moving, frozen)
    counts[FLIP] = 1 - counts[FLIP]     # the rows just gathered are the ones to remember
    counts[P] = m + frozen


@njit(cache=True)
def _renumber(ints, flts, counts, key, kept, new_index):
    """The remembered rows after a change of the body set: key[j] the new key
    of row j, kept[j] False when a body of it was removed; those rows move to
    GONE (bodies renumbered, -1 for the removed one), the others are
    compacted in place (their order, hence key order, is kept)."""
    p, g = counts[P], counts[G]
    rows_i, rows_f = _room(ints, flts, counts, g + p)
    prev_i, prev_f = _region(rows_i, rows_f, _prev(counts))
    gone_i, gone_f = _region(rows_i, rows_f, GONE)
    q = 0
    for j in range(p):
        a, b = new_index[prev_i[j, BODY_A]], new_index[prev_i[j, BODY_B]]
        if kept[j]:
            _move(prev_i, prev_f, j, q)
            prev_i[q, KEY] = key[j]
            prev_i[q, BODY_A] = a
            prev_i[q, BODY_B] = b
            q += 1
        else:
            _copy_row(prev_i, prev_f, j, gone_i, gone_f, g)
            gone_i[g, BODY_A] = a
            gone_i[g, BODY_B] = b
            g += 1
    counts[P] = q
    counts[G] = g


@njit(cache=True)
def _output(ints, flts, count):
    """Fresh copies of the output region's first `count` rows: vec (2, K, 3)
    point, normal; val (4, K) impulse, friction impulse, normal speed,
    depth; body (2, K) a, b; event (K,) uint8. Four arrays, not nine: each
    returned array costs ~0.25 µs to hand to Python, a view of one far less."""
    out_i, out_f = _region(ints[0], flts[0], OUT)
    vec = np.empty((2, count, 3))
    val = np.empty((4, count))
    body = np.empty((2, count), np.int64)
    event = np.empty(count, np.uint8)
    for r in range(count):
        for c in range(3):
            vec[0, r, c] = out_f[r, O_POINT + c]
            vec[1, r, c] = out_f[r, O_NORMAL + c]
        val[0, r] = out_f[r, O_IMPULSE]
        val[1, r] = out_f[r, O_FRICTION]
        val[2, r] = out_f[r, O_SPEED]
        val[3, r] = out_f[r, O_DEPTH]
        body[0, r] = out_i[r, O_A]
        body[1, r] = out_i[r, O_B]
        event[r] = out_i[r, O_EVENT]
    return vec, val, body, event


@njit(cache=True)
def _finish_output(ints, flts, counts, moving):
    """_log_finish, then _output of its rows: one call from Python, not two
    (each call pays ~0.7 µs per typed list it is handed)."""
    _log_finish(ints, flts, counts, moving)
    return _output(ints, flts, counts[K])


@njit(cache=True)
def _remembered_rows(ints, flts, counts):
    """The remembered rows in use (views), read from Python without compiling
    the typed list's getitem there."""
    prev_i, prev_f = _region(ints[0], flts[0], _prev(counts))
    return prev_i[:counts[P]], prev_f[:counts[P]]


# ---- entry points for compiled callers (state as one tuple) ------------------

@njit(cache=True, inline="always")
def events_reset(state):
    """Start a step: what events_add gathered before is dropped."""
    state[2][M] = 0


@njit(cache=True, inline="always")
def events_add(state, key, a, b, point, normal, depth, impulse_n, friction, speed):
    """Record one substep's contact rows, after its solve: key (k,) int64
    ascending and unique (else ValueError); a, b (k,) bodies; point, normal
    (k, 3); depth (k,); impulse_n (k,) accumulated normal impulse λ_n;
    friction (k, 3) tangential impulse as a world vector; speed (k,) approach
    speed before the solve (> 0 closing). Only touching rows (depth >= 0 or
    λ_n > 0) are kept, copied: the caller may reuse its arrays. k = 0 is a
    no-op (the other columns are not checked then)."""
    ints, flts, counts = state
    _log_add(ints, flts, counts, key, a, b, point, normal, depth, impulse_n, friction, speed)


@njit(cache=True, inline="always")
def events_finish(state, moving):
    """End the step: its events (then the pending ends of removed bodies'
    contacts) into the state's output buffers, the count in counts[K]; the
    touching contacts (and the frozen ones) are remembered for the next
    step's begin/end. `moving` (n,) bool marks the awake dynamic bodies (n
    above every body index added; not checked)."""
    ints, flts, counts = state
    _log_finish(ints, flts, counts, moving)


# ---- Python side -------------------------------------------------------------

def new_event_state(capacity=16):
    """A fresh event log state (ints, flts, counts), see the module docstring;
    `capacity` rows per buffer to start with (they grow as needed)."""
    return _make_state(int(capacity))


def events_output(state) -> ContactEvents:
    """The last finished step's events, as fresh copies of the output buffers
    (they stay valid after later steps); the one shared empty ContactEvents
    when there are none."""
    ints, flts, counts = state
    k = int(counts[K])
    if not k:
        return _EMPTY
    return _as_events(*_output(ints, flts, k))


def _as_events(vec, val, body, event) -> ContactEvents:
    """The ContactEvents of _output's arrays (views of them, contiguous)."""
    if not len(event):
        return _EMPTY
    return ContactEvents(point=vec[0], normal=vec[1], impulse=val[0], friction_impulse=val[1],
                         normal_speed=val[2], depth=val[3], body_a=body[0], body_b=body[1],
                         event=event)


def events_bodies_changed(state, n_old, n_new, new_index):
    """The remembered contacts after a change of the body set (new_index[old
    body] = its new index, -1 if removed): keys and bodies renumbered; the
    contacts of a removed body end at the next events_finish, after that
    step's own events, with -1 for that body. Ends queued by an earlier
    change are not renumbered again. (remap_keys is called from here, not
    from a kernel: a cached kernel would not notice a change of warm_cache.py.)"""
    ints, flts, counts = state
    p = int(counts[P])
    if not p:
        return
    prev_i, _ = _remembered_rows(ints, flts, counts)
    new_index = np.asarray(new_index, dtype=np.int64)
    key, kept = remap_keys(prev_i[:, KEY].copy(), n_old, n_new, new_index, SLOTS)
    _renumber(ints, flts, counts, key, kept, new_index)


class EventLog:
    """The contact events of each step, from the contact rows of its
    substeps: a Python face of the state above (`self.state`, which compiled
    code may use between these calls). `state`: an existing one to wrap
    (e.g. one a compiled loop runs on), else a fresh one of `capacity` rows."""

    def __init__(self, capacity=16, state=None):
        self.state = new_event_state(capacity) if state is None else state

    def reset(self):
        """Start a step (what add gathered before is dropped)."""
        self.state[2][M] = 0

    def add(self, key, a, b, point, normal, depth, impulse_n, friction, speed):
        """One substep's contact rows (see events_add)."""
        if not len(key):
            return
        ints, flts, counts = self.state
        _log_add(ints, flts, counts, key, a, b, point, normal, depth, impulse_n, friction, speed)

    def finish(self, moving) -> ContactEvents:
        """The step's events, then the ends of contacts whose body was removed
        (see events_finish); a step without an event returns one shared empty
        ContactEvents."""
        ints, flts, counts = self.state
        if not (counts[M] or counts[P] or counts[G]):
            counts[K] = 0       # nothing gathered, remembered or pending: skip the call
            return _EMPTY
        return _as_events(*_finish_output(ints, flts, counts, moving))

    def bodies_changed(self, n_old, n_new, new_index):
        """See events_bodies_changed."""
        events_bodies_changed(self.state, n_old, n_new, new_index)

    def remembered(self) -> dict:
        """Copies of the remembered contacts (last step's touching ones and the
        frozen ones), sorted by key: key, a, b, point, normal, depth."""
        ints, flts, counts = self.state
        ri, rf = _remembered_rows(ints, flts, counts)
        return dict(key=ri[:, KEY].copy(), a=ri[:, BODY_A].copy(), b=ri[:, BODY_B].copy(),
                    point=rf[:, POINT:POINT + 3].copy(), normal=rf[:, NORMAL:NORMAL + 3].copy(),
                    depth=rf[:, DEPTH].copy())
