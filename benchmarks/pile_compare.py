"""Sphere piles in this engine, PyBullet and MuJoCo, in one process: steps per second.

    python -m benchmarks.pile_compare [--sizes 100 1000 10000] [--steps 240] [--budget 120]
                                      [--repeat 1] [--others pybullet mujoco mujoco-cg] [--quick]

The scene: N spheres of radius 0.1 m and 1 kg on a grid of columns 0.25 m
apart, ten layers high (fewer below 100 spheres), the lowest 5 cm above a
ground plane, each shifted by up to 1 cm sideways (fixed seed) so the
columns topple; dropped under gravity, dt = 1/240 s. Every engine gets the
same bodies and step through benchmarks/engines.py: 8 solver iterations,
sleeping off. Each engine runs the same number of steps from the same start
(the first second: the fall, the impacts and the pile forming), timed
around the stepping only, in CPU seconds of this process (all three engines
step in this thread, so other load on the machine does not count against
one of them; the wall time is logged too); with `--repeat R` the engines
run in turn R times (rounds, as the pyramid's fresh processes do) and each
one's fastest run is kept; within a round, a run shorter than 0.2 s CPU
(measure.MIN_TIMED) is made again until its runs reach that (at most
measure.MAX_WINDOWS), the fastest kept. An engine that has not finished its
steps within `--budget` wall seconds stops there and is reported over the
steps it did (marked `*`: an early part of the run, the fall, is cheaper
than the pile); one whose cost at the previous size, scaled linearly with
the bodies, projects beyond 3 budgets is not started at all (a single step
of a native engine cannot be interrupted: MuJoCo's default Newton solver
takes minutes per step on the 10,000-sphere pile). PyBullet and MuJoCo are optional: a missing one is a column
of "not installed".

Prints a Markdown table with steps/s and the ratios, then where this
engine's step time goes (world.profile, per stage).
"""
import argparse
import importlib.util
import warnings
from time import perf_counter, process_time

import numpy as np

from . import engines
from .measure import BUDGET, fastest_run     # s of stepping per engine and size, at most

SIZES = (100, 1000, 10000)
STEPS = 240
QUICK_STEPS = 60
RADIUS = 0.1
SPACING = 0.25
LAYERS = 10
JITTER = 0.01
SEED = 0
OTHERS = engines.PEERS
SKIP_FACTOR = 3.0       # an engine projected to need more than this × budget at a size is not run


