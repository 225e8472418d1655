"""Borrowed views (physics_core/borrowed.py): same arrays, no reference
counting, nothing leaked or freed early by the step loop that uses them."""
import sys

import numpy as np
from numba import njit, typed
from numba.core.runtime import _nrt_python as _nrt, rtsys

from physics_core import load_scene
from physics_core.borrowed import borrow, keep_alive


@njit
def _write_through(t):
    a, (b, n), lst = borrow(t)
    a[0] = 1.5
    b[1, 2] = -2.0
    lst.append(n)
    return a.shape[0] + b.shape[0] * b.shape[1]


@njit
def _made_inside(n):
    owned = np.arange(n) * 1.0
    view = borrow(owned)
    total = 0.0
    for i in range(n):
        total += view[i]
    keep_alive(owned)
    return total


def test_a_borrowed_tuple_reads_and_writes_the_same_memory():
    a, b = np.zeros(4), np.zeros((2, 3))
    lst = typed.List([0])
    assert _write_through((a, (b, 7), lst)) == 4 + 6
    assert a[0] == 1.5 and b[1, 2] == -2.0 and list(lst) == [0, 7]


def test_an_array_made_inside_is_kept_while_its_borrowed_view_is_read():
    assert _made_inside(1000) == sum(range(1000))


def _live_allocations():
    s = rtsys.get_allocation_stats()
    return s.alloc - s.free, s.mi_alloc - s.mi_free


def test_stepping_with_borrowed_inputs_leaks_nothing_and_keeps_the_owners():
    world = load_scene({"dt": 1 / 240, "gravity": [0, 0, -9.81],
                        "effects": {"contacts": {"sleep": False}},
                        "bodies": [{"name": "ground", "shape": {"type": "plane"}, "static": True},
                                   {"name": "ball", "shape": {"type": "sphere", "radius": 0.1},
                                    "mass": 1.0, "position": [0, 0, 0.3]},
                                   {"name": "box", "shape": {"type": "box", "half_extents": [0.1] * 3},
                                    "mass": 1.0, "position": [0.05, 0, 0.6]}]})
    world.step(50)                                  # contacts made, caches warm
    refs = sys.getrefcount(world.state.pos), sys.getrefcount(world.state.vel)
    _nrt.memsys_enable_stats()
    try:
        before = _live_allocations()
        world.step(500)
        after = _live_allocations()
    finally:
        _nrt.memsys_disable_stats()
    assert after == before                          # every array a step made was freed
    assert (sys.getrefcount(world.state.pos), sys.getrefcount(world.state.vel)) == refs
    assert np.isfinite(world.state.pos).all() and world.state.pos[1, 2] < 0.3
