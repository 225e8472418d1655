"""`physics-bench sweep`: physics-sweep's runs per second on Ray with 1, 2 and
all cores against the serial in-process loop, Ray's cost per run, and the
speed-up with two workers on runs of at least 50 ms.

- Long runs: the default scene (contacts, a spring) stepped for as many
  simulated seconds as make one serial run take about `RUN_SECONDS` of CPU
  (calibrated first), with a per-step measure, as a sweep over restitution
  and seeds would run them.
- Each Ray configuration is a fresh local Ray with that many CPUs; its
  workers are started (one single-run task each) before the clock starts,
  so the figure is the steady rate; Ray's start-up is reported beside it.
- Scheduling overhead: runs of one step (scene build included, about a
  millisecond) through Ray on one CPU, one run per task (the worst case)
  and batched as physics-sweep batches them: the wall time × workers not
  spent inside a run (as the run itself timed it), per run. Time a loaded
  machine takes from a worker inside a run is not counted as overhead.
- The machine is shared: `cpu share` is the runs' own CPU seconds over
  wall seconds × workers, so a figure depressed by other load says so; the
  load average is recorded before and after.
"""
import copy
import os
import sys
import time

from physics_core import default_scene_path
from physics_sweep import SweepPlan, run_serial
from physics_sweep.ray_runner import keep_ray_on_loopback, run_on_ray

from .results_io import machine, write_json, write_text

RUN_SECONDS = 0.1
MEASURES = ("ball.position.z:max", "energy:end")


def _plan(duration, runs, seeds=None):
    """`runs` runs of the default scene over restitution (and seeds)."""
    from physics_core.scene_loader import read_scene_source
    scene = read_scene_source(default_scene_path())[0]
    vary = [f"bodies[ball].restitution=0.1:0.9:{runs // (seeds or 1)}"]
    return SweepPlan.make(copy.deepcopy(scene), vary, seeds=seeds, duration=duration, measures=MEASURES)


def _calibrate():
    probe = _plan(1.0, 1)
    list(run_serial(probe))                                   # kernels loaded
    (row,) = run_serial(probe)
    return max(0.25, round(RUN_SECONDS / row["cpu_s"] * 4) / 4)   # sim seconds, in quarter seconds


def _serial(plan):
    start, cpu = time.perf_counter(), time.process_time()
    rows = list(run_serial(plan))
    wall = time.perf_counter() - start
    return {"runs": len(rows), "wall_s": wall, "runs_per_s": len(rows) / wall,
            "cpu_s": time.process_time() - cpu, "run_cpu_s": sum(r["cpu_s"] for r in rows) / len(rows),
            "cpu_share": sum(r["cpu_s"] for r in rows) / wall}


def _on_ray(plan, workers, batch=None):
    import ray
    t0 = time.perf_counter()
    ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False)
    warm = _plan(plan.duration if plan.duration < 0.01 else 0.01, workers)
    run_on_ray(warm, warm.design.runs(), len(warm.design), lambda rows: None, batch=1)
    started = time.perf_counter() - t0
    rows = []
    start = time.perf_counter()
    run_on_ray(plan, plan.design.runs(), len(plan.design), rows.extend, batch=batch)
    wall = time.perf_counter() - start
    ray.shutdown()
    errors = [r["error"] for r in rows if r["error"]]
    if errors or len(rows) != len(plan.design):
        raise RuntimeError(f"sweep benchmark: {len(rows)} rows, errors: {errors[:1]}")
    inside = sum(r["wall_s"] for r in rows)
    return {"workers": workers, "runs": len(rows), "wall_s": wall, "runs_per_s": len(rows) / wall,
            "start_s": started, "cpu_share": sum(r["cpu_s"] for r in rows) / (wall * workers),
            "overhead_per_run_s": (wall * workers - inside) / len(rows)}


def _overhead(runs):
    """Seconds of Ray per run beyond the serial loop, for one-step runs on one worker."""
    tiny = _plan(1.0 / 240.0, runs)
    serial = _serial(tiny)
    one = _on_ray(tiny, 1, batch=1)
    batched = _on_ray(tiny, 1)
    return {"runs": runs, "serial_per_run_s": serial["wall_s"] / runs,
            "ray_one_per_task_s": one["overhead_per_run_s"], "ray_batched_s": batched["overhead_per_run_s"]}


def run(quick=False, out=None):
    keep_ray_on_loopback()
    load_before = os.getloadavg()
    duration = _calibrate()
    n = 24 if quick else 64
    plan = _plan(duration, n, seeds=4)
    sys.stderr.write(f"[sweep] {n} runs of {duration} s simulated each\n")
    serial = _serial(plan)
    sys.stderr.write(f"[sweep] serial {serial['runs_per_s']:.2f} runs/s\n")
    ray_rows = []
    for k in sorted({1, 2, os.cpu_count() or 1}):
        ray_rows.append(_on_ray(plan, k))
        sys.stderr.write(f"[sweep] ray x{k} {ray_rows[-1]['runs_per_s']:.2f} runs/s\n")
    overhead = _overhead(200 if quick else 1000)
    data = {"machine": machine(), "cores": os.cpu_count(), "duration": duration, "serial": serial,
            "ray": ray_rows, "overhead": overhead, "load_before": load_before, "load_after": os.getloadavg()}
    if out:
        write_json(out, "sweep.json", data)
        write_text(out, "sweep.md", markdown(data))
    return data


def markdown(d):
    s = d["serial"]
    lines = [f"# physics-sweep scaling\n\n{d['machine']}; load average before {d['load_before'][0]:.1f}, "
             f"after {d['load_after'][0]:.1f} (1 min), on {d['cores']} cores.\n",
             f"Runs: the default scene for {d['duration']} s simulated, measured every step; one serial run "
             f"takes {s['run_cpu_s'] * 1e3:.0f} ms of CPU.\n",
             "| how | workers | runs/s | speed-up over serial | cpu share | inside runs | overhead per run, ms "
             "| Ray start, s |",
             "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
             f"| serial loop | 1 | {s['runs_per_s']:.2f} | 1.00 | {s['cpu_share']:.2f} | | | |"]
    for r in d["ray"]:
        inside = 1.0 - r["overhead_per_run_s"] * r["runs_per_s"] / r["workers"]
        lines.append(f"| Ray, local | {r['workers']} | {r['runs_per_s']:.2f} | "
                     f"{r['runs_per_s'] / s['runs_per_s']:.2f} | {r['cpu_share']:.2f} | {inside:.3f} | "
                     f"{r['overhead_per_run_s'] * 1e3:.1f} | {r['start_s']:.1f} |")
    o = d["overhead"]
    lines += ["", f"Scheduling overhead ({o['runs']} one-step runs on one worker; a serial run of one is "
              f"{o['serial_per_run_s'] * 1e3:.2f} ms, the scene build included): "
              f"{o['ray_one_per_task_s'] * 1e3:.2f} ms per run with one run per task, "
              f"{o['ray_batched_s'] * 1e3:.3f} ms per run batched as physics-sweep batches.",
              "", "`inside runs`: the share of the workers' wall time spent inside runs; `overhead per run`: "
              "wall seconds × workers not spent inside a run, per run (scheduling, results back, idle at "
              "the end). `cpu share`: the runs' own CPU seconds over wall seconds × workers; below 1 the workers "
              "waited for a core (other processes on the machine) or for work."]
    return "\n".join(lines) + "\n"
