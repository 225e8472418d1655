"""The Python API: `sweep(...)` runs a whole sweep into a Parquet file.

    from physics_sweep import sweep
    summary = sweep("scenes/head_on.yaml", ["bodies[ball_a].restitution=0:1:11"], seeds=10,
                    duration=1.0, measures=["ball_a.velocity.x:end"], out="head_on.parquet")

`SweepPlan.make(...)` with `run_serial(plan)` gives the rows in-process
without Ray or a file.
"""
import time
from dataclasses import dataclass

from . import ray_runner
from .progress import Progress
from .results import ResultsFile
from .runs import SweepPlan, run_serial


@dataclass
class SweepSummary:
    out: str
    total: int            # runs in the design
    rows: int             # rows in the file at the end
    computed: int         # runs computed by this call (the others were in the file already)
    failed: int           # rows with an error, in the whole file
    seconds: float
    first_error: str = None
    interrupted: bool = False

    def line(self):
        head = "interrupted: " if self.interrupted else ""
        text = (f"{head}{self.rows}/{self.total} runs in {self.out} ({self.computed} computed now in "
                f"{self.seconds:.1f} s, {self.failed} failed)")
        if self.first_error:
            text += f"; first error: {self.first_error}"
        return text


def sweep(scene, vary=(), *, seeds=None, samples=None, design_seed=0, duration=1.0, measures=(),
          perturbs=None, out="sweep.parquet", **options):
    """Plan and run a sweep; `options` are those of `run_sweep`. Returns a SweepSummary."""
    plan = SweepPlan.make(scene, vary, seeds=seeds, samples=samples, design_seed=design_seed,
                          duration=duration, measures=measures, perturbs=perturbs)
    return run_sweep(plan, out, **options)


def run_sweep(plan, out, *, resume=False, overwrite=False, address=None, workers=None, serial=False,
              batch=None, retries=ray_runner.DEFAULT_RETRIES, flush_rows=256, progress=True):
    """Run `plan` into `out`: serially in this process, or on Ray (local unless `address`)."""
    results = ResultsFile(out, plan, resume=resume, overwrite=overwrite, flush_rows=flush_rows)
    total = len(plan.design)
    bar = Progress(total, already=len(results.done), failed=results.failed, enabled=progress)
    first_error = []
    start = time.perf_counter()

    def sink(rows):
        before = results.failed
        added = results.add(rows)
        first_error.extend(r["error"] for r in rows if r["error"] and not first_error)
        bar.update(added, results.failed - before)

    todo = (r for r in plan.design.runs() if r.run_id not in results.done)
    interrupted = False
    started = False
    try:
        if serial:
            for row in run_serial(plan, todo):
                sink([row])
        else:
            started = ray_runner.connect(address, workers)
            ray_runner.run_on_ray(plan, todo, total - len(results.done), sink, batch=batch, retries=retries)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        rows = results.close()
        bar.finish()
        if started:
            import ray
            ray.shutdown()
    computed = bar.done - bar.already
    return SweepSummary(results.path, total, rows, computed, results.failed, time.perf_counter() - start,
                        first_error[0] if first_error else None, interrupted)
