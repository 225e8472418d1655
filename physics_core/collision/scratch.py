"""Scratch arrays of a substep, in one buffer kept across steps.

A substep makes about as many arrays as it has stages (rows, contacts,
bounce targets, start-of-substep copies...). Allocating and freeing them,
and counting references to them at every call they pass through, cost
more than the arithmetic of a small scene (about half of a one-sphere
step). Instead they are consecutive views of one float64 buffer, kept in a
numba typed list (so compiled code can replace it and the owner sees the
replacement) owned by the ContactSystem and passed to the step loop.

`open_arena(scratch, counts)` starts a substep: the store (buffer, counts)
with the cursor at 0, the buffer borrowed (physics_core/borrowed.py) so its
views count no references. `take(store, size)` returns the next `size`
elements; a request past the end gets a new array of its own instead, and
the cursor still counts it, so the next substep's buffer is grown to the
whole demand (at least twice the old size: capacity doubling, as scenes
gain bodies or rows). A view is valid until the next `open_arena`, or
until `rewind` gives back the views taken after a `cursor` mark; its
contents are whatever was there (np.empty's contract). Integer and boolean
views share the buffer (`take_ints`, `take_bools`).

`counts` is the contact system's int64 counts array: ROW_GUESS (the
narrow phase's first row buffer size), CURSOR, PAIR_GUESS (the broad
phase's), KEPT and KEPT_NEED (the broad phase's kept pairs, kept_pairs.py:
how many are kept, -1 for none, and the buffer size they last needed).

The store is (buffer, counts, kept): `kept` is the typed list's second
buffer, which outlives the substep: the broad phase's kept pairs; like the
buffer, open_arena grows it to the size last asked for. (With the typed
list itself in the store, to fetch the buffer only where a scene has pairs
to keep, every function taking the store counted the list's references:
the 1,000-sphere pile's solve stage took 6 % longer.)
"""
import numpy as np
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic
from numba.np.arrayobj import populate_array
from numba.typed import List

from ..borrowed import borrow

ROW_GUESS, CURSOR, PAIR_GUESS, KEPT, KEPT_NEED, N_COUNTS = range(6)


@njit(cache=True)
def _new_store():
    """Built in compiled code: typed-list methods compiled in Python are not cached."""
    store = List()
    store.append(np.empty(0))
    store.append(np.empty(0))
    return store


def new_scratch():
    """The typed list holding the scratch buffer and the kept pairs' (empty:
    the first substep sizes them)."""
    return _new_store()


def new_counts(row_guess=16):
    counts = np.zeros(N_COUNTS, np.int64)
    counts[ROW_GUESS] = row_guess
    counts[KEPT] = -1
    return counts


@njit(cache=True)
def empty_store():
    """A store with no buffer: every take is a new array, nothing is kept
    (for callers outside the step)."""
    counts = np.zeros(N_COUNTS, np.int64)
    counts[KEPT] = -1
    return np.empty(0), counts, np.empty(0)


@njit(cache=True, inline="always")
def open_arena(scratch, counts):
    """The store of a new substep: the buffers grown to the last demands."""
    if counts[CURSOR] > len(scratch[0]):
        scratch[0] = np.empty(max(counts[CURSOR], 2 * len(scratch[0])))
    if counts[KEPT_NEED] > len(scratch[1]):
        scratch[1] = np.empty(max(counts[KEPT_NEED], 2 * len(scratch[1])))
    counts[CURSOR] = 0
    return borrow(scratch[0]), counts, borrow(scratch[1])


@intrinsic
def _carve(typingctx, buf, at, shape, like):
    """An unowned C-order array of `like`'s type and `shape` (a tuple) whose
    data starts at float64 element `at` of `buf`: a view without numba's
    reshape helper or a reference to count."""
    ndim = len(shape)
    ret = types.Array(like, ndim, "C")

    def codegen(context, builder, sig, args):
        intp = context.get_value_type(types.intp)
        src = context.make_array(sig.args[0])(context, builder, value=args[0])
        out = context.make_array(ret)(context, builder)
        size = context.get_abi_sizeof(context.get_data_type(like))
        dims = [context.cast(builder, builder.extract_value(args[2], i), sig.args[2][i], types.intp)
                for i in range(ndim)]
        strides = [intp(size)]
        for d in reversed(dims[1:]):
            strides.insert(0, builder.mul(strides[0], d))
        offset = builder.mul(context.cast(builder, args[1], sig.args[1], types.intp), intp(8))
        raw = builder.gep(builder.bitcast(src.data, cgutils.voidptr_t), [offset])
        populate_array(out, data=builder.bitcast(raw, out.data.type), shape=dims, strides=strides,
                       itemsize=intp(size), meminfo=None)
        return out._getvalue()
    return ret(buf, at, shape, like), codegen


@njit(cache=True, inline="always")
def _claim(store, units):
    """Where the next `units` float64 elements start in the buffer, -1 past its end."""
    buf, counts = store[0], store[1]
    at = counts[CURSOR]
    counts[CURSOR] = at + units
    return at if at + units <= len(buf) else -1


@njit(cache=True, inline="always")
def take(store, size):
    """(size,) float64: the next view of the buffer, or a new array past its end."""
    at = _claim(store, size)
    return _carve(store[0], at, (size,), 0.0) if at >= 0 else np.empty(size)


@njit(cache=True, inline="always")
def take_ints(store, size):
    at = _claim(store, size)
    return _carve(store[0], at, (size,), np.int64(0)) if at >= 0 else np.empty(size, np.int64)


@njit(cache=True, inline="always")
def take_bools(store, size):
    at = _claim(store, (size + 7) // 8)
    return _carve(store[0], at, (size,), False) if at >= 0 else np.empty(size, np.bool_)


@njit(cache=True, inline="always")
def take_rows(store, rows, cols):
    """(rows, cols) float64."""
    at = _claim(store, rows * cols)
    return _carve(store[0], at, (rows, cols), 0.0) if at >= 0 else np.empty((rows, cols))


@njit(cache=True, inline="always")
def take_int_rows(store, rows, cols):
    at = _claim(store, rows * cols)
    return (_carve(store[0], at, (rows, cols), np.int64(0)) if at >= 0
            else np.empty((rows, cols), np.int64))


@njit(cache=True, inline="always")
def cursor(store):
    """Where the next take starts: a mark for `rewind`."""
    return store[1][CURSOR]


@njit(cache=True, inline="always")
def rewind(store, mark):
    """Every view taken since the cursor was at `mark` given back (the caller
    no longer reads them): the next takes reuse their memory, still in the
    processor's cache, so a loop taking per-item tables works in one small
    region. Not when one of them fell past the buffer's end: the cursor
    then keeps the whole demand, which grows the next substep's buffer."""
    buf, counts = store[0], store[1]
    if counts[CURSOR] <= len(buf):
        counts[CURSOR] = mark


@njit(cache=True, inline="always")
def int_rows_at(buf, at, rows, cols):
    """An unowned (rows, cols) int64 view of float64 buffer `buf` from element
    `at` (the caller checks that it fits)."""
    return _carve(buf, at, (rows, cols), np.int64(0))
