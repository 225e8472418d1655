"""Floods against a running node: what reaches it, what it counts, what it costs.

    physics-bench hostile [--quick] [--out DIR]

Each row starts `physics-node` in a process of its own (a ROS domain of
its own) on a four-body contact scene at dt = 10 ms, real-time factor 1,
and drives it from this process:

- `flood`: N wrenches on one body's topic as fast as Python publishes, from
  a reliable publisher with a KEEP_LAST history of 100 or with KEEP_ALL;
- `paused`: N impulses while paused, then unpause;
- `unknown`: K publishers on `~/<name>/wrench` topics of bodies the scene
  lacks, each publishing once.

Reported per row: messages sent (publish calls that returned), received,
applied, dropped (by reason) and queued as the node counts them in
/diagnostics once its counts settle, the node's resident memory before and
after, and the sim-time rate (/clock sim seconds per wall second) over the
3 s after the flood, plus the longest wall gap between two /clock messages
in that window. This is a study, not a test: nothing here asserts (the
hostile-input tests do, on smaller floods).
"""
import os
import signal
import subprocess
import sys
import tempfile
import time

from .repo import REPO, on_path
from .results_io import write_json, write_text

SCENE = """\
dt: 0.01
gravity: earth
effects:
  contacts: {iterations: 8}
bodies:
  - {name: ground, shape: {type: plane}}
  - {name: ball, shape: {type: sphere, radius: 0.1}, mass: 1.0, position: [0, 0, 0.1]}
  - {name: box, shape: {type: box, half_extents: [0.2, 0.2, 0.2]}, mass: 4.0, position: [1, 0, 0.2]}
  - {name: speck, shape: {type: sphere, radius: 0.01}, mass: 1.0e-12, position: [50, 0, 5]}
"""


class Session:
    """A node process and a driver node in this process, on a domain of their own."""

    def __init__(self, workdir, domain):
        os.environ["ROS_DOMAIN_ID"] = str(domain)
        os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from diagnostic_msgs.msg import DiagnosticArray
        from rosgraph_msgs.msg import Clock

        scene = os.path.join(workdir, "scene.yaml")
        with open(scene, "w") as f:
            f.write(SCENE)
        env = on_path(os.environ)
        self.log = open(os.path.join(workdir, f"node-{domain}.log"), "wb")
        self.proc = subprocess.Popen([sys.executable, "-m", "physics_node.main", "--scene", scene], cwd=REPO,
                                     env=env, stdout=self.log, stderr=subprocess.STDOUT, start_new_session=True)
        rclpy.try_shutdown()  # the domain is read when the context starts
        rclpy.init()
        self.rclpy = rclpy
        self.node = rclpy.create_node(f"hostile_bench_{os.getpid()}_{domain}")
        self.executor = SingleThreadedExecutor()
        self.executor.add_node(self.node)
        self.clocks, self.reports = [], []
        self.node.create_subscription(Clock, "/clock", lambda m: self.clocks.append(
            (time.monotonic(), m.clock.sec + m.clock.nanosec * 1e-9)), 10)
        self.node.create_subscription(DiagnosticArray, "/diagnostics", self.reports.append, 10)
        if not self.spin_until(lambda: len(self.reports) >= 1, 600.0):  # a first run compiles kernels
            self.close()
            raise RuntimeError(f"the node never reported on /diagnostics; see {self.log.name}")

    def spin_until(self, predicate, timeout):
        end = time.monotonic() + timeout
        while time.monotonic() < end and not predicate():
            self.executor.spin_once(timeout_sec=0.01)
        return predicate()

    def spin_for(self, seconds):
        self.spin_until(lambda: False, seconds)

    def values(self):
        from msg_adapters import diagnostic_values
        seen = len(self.reports)
        self.spin_until(lambda: len(self.reports) > seen, 5.0)
        return diagnostic_values(self.reports[-1])

    def settled(self, timeout=60.0):
        last, end = None, time.monotonic() + timeout
        while time.monotonic() < end:
            v = self.values()
            key = (v["received_commands"], v["queued_commands"])
            if key == last and v["queued_commands"] == "0":
                return v
            last = key
        return v

    def rss_mb(self):
        with open(f"/proc/{self.proc.pid}/status") as f:
            return next(int(line.split()[1]) / 1024 for line in f if line.startswith("VmRSS:"))

    def clock_after(self, seconds=3.0):
        start = len(self.clocks)
        self.spin_for(seconds)
        window = self.clocks[start:]
        if len(window) < 2:
            return 0.0, seconds
        rate = (window[-1][1] - window[0][1]) / (window[-1][0] - window[0][0])
        gap = max(b[0] - a[0] for a, b in zip(window, window[1:]))
        return rate, gap

    def call(self, name):
        from std_srvs.srv import Empty
        client = self.node.create_client(Empty, name)
        self.spin_until(client.service_is_ready, 10.0)
        future = client.call_async(Empty.Request())
        self.spin_until(future.done, 10.0)

    def close(self):
        self.executor.remove_node(self.node)
        self.node.destroy_node()
        self.rclpy.try_shutdown()
        self.proc.send_signal(signal.SIGINT)
        try:
            self.proc.wait(20.0)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        self.log.close()


