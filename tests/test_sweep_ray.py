"""physics-sweep on a real two-node Ray cluster on this machine
(`ray.cluster_utils.Cluster`, one CPU a node, on the loopback address),
started once for the module: a 200-run sweep equals a serial run bit for
bit, a worker killed inside a task loses no run, an interrupted sweep
resumes without repeats, and the corpus check flags exactly the recording
that was altered."""
import copy
import os
import signal
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path

import pyarrow.parquet as pq
import pytest
import sweep_support
from sweep_support import DROP_SCENE, SPIN_SCENE, STALL_ENV, write_recording

from physics_sweep import SweepPlan, resimulate_corpus, run_serial
from physics_sweep.ray_runner import keep_ray_on_loopback, run_on_ray
from physics_sweep.results import ResultsFile

keep_ray_on_loopback()        # before ray is imported: its services on 127.0.0.1 only
import ray  # noqa: E402
from ray.cluster_utils import Cluster  # noqa: E402
from ray.util.scheduling_strategies import NodeAffinitySchedulingStrategy  # noqa: E402

TESTS = Path(__file__).resolve().parent
REPO = TESTS.parent
VARY = ["bodies[ball].restitution=0:0.9:10"]
MEASURES = ["ball.position.z:max", "ball.velocity.z:end", "energy:end", "ball.contacts.begin:sum"]


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    stall = tmp_path_factory.mktemp("stall")
    # Workers inherit the environment of the nodes: the tests' modules
    # (sweep_support's user measures) and the stall folder reach them.
    saved = {k: os.environ.get(k) for k in ("PYTHONPATH", STALL_ENV)}
    os.environ["PYTHONPATH"] = os.pathsep.join([str(TESTS), str(REPO)] + [p for p in [saved["PYTHONPATH"]] if p])
    os.environ[STALL_ENV] = str(stall)
    c = Cluster(initialize_head=True, head_node_args={"num_cpus": 1, "include_dashboard": False})
    c.add_node(num_cpus=1)
    c.wait_for_nodes()
    ray.init(address=c.address, log_to_driver=False)
    # A worker on each node imports the engine before the tests start, so
    # that neither node is still starting while the other takes all the work.
    warm = ray.remote(_node_of_worker)
    nodes = [n["NodeID"] for n in ray.nodes() if n["Alive"]]
    assert len(nodes) == 2
    ran = ray.get([warm.options(scheduling_strategy=NodeAffinitySchedulingStrategy(n, soft=False)).remote()
                   for n in nodes])
    assert sorted(ran) == sorted(nodes)
    c.stall = stall
    yield c
    ray.shutdown()
    c.shutdown()
    for k, v in saved.items():
        os.environ.pop(k, None) if v is None else os.environ.__setitem__(k, v)


def _node_of_worker():
    import physics_sweep.runs  # noqa: F401  (the engine and its kernels)
    return ray.get_runtime_context().get_node_id()


def _plan(measures=MEASURES, duration=0.25):
    return SweepPlan.make(copy.deepcopy(DROP_SCENE), VARY, seeds=20, duration=duration, measures=measures)


def _bits(v):
    return None if v is None else struct.pack("<d", v)


def _assert_same_as_serial(table, plan):
    rows = table.to_pylist()
    ids = [r["run_id"] for r in rows]
    assert len(ids) == 200 and sorted(ids) == list(range(200)), "every run exactly once"
    serial = {r["run_id"]: r for r in run_serial(plan)}
    for r in rows:
        s = serial[r["run_id"]]
        assert r["error"] is None and s["error"] is None, r["error"] or s["error"]
        for m in plan.measures:
            assert _bits(r[m]) == _bits(s[m]), (r["run_id"], m, r[m], s[m])
        assert (r["seed"], r["bodies[ball].restitution"], r["steps"]) == (s["seed"], s["bodies[ball].restitution"],
                                                                           s["steps"])


def test_two_node_sweep_of_200_runs_equals_the_serial_run_bit_for_bit(cluster, tmp_path):
    from physics_sweep import run_sweep
    plan = _plan()
    out = tmp_path / "sweep.parquet"
    summary = run_sweep(plan, out, progress=False)
    assert (summary.rows, summary.computed, summary.failed) == (200, 200, 0)
    table = pq.read_table(out)
    _assert_same_as_serial(table, plan)
    nodes = {w.split("/")[0] for w in table.column("worker").to_pylist()}
    assert len(nodes) == 2, f"both nodes ran tasks: {nodes}"
    # the perturbations really vary the runs: 20 seeds give 20 apexes at each restitution
    first = [r["ball.position.z:max"] for r in table.to_pylist() if r["bodies[ball].restitution"] == 0.0]
    assert len(set(first)) == 20


def _kill_the_stalled_worker(stall):
    """Arm the stall; a thread kills the worker that claims it. Returns (thread, {'pid': ...})."""
    for name in ("pid", "claimed"):
        (stall / name).unlink(missing_ok=True)
    (stall / "armed").write_text("")
    killed = {}

    def killer():
        pid_file = stall / "pid"
        deadline = time.monotonic() + 60.0
        while not pid_file.exists() and time.monotonic() < deadline:
            time.sleep(0.01)
        killed["pid"] = int(pid_file.read_text())
        os.kill(killed["pid"], signal.SIGKILL)

    thread = threading.Thread(target=killer, daemon=True)
    thread.start()
    return thread, killed


