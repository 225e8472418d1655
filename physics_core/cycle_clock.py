"""A clock compiled code can read: the processor's cycle counter.

Numba's nopython mode has no time function, yet every stage of the
compiled step is timed into `world.profile`. `cycles()` reads the counter
(LLVM's readcyclecounter: the TSC on x86, a few nanoseconds) and
`seconds_per_cycle()` converts, measured against time.perf_counter the first
time a profile is read (a 20 ms measurement no process start should pay).
Where the processor has no such counter it reads 0 and the profile stays
empty; the physics does not depend on it.
"""
from time import perf_counter

from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic


@intrinsic
def _readcyclecounter(typingctx):
    def codegen(context, builder, signature, args):
        fnty = ir.FunctionType(ir.IntType(64), [])
        fn = builder.module.declare_intrinsic("llvm.readcyclecounter", fnty=fnty)
        return builder.call(fn, [])
    return types.int64(), codegen


@njit(cache=True)
def cycles():
    return _readcyclecounter()


@njit(cache=True, inline="always")
def lap(prof, slot, t0):
    """The cycles since t0 added to prof[slot]; returns the counter now, the
    next stage's start. Consecutive stages share one reading at each
    boundary: a reading costs about 10 ns here, and a one-ball step has
    some ten stage boundaries (about 3 % of its step read twice)."""
    now = _readcyclecounter()
    prof[slot] += now - t0
    return now


def _calibrate(seconds=0.02):
    c0, t0 = cycles(), perf_counter()
    while perf_counter() - t0 < seconds:
        pass
    c1, t1 = cycles(), perf_counter()
    return (t1 - t0) / (c1 - c0) if c1 > c0 else 0.0


_SECONDS_PER_CYCLE = []


def seconds_per_cycle() -> float:
    if not _SECONDS_PER_CYCLE:
        _SECONDS_PER_CYCLE.append(_calibrate())
    return _SECONDS_PER_CYCLE[0]
