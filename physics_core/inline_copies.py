"""Numba's inliner, made to copy a function's blocks the way they are shared.

The step's kernels call many small helpers marked `inline="always"`;
numba inlines each call by copying the helper's IR, one block at a time
with its own `copy.deepcopy`. Every block points at the function's one
variable scope, so each block's copy drags a fresh copy of the whole scope
(every variable of the function) along: an inlined call costs blocks ×
variables, and helpers that inline helpers grow both. Measured on the
engine's cold compile (2-core host at 2.0 GHz): the inlining pass of the
shock sweep's layer kernel took 31.5 s of its 58 s compile, and the whole
cold compile took about 12 minutes.

`share_inline_copies()` gives the blocks of one copy one shared memo, so
they share one copy of the scope as the original blocks share the scope:
the same IR, built in a fraction of the time. The machine code is the
same, instruction for instruction (tests/test_inline_copies.py compares it
with and without). It changes nothing on a numba whose inliner is built
differently (it returns False there, and compiling takes as long as
before). Compiled code loaded from the cache never runs the inliner; this
only shortens a compile.
"""
import copy

from numba.core import inline_closurecall, ir

_memos = []       # one {id(scope): memo} per inline_ir call in progress


class _SharedCopies:
    """Stands in for the `copy` module inside numba's inliner: a block copied
    while an inline_ir call runs shares its memo with the blocks of the same
    scope copied in that call; everything else is copied as before."""
    copy = staticmethod(copy.copy)

    @staticmethod
    def deepcopy(x, memo=None):
        if memo is None and _memos and isinstance(x, ir.Block):
            memo = _memos[-1].setdefault(id(x.scope), {})
        return copy.deepcopy(x, memo)


def _with_shared_copies(inline_ir):
    def inline_ir_shared(self, *args, **kwargs):
        _memos.append({})
        try:
            return inline_ir(self, *args, **kwargs)
        finally:
            _memos.pop()
    inline_ir_shared.shares_copies = True
    inline_ir_shared.numbas_own = inline_ir
    return inline_ir_shared


def share_inline_copies():
    """True when numba's inliner copies a function's blocks with one memo."""
    worker = getattr(inline_closurecall, "InlineWorker", None)
    inline_ir = getattr(worker, "inline_ir", None)
    if getattr(inline_ir, "shares_copies", False):
        return True
    if inline_ir is None or getattr(inline_closurecall, "copy", None) is not copy:
        return False              # a numba whose inliner is built differently
    inline_closurecall.copy = _SharedCopies
    worker.inline_ir = _with_shared_copies(inline_ir)
    return True


def restore_inline_copies():
    """Numba's own inliner back, copying block by block (`physics-bench
    compile` times both). Returns whether it had been replaced."""
    worker = inline_closurecall.InlineWorker
    own = getattr(worker.inline_ir, "numbas_own", None)
    if own is None:
        return False
    worker.inline_ir = own
    inline_closurecall.copy = copy
    return True
