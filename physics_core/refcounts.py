"""Numba's reference counting, inlinable into the compiled step.

Numba counts references to arrays through two runtime functions,
NRT_incref and NRT_decref, compiled once per process and marked noinline
so that its pruning pass can find and cancel matched pairs. That pass runs
in the first, cheap optimisation round of every kernel; the full round that
follows could inline what was left, but the mark forbids it. So every
array crossing a call that is not inlined is counted through a call, even
when it is one of the step's borrowed arrays (borrowed.py) whose null owner
makes the call return at once: measured with perf on a one-body step, the
two functions took 22 % of its time.

`inline_reference_counts()` drops the noinline mark before numba compiles
its runtime. Pruning is unchanged (it still runs before inlining can
happen), and so is the counting itself; inlined, a borrowed array's count
is a test of a constant null pointer that the compiler removes. It must run
before numba's runtime is first compiled (physics_core/__init__.py calls it
first thing); afterwards, or on a numba whose runtime is built differently,
it changes nothing and returns False, and kernels compiled then count
through calls as before (the same results, slower).
"""
from numba.core.runtime import nrt, nrtdynmod

_COUNTERS = ("NRT_incref", "NRT_decref")


def _inlinable(define):
    def defining(module, atomic):
        out = define(module, atomic)
        for name in _COUNTERS:
            fn = module.globals.get(name)
            if fn is not None:
                fn.attributes.discard("noinline")
        return out
    defining.inlinable = True
    return defining


def inline_reference_counts():
    """True when numba's runtime will be compiled with inlinable counters."""
    define = getattr(nrtdynmod, "_define_nrt_incref", None)
    if getattr(define, "inlinable", False):
        return True
    if define is None or getattr(nrt.rtsys, "_init", True):
        return False              # compiled already, or a numba without these internals
    nrtdynmod._define_nrt_incref = _inlinable(nrtdynmod._define_nrt_incref)
    nrtdynmod._define_nrt_decref = _inlinable(nrtdynmod._define_nrt_decref)
    return True