def _flood(session, count, history, topic="/physics/box/wrench"):
    from geometry_msgs.msg import WrenchStamped
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from msg_adapters import wrench_stamped

    qos = QoSProfile(depth=100, history=history, reliability=ReliabilityPolicy.RELIABLE)
    pub = session.node.create_publisher(WrenchStamped, topic, qos)
    session.spin_until(lambda: pub.get_subscription_count() > 0, 10.0)
    msg = wrench_stamped((1.0, 0, 0))
    sent, start = 0, time.monotonic()
    for _ in range(count):
        try:
            pub.publish(msg)
            sent += 1
        except Exception:
            pass
    return pub, sent, time.monotonic() - start


def _row(session, name, sent, seconds, before_mb, before):
    v = session.settled()
    rate, gap = session.clock_after()
    counts = {k: int(v[k]) - int(before.get(k, 0)) for k in v if k.startswith("dropped_") or k in (
        "received_commands", "applied_commands")}
    dropped = {k[len("dropped_"):]: n for k, n in counts.items() if k.startswith("dropped_") and n and k != "dropped_commands"}
    row = dict(row=name, sent=sent, publish_s=round(seconds, 2), received=counts["received_commands"],
               applied=counts["applied_commands"], dropped=dropped, queued=int(v["queued_commands"]),
               rss_before_mb=round(before_mb), rss_after_mb=round(session.rss_mb()),
               sim_rate=round(rate, 3), longest_clock_gap_s=round(gap, 3))
    sys.stderr.write(f"[hostile] {row}\n")
    return row


def run(quick=False, out=None):
    from rclpy.qos import HistoryPolicy

    flood = 20_000 if quick else 100_000
    paused = 20_000 if quick else 300_000
    unknown = (200,) if quick else (500, 2_000)
    rows = []
    base = 201 + os.getpid() % 5  # above the test domains (1-200)
    with tempfile.TemporaryDirectory(prefix="hostile-bench-") as workdir:
        for k, (label, history) in enumerate((("KEEP_LAST 100", HistoryPolicy.KEEP_LAST),
                                              ("KEEP_ALL", HistoryPolicy.KEEP_ALL))):
            s = Session(workdir, base + k)
            try:
                before, mb = s.settled(), s.rss_mb()
                _pub, sent, seconds = _flood(s, flood, history)
                rows.append(_row(s, f"flood {flood:,} wrenches, {label}", sent, seconds, mb, before))
            finally:
                s.close()
        s = Session(workdir, base + 2)
        try:
            s.call("/pause_physics")
            before, mb = s.settled(), s.rss_mb()
            _pub, sent, seconds = _flood(s, paused, HistoryPolicy.KEEP_ALL, "/physics/ball/impulse")
            s.settled()
            s.call("/unpause_physics")
            rows.append(_row(s, f"{paused:,} impulses while paused, then unpause", sent, seconds, mb, before))
        finally:
            s.close()
        for k, n in enumerate(unknown):
            s = Session(workdir, base + 3 + k)
            try:
                from geometry_msgs.msg import WrenchStamped
                from msg_adapters import wrench_stamped
                before, mb = s.settled(), s.rss_mb()
                start = time.monotonic()
                pubs = [s.node.create_publisher(WrenchStamped, f"/physics/ghost{i}/wrench", 10) for i in range(n)]
                rate_during, gap_during = s.clock_after(5.0)
                for p in pubs:
                    p.publish(wrench_stamped((1.0, 0, 0)))
                row = _row(s, f"{n:,} publishers on unknown bodies", n, time.monotonic() - start, mb, before)
                row.update(sim_rate_during_discovery=round(rate_during, 3),
                           longest_clock_gap_during_discovery_s=round(gap_during, 3),
                           followed_topics=int(s.values()["unknown_body_topics"]))
                for p in pubs:
                    s.node.destroy_publisher(p)
                rows.append(row)
            finally:
                s.close()
    table = ["| row | sent | received | applied | dropped | RSS before → after (MB) | sim rate after | longest /clock gap (s) |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        dropped = ", ".join(f"{k} {n:,}" for k, n in r["dropped"].items()) or "0"
        table.append(f"| {r['row']} | {r['sent']:,} | {r['received']:,} | {r['applied']:,} | {dropped} | "
                     f"{r['rss_before_mb']} → {r['rss_after_mb']} | {r['sim_rate']} | {r['longest_clock_gap_s']} |")
    text = "\n".join(table) + "\n"
    if out:
        write_text(out, "hostile.md", text)
        write_json(out, "hostile.json", rows)
    print(text)
    return rows


if __name__ == "__main__":
    run(quick="--quick" in sys.argv)
