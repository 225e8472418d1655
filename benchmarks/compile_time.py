"""The kernels' cold compile, with numba's inliner as `import physics_core`
sets it (one memo per copy, physics_core/inline_copies.py) and as numba
ships it (block by block).

    physics-bench compile [--quick] [--out DIR]

Each side is a fresh process that steps `physics_core.warm_up`'s scenes with
NUMBA_CACHE_DIR set to an empty temporary folder, so every kernel compiles,
while numba's compile events are timed: the seconds in all, and each
kernel's own compile (the time inside its compile event, less that of the
kernels compiled within it). `--quick` times the first side alone (numba's
own inliner takes about twice as long: some 12 minutes on a 2 GHz pair).
Writes compile.md and compile.json.
"""
import json
import os
import subprocess
import sys
import tempfile
from time import perf_counter

from numba.core import event

from .progress import Progress
from .repo import REPO
from .results_io import machine, write_json, write_text

SIDES = ("shared", "numba")     # the inliner as physics_core sets it; numba's own
TOP = 8                         # kernels listed, by their own compile time

_CHILD = """
import json, sys
from physics_core import inline_copies
from physics_core.warm_up import warm_up
from benchmarks.compile_time import own_times
if sys.argv[1] == "numba":
    inline_copies.restore_inline_copies()
with own_times() as own:
    seconds = warm_up()
print(json.dumps({"seconds": seconds, "own": own}))
"""


class own_times(event.Listener):
    """A context whose dict fills with {kernel: seconds of its own compile}:
    numba's compile events nest (a kernel's compile holds those of the
    kernels it calls), and each one's time is counted to the innermost
    compile running."""

    def __init__(self):
        self.own, self._stack = {}, []

    def _charge(self, now):
        if self._stack:
            name, since = self._stack[-1]
            self.own[name] = self.own.get(name, 0.0) + now - since
            self._stack[-1][1] = now

    def on_start(self, ev):
        now = perf_counter()
        self._charge(now)
        f = ev.data["dispatcher"].py_func
        self._stack.append([f"{f.__module__}.{f.__qualname__}", now])

    def on_end(self, ev):
        now = perf_counter()
        self._charge(now)
        self._stack.pop()
        if self._stack:
            self._stack[-1][1] = now

    def __enter__(self):
        event.register("numba:compile", self)
        return self.own

    def __exit__(self, *exc):
        event.unregister("numba:compile", self)
        return False


def cold_compile(side):
    """{"seconds", "own"} of one side, compiled into an empty cache in a fresh process."""
    with tempfile.TemporaryDirectory(prefix="physics-bench-compile-") as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        done = subprocess.run([sys.executable, "-c", _CHILD, side], cwd=REPO, env=env,
                              capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"cold compile ({side} inliner) failed: {done.stderr[-2000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def markdown(runs):
    """The seconds in all, then the kernels with the longest own compile."""
    sides = [s for s in SIDES if s in runs]
    first = runs[sides[-1]]["own"]
    names = sorted(first, key=first.get, reverse=True)[:TOP]
    head = "| | " + " | ".join(f"{s} inliner, s" for s in sides) + " |"
    lines = ["# Cold compile of every kernel\n", head,
             "|---|" + "---:|" * len(sides),
             "| **all kernels** | " + " | ".join(f"**{runs[s]['seconds']:.0f}**" for s in sides) + " |"]
    for name in names:
        cells = " | ".join(f"{runs[s]['own'].get(name, 0.0):.1f}" for s in sides)
        lines.append(f"| `{name.removeprefix('physics_core.')}` (own) | {cells} |")
    return "\n".join(lines) + "\n"


def run(quick=False, out=None):
    sides = SIDES[:1] if quick else SIDES
    progress = Progress("compile", len(sides))
    runs = {}
    for side in sides:
        runs[side] = cold_compile(side)
        progress.note(f"{side} inliner: {runs[side]['seconds']:.0f} s")
    data = {"quick": quick, "machine": machine(), "runs": runs}
    if out:
        write_json(out, "compile.json", data)
        write_text(out, "compile.md", markdown(runs))
    return data
