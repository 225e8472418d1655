"""`physics-sweep`: many variations of a scene, or a corpus of recordings, on Ray.

    physics-sweep SCENE.yaml --vary 'bodies[ball].restitution=0:1:11' --vary 'dt=1/240,1/480' \\
        --seeds 100 --duration 5 --measure 'ball.position.z:max' --out results.parquet
    physics-sweep --resimulate 'recordings/*.mcap'

Ray runs the work: a local Ray on this machine unless --address names a
cluster ('auto', or ray://HOST:10001). --serial runs in this process.
Exit status: 0 done (runs that raised are rows with an error), 1 some
recordings diverge, 2 bad arguments or unreadable recordings, 130 interrupted
(the finished runs are in the file: --resume goes on).
"""
import argparse
import sys

from physics_core import SceneError

from .design import SweepError


def build_parser():
    p = argparse.ArgumentParser(prog="physics-sweep", description=__doc__.split("\n\n")[0],
                                epilog=__doc__.split("\n\n", 1)[1],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", nargs="?", help="scene file (YAML), or 'default' for the built-in scene")
    d = p.add_argument_group("design")
    d.add_argument("--vary", action="append", default=[], metavar="KEY=VALUES",
                   help="a scene key by its path (bodies[NAME].KEY, dt, effects.contacts.iterations, ...) "
                   "and its values: LOW:HIGH:COUNT or V1,V2,...; several --vary make a grid")
    d.add_argument("--samples", type=int, metavar="N",
                   help="a random design of N points instead of the grid (LOW:HIGH drawn uniformly)")
    d.add_argument("--seeds", type=int, metavar="N",
                   help="N seeded runs per point, each perturbing the initial conditions (see --perturb)")
    d.add_argument("--perturb", action="append", metavar="[bodies[NAME].]QUANTITY=SIGMA",
                   help="normal noise on position, velocity, angular_velocity (per component) or "
                   "orientation (rad) of the dynamic bodies, per seed; default with --seeds: position=0.001")
    d.add_argument("--design-seed", type=int, default=0, metavar="S",
                   help="seed of the random design and of the perturbations (default 0)")
    d.add_argument("--duration", type=float, default=1.0, metavar="S", help="simulated seconds per run (default 1)")
    d.add_argument("--measure", action="append", default=[], metavar="SPEC",
                   help="a column per run: BODY.QUANTITY[.C][:max|min|mean|sum|end|initial], a world quantity "
                   "(energy, kinetic_energy, momentum.x, contacts, ...) or MODULE:FUNCTION[:REDUCER]")
    o = p.add_argument_group("output")
    o.add_argument("--out", default="sweep.parquet", help="results file (Parquet, default %(default)s)")
    o.add_argument("--resume", action="store_true", help="skip runs already in --out and finish it")
    o.add_argument("--overwrite", action="store_true", help="replace the results already in --out")
    o.add_argument("--flush-every", type=int, default=256, metavar="N", help="rows kept in memory before a write")
    o.add_argument("--quiet", action="store_true", help="no progress line")
    r = p.add_argument_group("where it runs")
    r.add_argument("--address", help="an existing Ray cluster: auto, HOST:6379 or ray://HOST:10001")
    r.add_argument("--workers", type=int, help="CPUs of the local Ray (default: all of this machine's)")
    r.add_argument("--serial", action="store_true", help="no Ray: one run after another in this process")
    r.add_argument("--batch", type=int, metavar="N", help="runs per Ray task (default: sized to ~0.5 s a task)")
    r.add_argument("--retries", type=int, default=5, help="Ray retries of a task whose worker died (default 5)")
    p.add_argument("--resimulate", nargs="+", metavar="GLOB",
                   help="re-simulate every recording matched and report which diverge (first step and body)")
    return p


def _sweep(args):
    from .api import sweep
    summary = sweep(args.scene, args.vary, seeds=args.seeds, samples=args.samples,
                    design_seed=args.design_seed, duration=args.duration, measures=args.measure,
                    perturbs=args.perturb, out=args.out, resume=args.resume, overwrite=args.overwrite,
                    address=args.address, workers=args.workers, serial=args.serial, batch=args.batch,
                    retries=args.retries, flush_rows=args.flush_every, progress=not args.quiet)
    print(summary.line(), flush=True)
    if summary.interrupted:
        print("the finished runs are saved: run the same command with --resume to go on", file=sys.stderr)
        return 130
    return 0


def _resimulate(args):
    from . import corpus, ray_runner
    paths = corpus.expand(args.resimulate)
    reports = []

    def sink(report):
        reports.append({k: report[k] for k in ("path", "status", "step", "body")})   # the text is printed, not kept
        where = "" if report["status"] != "diverge" else f" at step {report['step']}, body {report['body']!r}"
        print(f"{report['path']}: {report['status']}{where}", flush=True)
        if report["status"] != "match":
            print("  " + report["report"].replace("\n", "\n  "), flush=True)

    if args.serial:
        corpus.resimulate_serial(paths, sink)
    else:
        started = ray_runner.connect(args.address, args.workers)
        try:
            ray_runner.resimulate_on_ray(paths, sink, retries=args.retries)
        finally:
            if started:
                import ray
                ray.shutdown()
    print(corpus.summary_line(reports), flush=True)
    return corpus.exit_status(reports)


def _check(args):
    if args.serial and args.address:
        raise SweepError("--serial runs in this process; --address names a Ray cluster: give one or the other")
    if args.workers is not None and (args.address or args.workers < 1):
        raise SweepError("--workers N (>= 1) sizes the local Ray; a cluster at --address has its own CPUs")
    if args.batch is not None and args.batch < 1:
        raise SweepError(f"--batch: an integer >= 1, got {args.batch}")
    if args.flush_every < 1 or args.retries < 0:
        raise SweepError("--flush-every is >= 1 and --retries >= 0")


def main(argv=None):
    args = build_parser().parse_args(argv)
    try:
        _check(args)
        if args.resimulate:
            if args.scene:
                raise SweepError("--resimulate takes recordings, not a scene; give one or the other")
            return _resimulate(args)
        if not args.scene:
            raise SweepError("give a scene file (or 'default'), or --resimulate 'recordings/*.mcap'")
        return _sweep(args)
    except (SweepError, SceneError) as e:
        print(f"physics-sweep: error: {e}", file=sys.stderr, flush=True)
        return 2
    except ConnectionError as e:          # ray.init: no cluster at --address
        print(f"physics-sweep: error: cannot reach the Ray cluster at {args.address!r}: {e}", file=sys.stderr,
              flush=True)
        return 2
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
