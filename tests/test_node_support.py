"""Shared helpers for the node tests: start `physics-node` as a separate
process and drive it from this one. Holds no tests itself.

Every test run uses its own ROS domain and localhost-only discovery, so
parallel runs and other ROS traffic do not mix: the domain is one no other
test process on this machine holds (a lock file per domain), not one taken
from the pid, which two runs at once shared one time in a hundred (a node
test then read another run's 10,000-body `/physics/bodies`).
"""

import fcntl
import os
import tempfile
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from physics_node.dds_profile import use_reply_profile

REPO = Path(__file__).resolve().parents[1]
# Every wait here is on a condition; its deadline only bounds a hang, so it
# can be generous without slowing a passing run. A 2-core machine shared with
# other work runs these processes several times slower than an idle one (a
# replay's re-simulation took over 60 s beside a CPU hog and six other jobs),
# so each deadline a test states is stretched by this factor.
DEADLINE_SCALE = float(os.environ.get("PHYSICS_TEST_DEADLINE_SCALE", "5"))
DOMAINS = 100          # test domains 1-100; each one's isolated twin is 101-200


def reserve_domain(folder=None):
    """(domain id, the open lock file) of the first test domain from a
    pid-dependent start whose lock no other process holds. The lock (flock)
    lasts while the file stays open, and the kernel drops it when the
    process ends however it ends, so a killed run never leaves one behind."""
    folder = folder or os.path.join(tempfile.gettempdir(), "physics-test-domains")
    os.makedirs(folder, exist_ok=True)
    start = os.getpid() % DOMAINS
    for k in range(DOMAINS):
        domain = 1 + (start + k) % DOMAINS
        try:
            lock = open(os.path.join(folder, f"{domain}.lock"), "a")
        except OSError:            # another user's lock file
            continue
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            lock.close()
            continue
        return str(domain), lock
    raise RuntimeError(f"all {DOMAINS} test ROS domains are held by other test runs ({folder})")


if os.environ.get("PHYSICS_TEST_DOMAIN_ID"):
    DOMAIN_ID, DOMAIN_LOCK = os.environ["PHYSICS_TEST_DOMAIN_ID"], None
else:
    DOMAIN_ID, DOMAIN_LOCK = reserve_domain()   # held for this process's life
os.environ["ROS_DOMAIN_ID"] = DOMAIN_ID
ISOLATED_DOMAIN_ID = str(int(DOMAIN_ID) + 100)
os.environ.setdefault("RMW_IMPLEMENTATION", "rmw_fastrtps_cpp")
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
# The node's own Fast DDS profile (service replies wait up to 5 s for the
# caller's reader), set here before any rclpy.init in this process: the
# drivers' services answer like the node's, and every node this process
# starts inherits the same variables.
use_reply_profile()

import rclpy  # noqa: E402  (the environment above must be set first)
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy  # noqa: E402

# Two free bodies (no gravity, no contacts): the box is turned 90° about z,
# so its body x axis points along world +y.
FREE_SCENE = """\
dt: 0.01
integrator: semi_implicit_euler
bodies:
  - name: ball
    shape: {type: sphere, radius: 0.1}
    mass: 2.0
    position: [0, 0, 1]
  - name: box
    shape: {type: box, half_extents: [0.2, 0.1, 0.1]}
    mass: 4.0
    position: [1, 0, 1]
    orientation: [0.7071067811865476, 0, 0, 0.7071067811865476]
"""
FREE_DT_NS = 10_000_000

LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
STREAM = QoSProfile(depth=50, reliability=ReliabilityPolicy.RELIABLE)