def test_killing_a_worker_inside_a_task_still_gives_200_rows_each_once(cluster, tmp_path):
    plan = _plan(measures=MEASURES + ["sweep_support:stall_once"])
    thread, killed = _kill_the_stalled_worker(cluster.stall)
    out = tmp_path / "killed.parquet"
    results = ResultsFile(out, plan, flush_rows=50)
    run_on_ray(plan, plan.design.runs(), len(plan.design), results.add, batch=10)
    thread.join(timeout=60)
    assert results.close() == 200
    table = pq.read_table(out)
    workers = set(table.column("worker").to_pylist())
    assert killed["pid"] and not any(w.endswith(f":{killed['pid']}") for w in workers), \
        "the killed worker returned nothing; its task was retried elsewhere"
    with pytest.raises(ProcessLookupError):
        os.kill(killed["pid"], 0)
    _assert_same_as_serial(table, plan)


def test_a_task_that_fails_past_its_retries_gives_its_runs_error_rows(cluster):
    plan = _plan(measures=["sweep_support:stall_once"])
    thread, killed = _kill_the_stalled_worker(cluster.stall)
    rows = []
    run_on_ray(plan, plan.design.runs(), len(plan.design), rows.extend, batch=10, retries=0)
    thread.join(timeout=60)
    assert sorted(r["run_id"] for r in rows) == list(range(200))
    lost = [r for r in rows if r["error"]]
    assert len(lost) == 10, "exactly the killed task's batch"
    assert all(r["error"].startswith("task failed after its retries: WorkerCrashedError") for r in lost), lost[0]
    assert all(r["sweep_support:stall_once"] is None for r in lost)
    ids = sorted(r["run_id"] for r in lost)
    assert ids == list(range(ids[0], ids[0] + 10)), "one batch: ten runs in design order"


def test_resume_after_an_interrupted_sweep_completes_it_without_repeats(cluster, tmp_path):
    measures = MEASURES + ["sweep_support:slow_height"]
    out = tmp_path / "resumed.parquet"
    scene = tmp_path / "drop.yaml"
    import yaml
    scene.write_text(yaml.safe_dump(DROP_SCENE))
    args = [sys.executable, "-m", "physics_sweep", str(scene), "--seeds", "20", "--duration", "0.25",
            "--out", str(out), "--address", cluster.address, "--batch", "5", "--flush-every", "20", "--quiet"]
    args += [a for v in VARY for a in ("--vary", v)] + [a for m in measures for a in ("--measure", m)]
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(TESTS), str(REPO), os.environ.get("PYTHONPATH", "")]))
    proc = subprocess.Popen(args, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    parts = Path(str(out) + ".parts")
    deadline = time.monotonic() + 90.0
    while len(list(parts.glob("part-*.parquet"))) < 2 and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.02)
    proc.kill()                                   # outright: no chance to close the file
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == -signal.SIGKILL, err
    assert not out.exists(), "the sweep was cut before it finished"
    saved = sum(pq.read_metadata(p).num_rows for p in parts.glob("part-*.parquet"))
    assert 0 < saved < 200

    from physics_sweep import run_sweep
    plan = SweepPlan.make(str(scene), VARY, seeds=20, duration=0.25, measures=measures)
    summary = run_sweep(plan, out, resume=True, progress=False)
    assert (summary.rows, summary.computed) == (200, 200 - saved)
    assert not parts.exists()
    _assert_same_as_serial(pq.read_table(out), plan)


def test_corpus_check_flags_exactly_the_altered_recording(cluster, tmp_path):
    corpus = tmp_path / "recordings"
    corpus.mkdir()
    sweep_scene = (REPO / "scenes" / "head_on.yaml").read_text()
    write_recording(corpus / "spin.mcap", SPIN_SCENE, 120, impulse_at=30)
    write_recording(corpus / "head_on.mcap", sweep_scene, 150)
    write_recording(corpus / "spin_altered.mcap", SPIN_SCENE, 120, impulse_at=30, tamper_step=77)
    write_recording(corpus / "default.mcap", (REPO / "physics_core" / "data" / "default.yaml").read_text(), 100)
    reports = {Path(r["path"]).name: r for r in resimulate_corpus(str(corpus / "*.mcap"))}
    assert set(reports) == {"spin.mcap", "head_on.mcap", "spin_altered.mcap", "default.mcap"}
    diverged = {name for name, r in reports.items() if r["status"] != "match"}
    assert diverged == {"spin_altered.mcap"}, {n: r["report"] for n, r in reports.items()}
    bad = reports["spin_altered.mcap"]
    assert (bad["status"], bad["step"], bad["body"]) == ("diverge", 77, "box")
    compared = {name: r["compared"] for name, r in reports.items() if name != "spin_altered.mcap"}
    assert compared == {"spin.mcap": 120, "head_on.mcap": 150, "default.mcap": 100}
