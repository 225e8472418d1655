"""Does the ROS 2 node hold real time? Step, publish and recording cost per step.

    physics-bench node [--quick] [--out DIR]
    python -m benchmarks.node_realtime [--quick] [--out DIR] [--seconds S] [--only CASE ...]

Targets: 100 bodies at 1 kHz (dt = 1 ms) and 1,000 bodies at 240 Hz
(dt = 1/240 s), real_time_factor 1, every output published every step
(`publish_every` 1: `/clock`, `~/poses`, `~/contacts`, and the
`~/<body>/odom` topics someone subscribes to: here one body's, followed by
the listener; the `odometry all` rows serve every body's topic), and
recording (`record`) costing under 10 % of the step.

Scenes (generated dicts, written to a temporary YAML file the node loads):

- `contacts`: spheres (r = 0.1 m, 0.25 m apart on a square grid) dropped from
  up to 2 cm onto a ground plane, then resting on it, with `sleep: false`, so
  every sphere's ground contact goes through the solver every step and
  every step publishes one contact event per sphere (the demanding case);
- `contacts, sleep`: the same with the engine's default `sleep: true`,
  stepped headless for 1.5 s of sim time before the node spins, so the
  window shows the pile asleep (the usual case for a scene at rest);
- `free`: the same spheres falling under gravity, no plane and no `contacts`
  effect, so what is left is the node's own cost.

How it is measured: in this process, the node class `PhysicsNode` spun by
rclpy's events executor with `spin_once` in a loop, as `physics-node`
(physics_node/main.py) runs it, with `real_time_factor` 1; each case runs
without and with `record`. A separate process subscribes to `~/poses` and
to `~/s0/odom` (raw CDR, not deserialized) and counts the poses that
arrive, so publishing has a real subscriber, and the table shows the rate
actually delivered. After a
warm-up (discovery, first steps; 1.5 s), the node runs for a fixed wall time
(quick 5 s, full 20 s). Every step the node's `_advance` (commands, engine
step, `/clock`, poses, odometry, contacts, markers, recording) is timed, and
inside it the engine step and the recorder's writes:

- engine = `Stepper.advance` (queued commands, none here, and `world.step`);
- record = `Recorder.write_many` / `write` on the node's thread (MCAP
  records and indexes; the zstd compression, CRC and file writes of each
  finished chunk run on the recorder's writer thread, counted in the
  process CPU);
- publish = the rest of the step: building the messages as CDR, handing them
  to the middleware (`Publisher.publish`), the node's bookkeeping;
- per message = publish time over the messages of a step;
- recording overhead = mean step with `record` minus mean step without, as a
  share of the step with `record`, and as a share of dt;
- in steps = share of the wall time spent inside steps (the rest is the
  executor, timers and idle time); CPU = process CPU time over wall time
  (all threads: the middleware's and the recorder's writer too); process
  CPU per step = the same per step; writer thread = CPU time of the
  recorder's writer thread per step (measured on that thread), so
  recording, both threads = record + writer thread; load = the machine's 1-minute load
  average at the end of the row (other work on the machine slows every row).

The real-time factor is sim time advanced over wall time in the window; the
node drops a backlog of more than 0.25 s, so a node that cannot keep up
shows a factor below 1, not a growing lag. p99 is over the steps of the
window. This is a benchmark, not a test: nothing here asserts.
"""
import argparse
import gc
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from time import perf_counter, thread_time

if __package__ in (None, ""):            # run as a script
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import numpy as np
import yaml

RADIUS = 0.1            # m
SPACING = 0.25          # m between sphere centres on the grid
DROP = 0.02             # m, largest initial gap under a sphere
RECORD_TARGET = 0.10    # recording under this share of the step time
QUICK_SECONDS, FULL_SECONDS = 5.0, 20.0
WARMUP_SECONDS = 1.5
SETTLE_SIM_SECONDS = 1.5  # `contacts_sleep`: sim time stepped headless first, so the pile is at rest
LISTENER_READY_S = 20.0


