"""physics_sweep: many runs of a scene — a grid or random design over scene keys,
seeded perturbations, measures per run — or a corpus of recordings re-simulated,
fanned out on Ray (local by default, a cluster by address), results to Parquet.

    from physics_sweep import sweep
    sweep("scenes/head_on.yaml", ["bodies[ball_a].restitution=0:1:11"], duration=1.0,
          measures=["ball_b.velocity.x:end"], out="head_on.parquet")

Ray and pyarrow are the `sweep` extra (`pip install -e '.[sweep]'`); the
serial path (`SweepPlan.make` + `run_serial`) needs neither.
"""
from .design import Design, Perturb, RunSpec, SweepError, Vary
from .runs import SweepPlan, execute, run_serial

__all__ = ["sweep", "run_sweep", "SweepPlan", "Design", "Vary", "Perturb", "RunSpec", "SweepError",
           "execute", "run_serial", "resimulate_corpus"]


def sweep(*args, **kwargs):
    from .api import sweep as _sweep
    return _sweep(*args, **kwargs)


def run_sweep(*args, **kwargs):
    from .api import run_sweep as _run_sweep
    return _run_sweep(*args, **kwargs)


def resimulate_corpus(patterns, *, address=None, workers=None, serial=False):
    """Reports (dicts: path, status, step, body, compared, report) of every recording matched."""
    from . import corpus, ray_runner
    reports = []
    paths = corpus.expand([patterns] if isinstance(patterns, str) else patterns)
    if serial:
        corpus.resimulate_serial(paths, reports.append)
        return reports
    started = ray_runner.connect(address, workers)
    try:
        ray_runner.resimulate_on_ray(paths, reports.append)
    finally:
        if started:
            import ray
            ray.shutdown()
    return reports
