"""`physics-bench`: accuracy, stability, scale and effect-cost studies.

    physics-bench accuracy  [--quick] [--out DIR]   integrators × dt × substeps, contacts
    physics-bench stability [--quick] [--out DIR]   hard cases, stiff spring, long runs, random scenes
    physics-bench scale     [--quick] [--repeat R] [--out DIR]   sphere and box piles and the pyramid beside PyBullet and MuJoCo
    physics-bench effects   [--quick] [--out DIR]   per-effect cost table
    physics-bench node      [--quick] [--out DIR]   ROS 2 node in real time: step, publish, recording cost
    physics-bench crosscheck [--quick] [--out DIR]  closed-form scenes beside PyBullet and MuJoCo
    physics-bench all       [--quick] [--out DIR]   all of the above
    physics-bench hostile   [--quick] [--out DIR]   floods against a node: received, counted, memory, /clock
                                                    (not part of `all`)
    physics-bench mutations [--only WORD ...] [--list] [--cold]
                                                    plant physics bugs one at a time; are they caught?
                                                    (hours on 2 shared cores; not part of `all`)
    physics-bench sweep     [--quick] [--out DIR]   physics-sweep on Ray: runs/s on 1, 2, all cores (not in all)
    physics-bench compile   [--quick] [--out DIR]   every kernel compiled cold, with numba's inliner as
                                                    physics_core sets it and as numba ships it (not in all)

Each writes Markdown tables (`*.md`), plots (`*.png`) and raw data (`*.json`)
into DIR (default benchmarks/results) and refreshes DIR/README_results.md;
with the default DIR, also the results section of the README. Progress goes
to stderr.
"""
import argparse
import os
import sys
from time import perf_counter

from .results_io import DEFAULT_OUT, ensure

STUDIES = ("accuracy", "stability", "scale", "effects", "node", "crosscheck")


def _run_accuracy(args):
    from . import accuracy, contact_accuracy
    accuracy.run(quick=args.quick, out=args.out, only=args.only)
    contact_accuracy.run(quick=args.quick, out=args.out)


def _run_stability(args):
    from . import stability
    stability.run(quick=args.quick, out=args.out)


def _run_scale(args):
    from . import scale
    scale.run(quick=args.quick, out=args.out, repeat=getattr(args, "repeat", 1))


def _run_effects(args):
    from . import effects_cost
    effects_cost.run(quick=args.quick, out=args.out)


def _run_node(args):
    try:
        from . import node_realtime
        import rclpy  # noqa: F401
    except ImportError as e:
        sys.stderr.write(f"[node] skipped: the ROS 2 client library is not installed ({e})\n")
        return
    node_realtime.run(quick=args.quick, out_dir=args.out)


def _run_hostile(args):
    from . import hostile_flood
    hostile_flood.run(quick=args.quick, out=args.out)


def _run_crosscheck(args):
    from . import crosscheck
    crosscheck.run(quick=args.quick, out=args.out)


def _run_compile(args):
    from . import compile_time
    compile_time.run(quick=args.quick, out=args.out)


def _run_sweep(args):
    try:
        import ray  # noqa: F401
    except ImportError as e:
        sys.stderr.write(f"[sweep] skipped: ray is not installed ({e}); pip install -e '.[sweep]'\n")
        return
    from . import sweep_scaling
    sweep_scaling.run(quick=args.quick, out=args.out)


RUNNERS = {"accuracy": _run_accuracy, "stability": _run_stability,
           "scale": _run_scale, "effects": _run_effects, "node": _run_node, "hostile": _run_hostile,
           "crosscheck": _run_crosscheck, "sweep": _run_sweep, "compile": _run_compile}


def parser():
    p = argparse.ArgumentParser(prog="physics-bench", description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog=__doc__.split("\n\n", 1)[1])
    sub = p.add_subparsers(dest="study", required=True)
    helps = {"accuracy": "integrators × dt × substeps on closed-form problems; contact accuracy",
             "stability": "stiff spring, 10⁵-step runs, random scenes, contact hard cases",
             "scale": "box pyramid and sphere piles beside PyBullet and MuJoCo",
             "effects": "cost of each declared effect",
             "node": "the ROS 2 node in real time: step, publish and recording cost per step",
             "crosscheck": "closed-form contact scenes in this engine, PyBullet and MuJoCo",
             "all": "every study, then the summary",
             "hostile": "floods against a running node: what reaches it, what it counts, memory, /clock",
             "sweep": "physics-sweep on a local Ray: runs/s on 1, 2 and all cores, overhead per run",
             "compile": "every kernel compiled cold: the inliner as physics_core sets it and numba's own"}
    sub.add_parser("mutations", add_help=False,
                   help="plant physics bugs one at a time and report which the tests catch "
                        "(physics-bench mutations --help)")
    for name in STUDIES + ("all", "hostile", "sweep", "compile"):
        s = sub.add_parser(name, help=helps[name])
        s.add_argument("--quick", action="store_true",
                       help="CI-sized run: fewer step sizes, shorter runs, fewer bodies")
        s.add_argument("--out", default=DEFAULT_OUT, help="output folder (default: %(default)s)")
        if name == "scale":
            s.add_argument("--repeat", type=int, default=1, metavar="R",
                           help="make every measurement R times, engines in turn, and keep "
                                "each engine's fastest run (default: %(default)s)")
        if name in ("accuracy", "all"):
            s.add_argument("--only", nargs="+", metavar="PROBLEM",
                           help="accuracy problems to run (harmonic damped drag_fall kepler "
                                "kepler_e09 stiff_spring free_top)")
    return p


def main(argv=None):
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv and argv[0] == "mutations":       # its own options (benchmarks/mutations.py)
        from . import mutations
        return mutations.main(argv[1:])
    args = parser().parse_args(argv)
    args.out = os.path.abspath(args.out)
    ensure(args.out)
    if not hasattr(args, "only"):
        args.only = None
    studies = STUDIES if args.study == "all" else (args.study,)
    start = perf_counter()
    if args.study in ("sweep", "compile"):   # their figures go to the README's own sections, not the results summary
        RUNNERS[args.study](args)
        sys.stderr.write(f"wrote {os.path.join(args.out, args.study + '.md')} "
                         f"({perf_counter() - start:.0f} s)\n")
        return 0
    for name in studies:
        t0 = perf_counter()
        sys.stderr.write(f"== {name}{' (quick)' if args.quick else ''} ==\n")
        RUNNERS[name](args)
        sys.stderr.write(f"== {name} done in {perf_counter() - t0:.0f} s ==\n")
    from . import summary
    written = summary.write(args.out, update_readme=os.path.samefile(args.out, ensure(DEFAULT_OUT)))
    sys.stderr.write(f"wrote {', '.join(written)} ({perf_counter() - start:.0f} s in all)\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