@dataclass(frozen=True)
class Case:
    name: str
    bodies: int
    dt: float
    scene: str      # contacts | contacts_sleep | free
    odometry: str = "subscribed"   # the node's `odometry` parameter

    @property
    def rate_hz(self):
        return 1.0 / self.dt


CASES = (
    Case("100 @ 1 kHz, contacts", 100, 0.001, "contacts"),
    Case("100 @ 1 kHz, contacts, sleep", 100, 0.001, "contacts_sleep"),
    Case("100 @ 1 kHz, free", 100, 0.001, "free"),
    Case("1000 @ 240 Hz, contacts", 1000, 1.0 / 240.0, "contacts"),
    Case("1000 @ 240 Hz, contacts, sleep", 1000, 1.0 / 240.0, "contacts_sleep"),
    Case("1000 @ 240 Hz, free", 1000, 1.0 / 240.0, "free"),
    # every body's odometry topic served each step, read or not
    Case("100 @ 1 kHz, free, odometry all", 100, 0.001, "free", "all"),
    Case("1000 @ 240 Hz, free, odometry all", 1000, 1.0 / 240.0, "free", "all"),
    # a large world: its bodies' topics are made on demand (physics_node/body_topics.py)
    Case("10000 @ 60 Hz, contacts", 10_000, 1.0 / 60.0, "contacts"),
)


# ---- scenes -------------------------------------------------------------------

def scene(case, seed=1):
    """The scene dict of one case: `case.bodies` spheres on a square grid,
    each up to DROP above the plane (or falling freely with no plane)."""
    rng = np.random.default_rng(seed)
    side = int(np.ceil(np.sqrt(case.bodies)))
    contacts = case.scene != "free"
    bodies = []
    if contacts:
        bodies.append({"name": "ground", "shape": {"type": "plane", "normal": [0, 0, 1], "offset": 0.0},
                       "material": "concrete"})
    for i in range(case.bodies):
        x, y = (i % side) * SPACING, (i // side) * SPACING
        bodies.append({"name": f"s{i}", "shape": {"type": "sphere", "radius": RADIUS}, "mass": 1.0,
                       "material": "rubber", "restitution": 0.3,
                       "position": [x, y, RADIUS + DROP * float(rng.random())]})
    sc = {"name": f"node_realtime_{case.scene}_{case.bodies}", "dt": case.dt,
          "integrator": "semi_implicit_euler", "gravity": "earth", "bodies": bodies}
    if contacts:
        sc["effects"] = {"contacts": {"sleep": case.scene == "contacts_sleep"}}
        sc["friction"] = [{"a": "rubber", "b": "rubber", "static": 1.0, "kinetic": 0.8},
                          {"a": "concrete", "b": "concrete", "static": 0.6, "kinetic": 0.5}]
    return sc


# ---- ROS environment ------------------------------------------------------------

def ros_environment():
    """Localhost-only discovery and a domain of our own unless the caller set
    one, and the node's Fast DDS profile (physics_node/dds_profile.py): the
    node measured here runs in this process, so it gets the environment
    physics-node gives itself."""
    from physics_node.dds_profile import use_reply_profile
    os.environ.setdefault("RMW_IMPLEMENTATION", "rmw_fastrtps_cpp")
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    os.environ.setdefault("ROS_DOMAIN_ID", str(201 + os.getpid() % 30))
    use_reply_profile()
    return dict(os.environ)


class Listener:
    """A subscriber to `topic` in its own process, counting raw messages.
    Prints `ready` once it matches a publisher and the count when stdin closes."""

    def __init__(self, topic):
        from .repo import REPO, on_path
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "benchmarks.node_realtime", "--listen", topic],
            env=on_path(ros_environment()), cwd=REPO, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)

    def wait_ready(self, spin, timeout=LISTENER_READY_S):
        """Spin the node (`spin()`) until the listener has matched it."""
        import selectors
        sel = selectors.DefaultSelector()
        sel.register(self.proc.stdout, selectors.EVENT_READ)
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            spin()
            if sel.select(timeout=0):
                line = self.proc.stdout.readline()
                if line.strip() == "ready":
                    return True
                if not line:
                    return False
        return False

    def mark(self):
        """Ask for the count so far (the start of the measured window)."""
        self.proc.stdin.write("mark\n")
        self.proc.stdin.flush()

    def finish(self):
        """(messages since `mark`, seconds between `mark` and now) as the listener saw them."""
        try:
            out, _ = self.proc.communicate("", timeout=30)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            out, _ = self.proc.communicate()
        for line in out.splitlines():
            if line.startswith("count "):
                _, n, seconds = line.split()
                return int(n), float(seconds)
        return None, None