def node_env(domain_id=None):
    env = dict(os.environ)
    if domain_id is not None:
        env["ROS_DOMAIN_ID"] = str(domain_id)
    env["PYTHONPATH"] = os.pathsep.join([str(REPO), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    env["PYTHONUNBUFFERED"] = "1"
    return env


class NodeProcess:
    """`python -m physics_node.main ARGS` in its own process group."""

    def __init__(self, args, workdir, module="physics_node.main", isolated=False):
        # isolated: a domain of its own, for a process no test node talks to,
        # so it cannot disturb a node another test is driving.
        self.log_path = Path(workdir) / f"node-{time.monotonic_ns()}.log"
        self._log = open(self.log_path, "wb")
        self.proc = subprocess.Popen(
            [sys.executable, "-m", module, *map(str, args)],
            cwd=REPO,
            env=node_env(ISOLATED_DOMAIN_ID if isolated else None),
            stdout=self._log,
            stderr=subprocess.STDOUT,
            start_new_session=True,
            # the node holds the domain's lock too: a node that outlives this
            # run (it is in a session of its own) keeps its domain from the next
            pass_fds=() if DOMAIN_LOCK is None else (DOMAIN_LOCK.fileno(),),
        )

    def alive(self):
        return self.proc.poll() is None

    def log(self):
        if not self._log.closed:
            self._log.flush()
        return self.log_path.read_text(errors="replace")

    def wait_for_log(self, text, timeout=20.0):
        """Wait until the node has printed `text` (it prints how to push a body
        once it is up)."""
        end = time.monotonic() + timeout * DEADLINE_SCALE
        while time.monotonic() < end:
            if text in self.log():
                return
            if not self.alive():
                pytest.fail(f"node exited with {self.proc.returncode}; log:\n{self.log()}")
            time.sleep(0.05)
        pytest.fail(f"node never printed {text!r}; log:\n{self.log()}")

    def wait_until_up(self, timeout=20.0):
        self.wait_for_log("Push '", timeout)

    def signal(self, sig):
        if self.alive():
            os.kill(self.proc.pid, sig)

    def wait(self, timeout=15.0):
        try:
            return self.proc.wait(timeout * DEADLINE_SCALE)
        except subprocess.TimeoutExpired:
            pytest.fail(f"node did not exit within {timeout * DEADLINE_SCALE} s; log:\n{self.log()}")

    def stop(self):
        """Make sure the process is gone (used in finally blocks)."""
        if self.alive():
            self.signal(signal.SIGINT)
            try:
                self.proc.wait(5.0)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(5.0)
        self._log.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stop()


def run_cli(module, args, timeout=60.0):
    """Run a module's CLI to completion; returns CompletedProcess (text)."""
    return subprocess.run(
        [sys.executable, "-m", module, *map(str, args)],
        cwd=REPO,
        env=node_env(),
        capture_output=True,
        text=True,
        timeout=timeout * DEADLINE_SCALE,
    )


class Driver:
    """A node in the test process that publishes commands, calls services and
    keeps what it receives."""

    def __init__(self, name="test_driver"):
        if not rclpy.ok():
            rclpy.init()
        self.node = rclpy.create_node(f"{name}_{os.getpid()}_{time.monotonic_ns()}")
        self.executor = SingleThreadedExecutor()
        self.executor.add_node(self.node)
        self.received = {}
        self._publishers = {}
        self._clients = {}

    def close(self):
        self.executor.remove_node(self.node)
        self.node.destroy_node()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # -- topics -------------------------------------------------------------
    def listen(self, msg_type, topic, qos=STREAM):
        box = self.received.setdefault(topic, [])
        self.node.create_subscription(msg_type, topic, box.append, qos)
        return box

    def publisher(self, msg_type, topic):
        pub = self._publishers.get(topic)
        if pub is None:
            pub = self.node.create_publisher(msg_type, topic, 100)
            self._publishers[topic] = pub
        return pub

    def publish_acked(self, pub, msg, timeout=10.0):
        """Publish and return once every matched subscriber has acknowledged
        the message (reliable delivery): the node has it before anything this
        process sends next, e.g. a ~/step request (its executor takes
        callbacks in the order their messages arrived)."""
        from rclpy.duration import Duration

        pub.publish(msg)
        timeout *= DEADLINE_SCALE
        if not pub.wait_for_all_acked(Duration(seconds=timeout)):
            pytest.fail(f"{pub.topic_name}: the message was not acknowledged within {timeout} s")

    def wait_for_subscriber(self, msg_type, topic, timeout=10.0):
        pub = self.publisher(msg_type, topic)
        self.spin_until(lambda: pub.get_subscription_count() > 0, timeout, f"no subscriber on {topic}")
        return pub

    def spin_for(self, seconds):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.executor.spin_once(timeout_sec=0.01)

    def spin_until(self, predicate, timeout=10.0, what="condition"):
        timeout *= DEADLINE_SCALE
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if predicate():
                return
            self.executor.spin_once(timeout_sec=0.01)
        if predicate():
            return
        pytest.fail(f"timed out after {timeout} s waiting for {what}")

    # -- services -------------------------------------------------------------
    def call(self, srv_type, name, timeout=10.0, request=None):
        future = self.send_request(srv_type, name, timeout, request)
        self.spin_until(future.done, timeout, f"reply from {name}")
        return future.result()

    def send_request(self, srv_type, name, timeout=10.0, request=None):
        """Send a request once the service is there; returns the reply's future.
        For a request that makes the node exit at once (unpausing a run with a
        --duration), whose reply may leave with the process: wait on the exit."""
        client = self._clients.get(name)
        if client is None:
            client = self.node.create_client(srv_type, name)
            self._clients[name] = client
        self.spin_until(client.service_is_ready, timeout, f"service {name}")
        return client.call_async(request if request is not None else srv_type.Request())
