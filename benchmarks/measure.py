"""Steps/s and peak memory of one engine on one scene, each in a fresh process.

Steps/s is the mean over the timed run: a contact scene's work changes as
it settles, so no single chunk stands for it (the fastest chunk is kept too,
as `fastest_steps_per_second`). A run shorter than MIN_TIMED is made again
from a freshly built scene and its fastest window kept (measure_here).

A fresh process per measurement keeps one engine's caches and allocations
out of another's numbers, and lets the peak resident memory (ru_maxrss) be
read for that run alone (VmHWM). Run as
`python -m benchmarks.measure SCENE_MODULE SCENE_FUNCTION N ENGINE STEPS`;
prints one JSON line.
"""
import importlib
import json
import os
import subprocess
import sys
from time import perf_counter

import numpy as np

from .repo import on_path

WARMUP = 5          # steps before timing: first contacts, caches, lazy set-up; taken as
                    # WARMUP calls of one step, the calls PyBullet's and MuJoCo's step(n)
                    # make (one per step): the interpreter's first passes through an
                    # engine's step call cost tens of µs, and one call of WARMUP steps
                    # left this engine's first timed calls to pay them
HEARTBEAT = 15.0    # s between progress lines of a long measurement
MIN_TIMED = 0.2     # s: a run's window is timed again until the windows reach this in all
MAX_WINDOWS = 200   # (measure_here), at most this many
BUDGET = 120.0      # s of stepping at most (pile_compare's too): an engine still short of its steps then is
                    # reported over the steps it did (an early part of the run, which
                    # costs less than the rest once the contacts have formed)


def _rss_mb():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2 ** 20


def _peak_mb():
    """Peak resident memory of this process (VmHWM). Not ru_maxrss: Linux carries that
    across fork and exec, so a child would report its parent's peak."""
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024.0
    return float("nan")


def measure_here(scene_module, scene_function, n, engine, steps, budget=BUDGET):
    """One engine's run of `steps` steps on the scene, in this process: a
    window of the same run from a freshly built scene is timed again while
    the windows so far took under MIN_TIMED seconds in all (at most
    MAX_WINDOWS), and the fastest window is the one reported (its steps/s,
    stages and what it left), with `windows` the number timed. A run of a
    few bodies takes about a millisecond, and on a shared machine a single
    such window came out anywhere within ±30 % of another: a 1-sphere run
    gave this engine 2.3e5 to 3.7e5 steps/s and PyBullet 2.1e5 to 3.7e5 in
    five runs each. Every engine gets the same rule, so the ratio is of
    fastest to fastest."""
    from . import engines
    bodies = getattr(importlib.import_module(scene_module), scene_function)(n)
    # the engine's own module is imported before the baseline, so it does not count as scene memory
    importlib.import_module(engines.module_of(engine))
    base = _rss_mb()
    (done, elapsed, best), windows = fastest_run(
        lambda: _window(engines, engine, bodies, steps, budget), steps)
    pos = best.pop("positions")
    peak = _peak_mb()
    return {"engine": engine, "bodies": len(bodies), "steps": done, "steps_asked": steps,
            "steps_per_second": done / elapsed, "body_steps_per_second": len(bodies) * done / elapsed,
            **best, "windows": windows, "peak_rss_mb": peak, "baseline_rss_mb": base,
            "scene_mb": max(0.0, peak - base), "min_z": float(pos[:, 2].min()) if len(pos) else 0.0,
            **left_by(bodies, pos)}


def fastest_run(run_once, steps):
    """(the fastest of one run or more, how many were made): `run_once()`
    returns (steps done, seconds, ...), and runs are made again while each
    finished its `steps` and all took under MIN_TIMED seconds (at most
    MAX_WINDOWS); fastest by steps done over seconds."""
    best, spent, runs = None, 0.0, 0
    while True:
        r = run_once()
        runs += 1
        spent += r[1]
        if best is None or r[0] / r[1] > best[0] / best[1]:
            best = r
        if r[0] < steps or spent >= MIN_TIMED or runs >= MAX_WINDOWS:
            return best, runs


def _window(engines, engine, bodies, steps, budget):
    """One timed run from a freshly built scene (after WARMUP single steps):
    (steps done, seconds, {its steps, seconds, fastest chunk, build time,
    stages and end positions})."""
    t0 = perf_counter()
    step, positions, stages = engines.build(engine, bodies)
    build = perf_counter() - t0
    for _ in range(WARMUP):
        step(1)
    before = stages() or {}
    t0 = last = perf_counter()
    chunk = max(1, steps // 20)
    best = float("inf")       # fastest chunk, per step
    done = 0
    while done < steps and perf_counter() - t0 < budget:
        k = min(chunk, steps - done)
        c0 = perf_counter()
        step(k)
        done += k
        best = min(best, (perf_counter() - c0) / k)
        if perf_counter() - last > HEARTBEAT:
            last = perf_counter()
            sys.stderr.write(f"    {engine}, {len(bodies)} bodies: {done}/{steps} steps "
                             f"({last - t0:.0f} s)\n")
            sys.stderr.flush()
    elapsed = perf_counter() - t0
    after = stages()
    # where this engine's time goes: seconds per step in each named stage
    profile = None if after is None else {
        k: (v - before.get(k, 0.0)) / done for k, v in after.items() if k != "step"}
    return done, elapsed, {"steps": done, "seconds": elapsed, "fastest_steps_per_second": 1.0 / best,
                           "build_seconds": build, "stage_seconds_per_step": profile,
                           "positions": positions()}


def left_by(bodies, pos):
    """What the run left, for a reader to weigh speed against: `sink_mm`, how far
    the deepest centre is below its resting height on the ground (a box's half
    height, a sphere's radius; 0 if none is), and `moved_mm`, the largest
    sideways move of a centre from where it started (a pyramid that spreads
    is collapsing)."""
    if not len(pos):
        return {"sink_mm": 0.0, "moved_mm": 0.0}
    rest = np.array([np.atleast_1d(size)[-1] for _, size, _ in bodies], dtype=float)
    start = np.array([p for _, _, p in bodies], dtype=float)
    return {"sink_mm": 1000.0 * max(0.0, float(np.max(rest - pos[:, 2]))),
            "moved_mm": 1000.0 * float(np.max(np.hypot(*(pos[:, :2] - start[:, :2]).T)))}


def measure(scene_module, scene_function, n, engine, steps, timeout=1800):
    """Run one measurement in a child process; returns its dict or {"error": ...}."""
    env = on_path(os.environ)
    cmd = [sys.executable, "-m", "benchmarks.measure", scene_module, scene_function, str(n), engine,
           str(steps)]
    try:
        # stderr passes through: the child's progress lines and any traceback show as they come
        out = subprocess.run(cmd, stdout=subprocess.PIPE, text=True, timeout=timeout, env=env)
    except subprocess.TimeoutExpired:
        return {"engine": engine, "error": f"timed out after {timeout} s"}
    if out.returncode != 0:
        return {"engine": engine, "error": f"exit status {out.returncode} (traceback above)"}
    lines = [ln for ln in out.stdout.splitlines() if ln.startswith("{")]
    if not lines:
        return {"engine": engine, "error": "no result printed"}
    return json.loads(lines[-1])


if __name__ == "__main__":
    mod, fn, n, engine, steps = sys.argv[1:6]
    print(json.dumps(measure_here(mod, fn, int(n), engine, int(steps))))