def listen(topic):
    """The listener process: count messages on `topic` between `mark` on stdin
    and stdin closing (raw CDR, so its own cost stays small)."""
    import threading

    import rclpy
    from geometry_msgs.msg import PoseArray
    from nav_msgs.msg import Odometry
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import QoSProfile, ReliabilityPolicy

    ros_environment()
    rclpy.init()
    node = rclpy.create_node("node_realtime_listener")
    count = [0]
    qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
    node.create_subscription(PoseArray, topic, lambda _raw: count.__setitem__(0, count[0] + 1), qos, raw=True)
    # and one body's odometry, as a client following a body does (the node
    # publishes a body's odometry while someone reads it)
    node.create_subscription(Odometry, topic.rsplit("/", 1)[0] + "/s0/odom", lambda _raw: None, qos, raw=True)
    state = {"mark": None, "base": 0, "done": False}

    def read_stdin():
        for line in sys.stdin:
            if line.strip() == "mark":
                state["mark"], state["base"] = time.monotonic(), count[0]
        state["done"] = True

    threading.Thread(target=read_stdin, daemon=True).start()
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    announced = False
    while not state["done"]:
        executor.spin_once(timeout_sec=0.05)
        if not announced and node.count_publishers(topic) > 0 and count[0] > 0:
            print("ready", flush=True)
            announced = True
    end = time.monotonic()
    start = state["mark"] if state["mark"] is not None else end
    print(f"count {count[0] - state['base']} {end - start:.6f}", flush=True)
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


# ---- one measurement ----------------------------------------------------------------

class StepProbe:
    """Times every step of a node: the whole `_advance`, the engine step
    inside it and the recorder's writes inside it, each in wall time and in
    CPU time of the node's thread (which other load on the machine does not
    inflate the way it inflates wall time)."""

    def __init__(self, node, capacity):
        self.measuring = False
        self.n = 0
        # columns: step, engine, record; wall then thread CPU
        self.samples_ = np.zeros((capacity, 6))
        self._engine = (0.0, 0.0)
        self._record = [0.0, 0.0]
        stepper_advance = node.stepper.advance
        node_advance = node._advance

        def timed_stepper_advance():
            t0, c0 = perf_counter(), thread_time()
            boundary = stepper_advance()
            self._engine = (perf_counter() - t0, thread_time() - c0)
            return boundary

        def timed_node_advance(publish_all=False):
            self._record = [0.0, 0.0]
            t0, c0 = perf_counter(), thread_time()
            node_advance(publish_all)
            wall, cpu = perf_counter() - t0, thread_time() - c0
            if self.measuring and self.n < len(self.samples_):
                self.samples_[self.n] = (wall, self._engine[0], self._record[0], cpu, self._engine[1], self._record[1])
                self.n += 1

        node.stepper.advance = timed_stepper_advance
        node._advance = timed_node_advance
        recorder = node.recorder
        if recorder is not None:
            # Every write goes through write_many where the recorder has it.
            name = "write_many" if hasattr(recorder, "write_many") else "write"
            write = getattr(recorder, name)

            def timed_write(*args, **kwargs):
                t0, c0 = perf_counter(), thread_time()
                write(*args, **kwargs)
                self._record[0] += perf_counter() - t0
                self._record[1] += thread_time() - c0

            setattr(recorder, name, timed_write)

    def samples(self):
        """(step, engine, record) wall seconds per step, then the same in thread CPU seconds."""
        return tuple(self.samples_[: self.n].T)


def _all_topics_at_start(case):
    """`odometry: all` serves every body's topic from the start, which the node
    refuses for a world past topics_on_demand_above (its topics are made on
    demand there): those cases raise the threshold above their body count."""
    from rclpy.parameter import Parameter
    if case.odometry != "all":
        return []
    return [Parameter("topics_on_demand_above", Parameter.Type.INTEGER, case.bodies + 1)]


