"""Runs fanned out on Ray: the plan in the object store once, runs batched
into tasks, results streamed back with `ray.wait` as tasks finish.

- Batches: Ray's guidance is that tasks under about 10 ms gain nothing from
  being remote (the per-task cost is of that order), so runs are grouped
  until a task takes about `target` seconds (0.5 s by default): the first
  tasks hold one run each, and the mean wall time of the runs returned so
  far sizes the next ones. Near the end batches shrink so that every CPU
  still has two tasks to take (no long tail on one worker). `batch` fixes
  the size instead. Which runs share a task does not change any run's
  result: each builds its own world.
- At most `window` tasks (twice the cluster's CPUs) are in flight; the
  runs are drawn lazily from the design, and each finished task's rows go
  straight to `sink`, so the driver never holds the whole sweep.
- Faults: tasks are retried by Ray (`max_retries`, on a worker process or
  node that died), so a killed worker loses nothing; a task that still
  fails after its retries gives each of its runs a row with the error.
  A run that raises is not a task failure: its error is in its row.
"""
import logging
import math
import os
import re
import socket
import sys
from itertools import islice

TARGET_TASK_SECONDS = 0.5
MAX_BATCH = 10_000
DEFAULT_RETRIES = 5


def connect(address=None, workers=None):
    """ray.init: an existing cluster at `address` ('auto', 'ray://host:10001',
    'host:6379'), or a local Ray on this machine with `workers` CPUs (default: all).
    Returns True when this call started Ray (so the caller shuts it down)."""
    if not address and "ray" not in sys.modules:
        keep_ray_on_loopback()
    import ray
    if ray.is_initialized():
        return False
    if address:
        _check_reachable(address)
        ray.init(address=address)
    else:
        # Workers are new processes: they import this checkout, whatever put it on this process's path.
        ray.init(num_cpus=workers, include_dashboard=False, logging_level=logging.WARNING,
                 runtime_env={"env_vars": {"PYTHONPATH": _import_path()}})
    return True


def _import_path():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    paths = [root, os.getcwd()] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]
    return os.pathsep.join(dict.fromkeys(paths))


def _check_reachable(address):
    """Fail in seconds, not minutes: ray.init keeps retrying an address where nothing listens."""
    if address == "auto":
        return
    hostport = address.split("://", 1)[-1]
    host, _, port = hostport.rpartition(":")
    try:
        socket.create_connection((host, int(port)), timeout=5.0).close()
    except (OSError, ValueError) as e:
        raise ConnectionError(f"nothing answers at {hostport} ({e}); on the head machine: "
                              "ray start --head (GCS port 6379, Ray Client port 10001)") from None


def keep_ray_on_loopback():
    """A local Ray listens on 127.0.0.1 only, reachable from nowhere else.

    On Linux Ray binds its services to the machine's network address (so that
    other machines can join); the setting Ray uses on macOS and Windows
    (where clusters are off by default) makes it use the loopback address.
    It is read when `ray` is imported and inherited by Ray's processes."""
    os.environ.setdefault("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", "0")


def cluster_cpus():
    import ray
    return max(1, int(ray.cluster_resources().get("CPU", 1)))


def _run_batch(plan, runs):
    import ray
    from .runs import execute
    node = ray.get_runtime_context().get_node_id()[:8]
    rows = [execute(plan, r) for r in runs]
    for row in rows:
        row["worker"] = f"{node}/{row['worker']}"     # Ray node, then host:pid
    return rows


class BatchSizer:
    """Runs per task: about `target` seconds of work, at least two tasks per CPU at the end."""

    def __init__(self, cpus, fixed=None, target=TARGET_TASK_SECONDS):
        self.cpus, self.fixed, self.target = cpus, fixed, target
        self.seconds, self.count = 0.0, 0

    def learn(self, rows):
        self.seconds += sum(r["wall_s"] or 0.0 for r in rows)
        self.count += len(rows)

    def size(self, remaining):
        if self.fixed:
            return self.fixed
        if self.count == 0:
            return 1
        per_run = max(self.seconds / self.count, 1e-6)
        size = min(MAX_BATCH, max(1, round(self.target / per_run)))
        return max(1, min(size, math.ceil(remaining / (2 * self.cpus))))


def _lost_rows(plan, runs, error):
    from .runs import worker_name
    lines = [ln.strip() for ln in re.sub(r"\x1b\[[0-9;]*m", "", str(error)).splitlines() if ln.strip()]
    text = f"task failed after its retries: {type(error).__name__}: " + " ... ".join(dict.fromkeys(lines[:1] + lines[-1:]))
    out = []
    for r in runs:
        row = {"run_id": r.run_id, "seed": r.seed, **dict(r.params), **{m: None for m in plan.measures}}
        row.update(steps=0, wall_s=None, cpu_s=None, engine_version=plan.engine_version,
                   worker=worker_name(), error=text)
        out.append(row)
    return out


def run_on_ray(plan, runs, total, sink, *, batch=None, retries=DEFAULT_RETRIES, window=None,
               target=TARGET_TASK_SECONDS):
    """Compute `runs` (an iterable of RunSpec, `total` of them) on the connected
    Ray cluster; `sink(rows)` gets each finished task's rows, in finishing order."""
    import ray
    task = ray.remote(_run_batch).options(num_cpus=1, max_retries=retries, retry_exceptions=False)
    plan_ref = ray.put(plan)               # once; every task gets the same object
    cpus = cluster_cpus()
    window = window or 2 * cpus
    sizer = BatchSizer(cpus, batch, target)
    runs, pending, left = iter(runs), {}, total
    try:
        while True:
            while len(pending) < window:
                chunk = list(islice(runs, sizer.size(left)))
                if not chunk:
                    break
                left -= len(chunk)
                pending[task.remote(plan_ref, chunk)] = chunk
            if not pending:
                return
            ready, _ = ray.wait(list(pending), num_returns=1)
            for ref in ready:
                chunk = pending.pop(ref)
                try:
                    rows = ray.get(ref)
                except ray.exceptions.RayError as e:
                    rows = _lost_rows(plan, chunk, e)
                sizer.learn(rows)
                sink(rows)
    finally:
        for ref in pending:                # stopped early (Ctrl-C, an error in sink)
            ray.cancel(ref)


def _resimulate_one(path):
    from .corpus import check_recording
    return check_recording(path)


def resimulate_on_ray(paths, sink, *, retries=DEFAULT_RETRIES):
    """One task per recording; `sink(report)` as each finishes."""
    import ray
    task = ray.remote(_resimulate_one).options(num_cpus=1, max_retries=retries, retry_exceptions=False)
    pending = {task.remote(p): p for p in paths}
    try:
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1)
            for ref in ready:
                path = pending.pop(ref)
                try:
                    sink(ray.get(ref))
                except ray.exceptions.RayError as e:
                    from .corpus import error_report
                    sink(error_report(path, f"task failed after its retries: {type(e).__name__}"))
    finally:
        for ref in pending:
            ray.cancel(ref)