def pile(n, radius=RADIUS, spacing=SPACING, layers=LAYERS, seed=SEED):
    """[(shape, size, position)] for benchmarks.engines: n spheres in columns."""
    side = max(1, int(np.ceil(np.sqrt(n / layers)))) if n >= 10 * layers else max(1, int(np.ceil(n ** (1 / 3))))
    i = np.arange(n)
    pos = np.stack([(i % side) * spacing, ((i // side) % side) * spacing,
                    radius + 0.05 + (i // side ** 2) * spacing], axis=1).astype(float)
    pos[:, :2] += np.random.default_rng(seed).uniform(-JITTER, JITTER, (n, 2))
    return [("sphere", radius, p) for p in pos]


def installed(engine):
    return engine == "physics_core" or importlib.util.find_spec(engines.module_of(engine)) is not None


def time_engine(engine, bodies, steps, budget):
    """(steps done, CPU seconds, wall seconds, stage profile or None)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        step, _, stages = engines.build(engine, bodies)
    # every engine takes one step before the clock starts: this engine's first
    # call loads its compiled kernels (a one-time cost of the process, reported
    # as start-up, not per step), the others' sets up their solvers
    step(1)
    done, t0, c0 = 0, perf_counter(), process_time()
    chunk = 1                      # grown while a chunk takes under a second, so a slow
    while done < steps and perf_counter() - t0 < budget:   # engine still meets the budget
        k = min(chunk, steps - done)
        c = perf_counter()
        step(k)
        done += k
        if perf_counter() - c < 0.5:
            chunk = min(2 * chunk, max(1, steps // 24))
    return done, process_time() - c0, perf_counter() - t0, stages()


def _fastest_run(engine, bodies, steps, budget, log):
    """(steps, CPU s, stages) of the fastest of one run or more
    (measure.fastest_run: a run of a few bodies, about a millisecond, is
    made again until the runs reach MIN_TIMED CPU seconds)."""
    (done, cpu, wall, prof), runs = fastest_run(
        lambda: time_engine(engine, bodies, steps, budget), steps)
    log(f"  {len(bodies)} spheres, {engine}: {done} steps in {cpu:.2f} s CPU ({wall:.2f} s wall), "
        f"{done / cpu:.3g} steps/s" + (f", the fastest of {runs} runs" if runs > 1 else ""))
    return done, cpu, prof


def _runnable(engine, n, per_step, steps, budget, row, log):
    """Whether to run `engine` at n spheres; if not, why, in its row cell. An
    engine that would take far beyond the budget (its last size's cost,
    scaled linearly) is not started: one of its steps cannot be interrupted."""
    if not installed(engine):
        row[f"{engine} steps/s"] = "not installed"
        return False
    if engine in per_step:
        n0, sec = per_step[engine]
        projected = sec * n / n0 * steps
        if projected > SKIP_FACTOR * budget:
            row[f"{engine} steps/s"] = f"not run (≥ {projected:.0f} s projected)"
            log(f"  {n} spheres, {engine}: not run, {projected:.0f} s projected from {n0} spheres")
            return False
    return True


def _rounds(engines_here, bodies, steps, budget, repeat, log):
    """{engine: (steps, CPU s, stages)}, each engine's fastest over `repeat`
    rounds, the engines in turn within each round (as the pyramid's fresh
    processes are), so that a slow phase of the machine lasting all of one
    engine's runs in place does not count against it alone; an engine
    that ran out of its budget is not run again."""
    best = {}
    for _ in range(max(1, repeat)):
        for engine in engines_here:
            if engine in best and best[engine][0] < steps:
                continue
            done, cpu, prof = _fastest_run(engine, bodies, steps, budget, log)
            if engine not in best or done / cpu > best[engine][0] / best[engine][1]:
                best[engine] = (done, cpu, prof)
    return best


def run(sizes=SIZES, steps=None, budget=BUDGET, quick=False, log=print, others=OTHERS, repeat=1):
    """One row per size: steps/s of each engine and how they compare."""
    steps = steps or (QUICK_STEPS if quick else STEPS)
    rows, profiles = [], {}
    per_step = {}          # engine -> (bodies, CPU s per step) at the last size run
    for n in sizes:
        bodies = pile(n)
        row = {"spheres": n, "steps": steps}
        engines_here = [e for e in ("physics_core",) + tuple(others)
                        if _runnable(e, n, per_step, steps, budget, row, log)]
        rate = {}
        for engine, (done, cpu, prof) in _rounds(engines_here, bodies, steps, budget, repeat,
                                                 log).items():
            per_step[engine] = (n, cpu / done)
            rate[engine] = done / cpu
            row[f"{engine} steps/s"] = f"{rate[engine]:.3g}" + ("" if done == steps else f"* ({done} steps)")
            if prof:
                profiles[n] = {k: v / done for k, v in prof.items()}
        for engine in others:
            if engine in rate and "physics_core" in rate:
                row[f"this / {engine}"] = f"{rate['physics_core'] / rate[engine]:.2f}"
            else:
                row[f"this / {engine}"] = "—"
        peers = [rate[e] for e in others if e in rate]
        row["this / fastest peer"] = (f"{rate['physics_core'] / max(peers):.2f}"
                                      if peers and "physics_core" in rate else "—")
        rows.append(row)
    run.profiles = profiles
    return rows


def markdown(rows):
    head = list(rows[0])
    lines = ["| " + " | ".join(head) + " |", "|" + "---:|" * len(head)]
    lines += ["| " + " | ".join(str(r.get(k, "")) for k in head) + " |" for r in rows]
    return "\n".join(lines)


def profile_markdown(profiles):
    if not profiles:
        return ""
    stages = []
    for p in profiles.values():
        stages += [k for k in p if k not in stages and k != "step"]
    head = ["spheres", "step ms"] + stages
    lines = ["| " + " | ".join(head) + " |", "|" + "---:|" * len(head)]
    for n, p in profiles.items():
        total = p.get("step", sum(p.values()))
        lines.append("| " + " | ".join([str(n), f"{1e3 * total:.2f}"]
                                       + [f"{100 * p.get(k, 0.0) / total:.0f}%" for k in stages]) + " |")
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=list(SIZES))
    ap.add_argument("--steps", type=int, default=None, help=f"steps per run (default {STEPS}, quick {QUICK_STEPS})")
    ap.add_argument("--budget", type=float, default=BUDGET, help="seconds of stepping per engine and size, at most")
    ap.add_argument("--repeat", type=int, default=1, help="runs per engine and size; the fastest is kept")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--others", nargs="*", default=list(OTHERS), choices=OTHERS,
                    help="engines to compare with (default: both)")
    args = ap.parse_args(argv)
    rows = run(args.sizes, args.steps, args.budget, args.quick, others=args.others, repeat=args.repeat)
    print()
    print(f"Sphere pile, r = {RADIUS} m, dt = 1/{round(1 / engines.DT)} s, "
          f"{engines.ITERATIONS} solver iterations, sleeping off; steps per CPU second "
          "(higher is faster):\n")
    print(markdown(rows))
    print("\nThis engine, share of the step per stage (world.profile):\n")
    print(profile_markdown(run.profiles))


if __name__ == "__main__":
    main()