def measure(case, record, seconds, workdir, listener=True, executor="events"):
    """Run the node on `case` for `seconds` of wall time after a warm-up; one row.
    `executor`: "events" (rclpy.experimental's EventsExecutor, physics-node's
    default) or "single" (rclpy's SingleThreadedExecutor, `--executor single`)."""
    executor_kind = executor
    ros_environment()
    import rclpy
    from rclpy.parameter import Parameter

    from physics_node.main import make_executor
    from physics_node.node import PhysicsNode

    tag = f"{case.scene}_{case.bodies}_{'rec' if record else 'norec'}"
    scene_path = os.path.join(workdir, f"{tag}.yaml")
    with open(scene_path, "w", encoding="utf-8") as f:
        yaml.safe_dump(scene(case), f, sort_keys=False)
    record_path = os.path.join(workdir, f"{tag}.mcap") if record else ""

    # The default context, as physics-node uses: PhysicsNode takes no other.
    rclpy.init()
    node = executor = watcher = None
    try:
        start = time.monotonic()
        node = PhysicsNode(parameter_overrides=[
            Parameter("scene", Parameter.Type.STRING, scene_path),
            Parameter("real_time_factor", Parameter.Type.DOUBLE, 1.0),
            Parameter("record", Parameter.Type.STRING, record_path),
            Parameter("publish_every", Parameter.Type.INTEGER, 1),
            Parameter("odometry", Parameter.Type.STRING, case.odometry),
            Parameter("max_bodies", Parameter.Type.INTEGER, max(10_000, case.bodies + 1)),  # the ground too
        ] + _all_topics_at_start(case))
        start_s = time.monotonic() - start
        if case.scene == "contacts_sleep":
            # Let the spheres land and fall asleep before the node runs, so
            # the window shows the scene at rest whatever rate the node holds.
            while node.world.time < SETTLE_SIM_SECONDS:
                node.world.step()
        capacity = int(1.2 * (seconds + WARMUP_SECONDS) / case.dt) + 1000
        probe = StepProbe(node, capacity)
        executor = make_executor(executor_kind)
        executor.add_node(node)

        def spin():
            executor.spin_once(timeout_sec=0.1)

        ready = None
        if listener:
            watcher = Listener(node.get_fully_qualified_name() + "/poses")
            ready = watcher.wait_ready(spin)
        end = time.monotonic() + WARMUP_SECONDS
        while time.monotonic() < end:
            spin()
        gc.collect()
        if watcher is not None:
            watcher.mark()
        sim0, step0 = node.world.time, node.world.step_index
        writer0 = node.recorder.writer_cpu_seconds if node.recorder is not None else 0.0
        cpu0, wall0 = time.process_time(), time.monotonic()
        probe.measuring = True
        end = wall0 + seconds
        while time.monotonic() < end:
            spin()
        probe.measuring = False
        wall = time.monotonic() - wall0
        cpu = time.process_time() - cpu0
        sim = node.world.time - sim0
        steps = node.world.step_index - step0
        contacts_now = len(node.world.contacts)
        received, listen_s = watcher.finish() if watcher is not None else (None, None)
        watcher = None
        messages = node.recorder.message_count if node.recorder is not None else None
        writer = node.recorder.writer_cpu_seconds - writer0 if node.recorder is not None else None
        messages_per_step = 1 + node.outputs.state_messages
        steps_total = node.world.step_index
    finally:
        if watcher is not None:
            watcher.finish()
        stop = time.monotonic()
        if node is not None:
            node.close()
            node.destroy_node()
        stop_s = time.monotonic() - stop
        if executor is not None:
            executor.shutdown()
        rclpy.try_shutdown()
    size = os.path.getsize(record_path) if record else None
    if record:
        os.remove(record_path)

    loop, engine, rec, loop_cpu, engine_cpu, rec_cpu = probe.samples()
    publish = loop - engine - rec
    ms = 1e3

    def stat(a):
        return (float(a.mean() * ms), float(np.percentile(a, 99) * ms)) if len(a) else (None, None)

    row = {
        "case": case.name, "scene": case.scene, "bodies": case.bodies, "dt_ms": case.dt * ms,
        "rate_hz": case.rate_hz, "record": record, "executor": executor_kind,
        "wall_s": wall, "sim_s": sim, "steps": steps,
        "rtf": sim / wall, "cpu_share": cpu / wall, "busy_share": float(loop.sum()) / wall,
        "contacts_at_end": contacts_now, "odometry": case.odometry,
        "messages_per_step": messages_per_step,
        "process_cpu_ms": cpu / max(steps, 1) * ms,
        "writer_cpu_ms": writer / max(steps, 1) * ms if writer is not None else None,
    }
    for name, a in (("step", loop), ("engine", engine), ("publish", publish), ("record", rec)):
        row[f"{name}_mean_ms"], row[f"{name}_p99_ms"] = stat(a)
    for name, a in (("step", loop_cpu), ("engine", engine_cpu), ("publish", loop_cpu - engine_cpu - rec_cpu),
                    ("record", rec_cpu)):
        row[f"{name}_cpu_ms"] = float(a.mean() * ms) if len(a) else None
    row["record_share_direct"] = float(rec.sum() / loop.sum()) if record and len(loop) else None
    row["listener_ready"] = ready
    row["poses_received_hz"] = received / listen_s if received is not None and listen_s else None
    row["recording_mb_per_s"] = size / 1e6 / wall if size is not None else None
    row["recording_kb_per_step"] = size / 1e3 / max(steps_total, 1) if size is not None else None
    row["recorded_messages"] = messages
    row["load_average"] = os.getloadavg()[0]
    row["node_start_s"], row["node_stop_s"] = start_s, stop_s
    row["seconds"] = seconds
    return row


