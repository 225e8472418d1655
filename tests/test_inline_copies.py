"""Numba's inliner copies a function's blocks with one memo after `import
physics_core` (physics_core/inline_copies.py), and the code it compiles is
the same as without.

Each compile runs in a fresh process (the kernel is not cached), so both
sides compile from source."""
import os

from fresh_process import ROOT, printed_value

# loaded on its own, not through `import physics_core`: neither side defines
# the engine's kernels, so both number their functions alike
_MODULE = os.path.join(ROOT, "physics_core", "inline_copies.py")

# Helpers inlined into helpers, with loops, branches and tuples: the shapes
# the step's kernels inline, small enough to compile in a second or two.
_KERNEL = '''
import numpy as np
from numba import njit

@njit(inline="always")
def clamp(x, lo, hi):
    if x < lo:
        return lo
    if x > hi:
        return hi
    return x

@njit(inline="always")
def pair(v, i, j):
    s = 0.0
    for k in range(3):
        s += clamp(v[i, k] - v[j, k], -1.0, 1.0)
    return s, abs(s)

@njit(inline="always")
def sweep(v, out):
    worst = 0.0
    for i in range(len(v) - 1):
        d, m = pair(v, i, i + 1)
        out[i] = d
        if m > worst:
            worst = m
    return worst

@njit
def kernel(v, out, passes):
    total = 0.0
    for _ in range(passes):
        w = sweep(v, out)
        total += w if w > 0.5 else clamp(w, 0.1, 0.4)
    return total
'''


def _compile(shared):
    setup = (
        "import importlib.util\n"
        f"spec = importlib.util.spec_from_file_location('inline_copies', {_MODULE!r})\n"
        "m = importlib.util.module_from_spec(spec); spec.loader.exec_module(m)\n"
        "assert m.share_inline_copies()\n") if shared else ""
    code = (setup + _KERNEL +
            "from numba.core import inline_closurecall as ic\n"
            "v = np.linspace(0.0, 3.0, 30).reshape(10, 3) ** 2\n"
            "out = np.zeros(9)\n"
            "total = kernel(v, out, 3)\n"
            "sig = kernel.signatures[0]\n"
            "print(repr({'shared': getattr(ic.InlineWorker.inline_ir, 'shares_copies', False),"
            " 'asm': kernel.inspect_asm(sig), 'total': total.hex(), 'out': [x.hex() for x in out]}))")
    return printed_value(code)


def test_importing_the_engine_makes_the_inliner_share_one_memo_per_copy():
    code = ("import physics_core\n"
            "from numba.core import inline_closurecall as ic\n"
            "from physics_core.inline_copies import share_inline_copies\n"
            "print([getattr(ic.InlineWorker.inline_ir, 'shares_copies', False),"
            " share_inline_copies()])")
    assert printed_value(code) == [True, True]


def test_inlined_helpers_compile_to_the_same_machine_code_with_shared_copies():
    """Three layers of inline="always" helpers: the same assembly, and the
    same numbers, whether numba's inliner copies blocks one by one or with
    one memo per copy."""
    before, after = _compile(False), _compile(True)
    assert before["shared"] is False and after["shared"] is True
    assert after["asm"] == before["asm"]
    assert after["asm"].count("\n") > 100
    assert (after["total"], after["out"]) == (before["total"], before["out"])
