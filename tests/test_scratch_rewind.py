"""The scratch arena's rewind (collision/scratch.py): views given back after
a cursor mark are reused by the next takes, in the same memory; when a take
fell past the buffer's end the cursor keeps the whole demand, so the next
substep's buffer is grown to hold it (shock_propagation._settle_body
rewinds after each body)."""
import numpy as np
from numba import njit

from physics_core.collision.scratch import (CURSOR, cursor, new_counts, new_scratch, open_arena,
                                            rewind, take, take_rows)


@njit
def _per_item_tables(store, items, size):
    """For each item: a mark, a (size, 3) table written with the item's
    number, the mark given back; then one more table. Returns (the cursor
    at the end, the new table's first number: what the last item left)."""
    first = take(store, 4)
    first[:] = -1.0
    for i in range(items):
        mark = cursor(store)
        table = take_rows(store, size, 3)
        table[:] = i
        rewind(store, mark)
    again = take_rows(store, size, 3)
    return cursor(store), again[0, 0]


def test_a_rewound_table_is_reused_by_the_next_take_in_the_same_memory():
    scratch, counts = new_scratch(), new_counts()
    counts[CURSOR] = 1000
    store = open_arena(scratch, counts)           # a buffer of 1,000 float64
    end, again = _per_item_tables(store, 50, 10)
    # 4 + 50 tables of 30 without rewinding would be 1,504 > 1,000: each reused the first's place
    assert end == 4 + 30
    assert again == 49.0                          # the last table's numbers, where it left them


def test_a_rewind_after_a_take_past_the_end_keeps_the_demand_that_grows_the_next_buffer():
    scratch, counts = new_scratch(), new_counts()
    counts[CURSOR] = 100
    store = open_arena(scratch, counts)           # 100 float64: a (40, 3) table does not fit
    end, _ = _per_item_tables(store, 3, 40)
    assert end > 100                              # not rewound: the demand is kept
    store = open_arena(scratch, counts)
    assert len(scratch[0]) >= end
    end, _ = _per_item_tables(store, 3, 40)
    assert end == 4 + 120                         # the grown buffer holds one table, reused