# ---- the study ------------------------------------------------------------------------

def run(quick=False, out_dir=None, seconds=None, only=None, listener=True, executor="events"):
    """Every case with and without `record`; rows as `measure` returns them.
    Writes `node_realtime.md` and `node_realtime.json` into `out_dir` if given."""
    from .progress import Progress
    from .results_io import machine, write_json, write_text

    seconds = float(seconds or (QUICK_SECONDS if quick else FULL_SECONDS))
    cases = [c for c in CASES if not only or any(o in (c.name, c.scene) for o in only)]
    progress = Progress("node", 2 * len(cases))
    rows = []
    with tempfile.TemporaryDirectory(prefix="node_realtime_") as workdir:
        for case in cases:
            for record in (False, True):
                row = measure(case, record, seconds, workdir, listener=listener, executor=executor)
                rows.append(row)
                progress.step(f"{case.name}{', record' if record else ''}: real-time factor "
                              f"{row['rtf']:.3f}, step {row['step_mean_ms']:.3f} ms mean "
                              f"(engine {row['engine_mean_ms']:.3f}, publish {row['publish_mean_ms']:.3f}, "
                              f"record {row['record_mean_ms']:.3f}) of {row['dt_ms']:.3f} ms")
    add_overheads(rows)
    if out_dir:
        kept = _rows_not_run(out_dir, rows, only)
        data = {"quick": quick, "seconds": seconds, "machine": machine(), "rows": kept + rows}
        write_json(out_dir, "node_realtime.json", data)
        write_text(out_dir, "node_realtime.md", markdown(_in_case_order(kept + rows), seconds, machine()))
    return rows


def _rows_not_run(out_dir, rows, only):
    """The rows of the results already in `out_dir` whose case was not run now
    (`--only` replaces the rows of the cases it names and keeps the rest)."""
    import json
    path = os.path.join(out_dir, "node_realtime.json")
    if not only or not os.path.exists(path):
        return []
    with open(path, encoding="utf-8") as f:
        old = json.load(f).get("rows", [])
    ran = {(r["case"], r.get("executor")) for r in rows}
    return [r for r in old if (r["case"], r.get("executor")) not in ran]


def _in_case_order(rows):
    order = {c.name: i for i, c in enumerate(CASES)}
    return sorted(rows, key=lambda r: (order.get(r["case"], len(order)), r.get("executor") or "", r["record"]))


def add_overheads(rows):
    """Recording overhead of each recorded row against the same case unrecorded,
    in wall time and in the node thread's CPU time."""
    plain = {(r["case"], r.get("executor")): r for r in rows if not r["record"]}
    for r in rows:
        base = plain.get((r["case"], r.get("executor")))
        for key, clock in (("", "step_mean_ms"), ("_cpu", "step_cpu_ms")):
            if r["record"] and base and r[clock] and base[clock]:
                r[f"record_overhead{key}_ms"] = r[clock] - base[clock]
                r[f"record_overhead{key}_share"] = r[f"record_overhead{key}_ms"] / r[clock]
            else:
                r[f"record_overhead{key}_ms"] = r[f"record_overhead{key}_share"] = None


def _f(x, digits=3):
    return "—" if x is None else f"{x:.{digits}f}"


def _pct(x):
    return "—" if x is None else f"{100 * x:.1f} %"


def _label(row):
    return row["case"] + (" (single-threaded executor)" if row.get("executor") == "single" else "")


def recording_ms(row):
    """CPU per step the recording costs: the node thread's writes plus the
    writer thread's compression and file writes (both measured directly)."""
    if row.get("record_cpu_ms") is None or row.get("writer_cpu_ms") is None:
        return None
    return row["record_cpu_ms"] + row["writer_cpu_ms"]


def messages_per_step(row):
    """`/clock`, poses, contacts and the odometry (and markers) sent."""
    return row.get("messages_per_step") or row["bodies"] + 4


def markdown(rows, seconds, machine_line):
    from .markdown import table
    wall_header = ["case", "record", "real-time factor", "poses received (Hz)", "step mean / p99",
                   "engine mean / p99", "publish mean / p99", "record mean / p99", "budget dt",
                   "in steps", "CPU", "load", "node start / stop (s)"]
    wall = []
    for r in rows:
        wall.append([
            _label(r), "yes" if r["record"] else "no", _f(r["rtf"]), _f(r["poses_received_hz"], 0),
            f"{_f(r['step_mean_ms'])} / {_f(r['step_p99_ms'])}",
            f"{_f(r['engine_mean_ms'])} / {_f(r['engine_p99_ms'])}",
            f"{_f(r['publish_mean_ms'])} / {_f(r['publish_p99_ms'])}",
            f"{_f(r['record_mean_ms'])} / {_f(r['record_p99_ms'])}" if r["record"] else "—",
            _f(r["dt_ms"]), f"{100 * r['busy_share']:.0f} %", f"{100 * r['cpu_share']:.0f} %",
            _f(r.get("load_average"), 1),
            f"{_f(r.get('node_start_s'), 2)} / {_f(r.get('node_stop_s'), 2)}",
        ])
    cpu_header = ["case", "record", "step", "engine", "publish", "messages", "per message (µs)", "record",
                  "record share of step", "recording overhead (of step / of dt)", "writer thread",
                  "recording, both threads (of dt)", "process CPU per step", "MCAP per step (kB)"]
    cpu = []
    for r in rows:
        rec = r["record"]
        cpu.append([
            _label(r), "yes" if rec else "no", _f(r["step_cpu_ms"]), _f(r["engine_cpu_ms"]),
            _f(r["publish_cpu_ms"]), str(messages_per_step(r)),
            _f(1e3 * r["publish_cpu_ms"] / messages_per_step(r), 1),
            _f(r["record_cpu_ms"]) if rec else "—",
            _pct(r["record_cpu_ms"] / r["step_cpu_ms"]) if rec else "—",
            f"{_pct(r['record_overhead_cpu_share'])} / {_pct(r['record_overhead_cpu_ms'] / r['dt_ms'])}"
            if rec and r["record_overhead_cpu_ms"] is not None else "—",
            _f(r.get("writer_cpu_ms")) if rec else "—",
            _pct(recording_ms(r) / r["dt_ms"]) if rec and recording_ms(r) is not None else "—",
            _f(r.get("process_cpu_ms")),
            _f(r["recording_kb_per_step"], 1) if rec else "—",
        ])
    align = "ll" + "r" * 20
    lines = [
        "# Node real time: step, publish and recording cost", "",
        f"Machine: {machine_line}. Each row: {seconds:g} s of wall time at real_time_factor 1 (a row kept "
        "from an earlier run with `--only` has its own), every output someone reads published every step, "
        "after a warm-up. Node start = constructing PhysicsNode (scene load, world, topics, first outputs; "
        "not the imports), stop = closing and destroying it. Regenerate with `physics-bench node` "
        "(`--quick`: 5 s per row; `--only CASE`: those rows, the others kept).",
        "", "## Real time (wall clock, ms)", "",
        table(wall_header, wall, align=align[: len(wall_header)]),
        "## Cost per step (CPU time of the node's thread, mean, ms)", "",
        "CPU time counts only the node's own thread, so it is much less inflated than wall time by other "
        "load on the machine (not entirely: shared caches and cores). The recording share is the "
        "recorder's part of the recorded step; the overhead is the difference between the recorded and "
        "unrecorded rows.", "",
        table(cpu_header, cpu, align=align[: len(cpu_header)]),
        "## Reading", "",
    ]
    lines += [f"- {line}" for line in reading(rows)]
    lines += ["", "## Method", "", __doc__.split("\n\n", 2)[2].strip(), ""]
    return "\n".join(lines)


def reading(rows):
    """One line per row: did it hold real time, and where the step went."""
    out = []
    for r in rows:
        held = r["rtf"] >= 0.98
        what = "holds real time" if held else f"misses real time (factor {r['rtf']:.2f})"
        step, budget = r["step_cpu_ms"], r["dt_ms"]
        parts = [f"engine {r['engine_cpu_ms']:.3f}", f"publish {r['publish_cpu_ms']:.3f}"]
        if r["record"]:
            parts.append(f"record {r['record_cpu_ms']:.3f}")
        line = (f"{_label(r)}{', record' if r['record'] else ''}: {what}; a step costs {step:.3f} ms of CPU "
                f"against a {budget:.3f} ms budget ({step / budget:.0%}: {', '.join(parts)} ms)")
        if r["engine_cpu_ms"] > budget:
            line += f"; the engine step alone is {r['engine_cpu_ms'] / budget:.1f}× the budget"
        if r["contacts_at_end"]:
            line += f"; {r['contacts_at_end']} contact events in the last step"
        if r["record"]:
            share = r["record_cpu_ms"] / step
            ok = "under" if share < RECORD_TARGET else "over"
            line += (f"; recording takes {share:.0%} of the step on the node's thread ({ok} the 10 % target), "
                     f"{r['recording_kb_per_step']:.1f} kB of MCAP per step")
            total = recording_ms(r)
            if total is not None:
                line += (f"; with the writer thread's compression and writes, recording costs {total:.3f} ms "
                         f"of CPU per step ({total / budget:.1%} of dt)")
        if r.get("listener_ready") is False:
            line += "; the ~/poses subscriber never matched"
        out.append(line + ".")
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--quick", action="store_true", help="5 s per row instead of 20 s")
    p.add_argument("--out", default=None, help="output folder (default: benchmarks/results)")
    p.add_argument("--seconds", type=float, default=None, help="wall seconds per row")
    p.add_argument("--only", nargs="+", metavar="CASE", help="case names or scene kinds to run")
    p.add_argument("--no-listener", action="store_true", help="no subscriber process on ~/poses")
    p.add_argument("--executor", choices=("events", "single"), default="events",
                   help="rclpy executor: events (as physics-node runs by default) or rclpy's single-threaded one")
    p.add_argument("--listen", metavar="TOPIC", help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.listen:
        return listen(args.listen)
    from .results_io import DEFAULT_OUT
    run(quick=args.quick, out_dir=os.path.abspath(args.out or DEFAULT_OUT), seconds=args.seconds,
        only=args.only, listener=not args.no_listener, executor=args.executor)
    return 0


if __name__ == "__main__":
    if __package__ in (None, ""):
        __package__ = "benchmarks"  # noqa: A001  (relative imports when run as a script)
    sys.exit(main())
