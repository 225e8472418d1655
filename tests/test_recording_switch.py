"""`record` pointed at a new file while the node runs (issue 11 §5), with the
node in a separate process: `ros2 param set /physics record B.mcap` closes
the recording so far complete and starts B, which opens in the `mcap` and
`rosbags` readers and re-simulates bit for bit although it starts
mid-session (the node's history since the last reset is attached to it,
physics_node/session_history.py). A path `--record` would refuse is refused
with the reason and the node runs on; after a write fault the node records
into a new file again. Waits are on conditions.
"""

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from mcap.reader import make_reader
from rosbags.highlevel import AnyReader
from test_node_support import REPO, Driver, NodeProcess, node_env, run_cli

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import WrenchStamped
from rcl_interfaces.srv import SetParameters
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock

from msg_adapters import diagnostic_values, time_ns, wrench_stamped
from physics_node.recording_reader import Recording
from physics_node.session_history import HISTORY_NAME, STARTED_AT_STEP

DT = 0.01
# A ball and a box on the ground with contacts: warm starts, sleep timers and
# a held wrench carry over the switch, so B only re-simulates if the history
# rebuilds all of it.
SCENE = f"""\
dt: {DT}
gravity: earth
effects:
  contacts: {{iterations: 8}}
bodies:
  - name: ground
    shape: {{type: plane, normal: [0, 0, 1], offset: 0.0}}
  - name: ball
    shape: {{type: sphere, radius: 0.1}}
    mass: 1.0
    position: [0, 0, 0.3]
  - name: box
    shape: {{type: box, half_extents: [0.2, 0.2, 0.2]}}
    mass: 4.0
    position: [1, 0, 0.2]
"""
CLOCK_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)


def set_param(driver, **values):
    request = SetParameters.Request(parameters=[Parameter(k, value=v).to_parameter_msg() for k, v in values.items()])
    return driver.call(SetParameters, "/physics/set_parameters", request=request).results


def sim_time(driver):
    clocks = driver.received["/clock"]
    return time_ns(clocks[-1].clock) if clocks else -1


def run_until(driver, sim_ns, what):
    driver.spin_until(lambda: sim_time(driver) >= sim_ns, 30.0, what)


def push(driver, body, kind, force):
    pub = driver.wait_for_subscriber(WrenchStamped, f"/physics/{body}/{kind}")
    driver.publish_acked(pub, wrench_stamped(force))


def pose_steps(path):
    return [m.sequence for m in Recording(path).messages() if m.topic == "/physics/poses"]


def assert_opens_in_both_readers(path):
    with open(path, "rb") as f:
        assert sum(1 for _ in make_reader(f).iter_messages()) > 0
    with AnyReader([Path(path)]) as reader:
        poses = [c for c in reader.connections if c.topic == "/physics/poses"]
        decoded = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages(connections=poses)]
    assert decoded and all(len(m.poses) == 3 for m in decoded)


def assert_resimulates(path):
    result = run_cli("physics_node.replay", [path, "--resimulate"], timeout=120.0)
    assert result.returncode == 0 and result.stdout.startswith("match"), result.stdout + result.stderr
    return result.stdout


@pytest.fixture()
def node(tmp_path):
    scene = tmp_path / "switch.yaml"
    scene.write_text(SCENE)
    proc = NodeProcess(["--scene", scene, "--rtf", "1", "--record", tmp_path / "a.mcap"], tmp_path)
    driver = Driver("recording_switch")
    driver.listen(Clock, "/clock", CLOCK_QOS)
    driver.listen(DiagnosticArray, "/diagnostics")
    try:
        proc.wait_until_up(60.0)
        yield proc, driver
    finally:
        driver.close()
        proc.stop()


def test_record_switched_mid_run_leaves_two_files_that_each_resimulate(node, tmp_path):
    proc, driver = node
    a, b = tmp_path / "a.mcap", tmp_path / "b.mcap"
    push(driver, "ball", "impulse", (0.5, 0, 2.0))
    push(driver, "box", "wrench", (6.0, 0, 0))  # held across the switch
    run_until(driver, int(0.5e9), "half a second of sim time")
    (result,) = set_param(driver, record=str(b))
    assert result.successful, result.reason
    switched = sim_time(driver)
    push(driver, "ball", "impulse", (-0.3, 0.2, 1.0))
    run_until(driver, switched + int(0.5e9), "half a second after the switch")

    folder = tmp_path / "a_folder"
    folder.mkdir()
    for bad in (folder, "/proc/no/such/x.mcap", b):
        (result,) = set_param(driver, record=str(bad))
        assert not result.successful and result.reason.startswith("record:"), (bad, result.reason)
    run_until(driver, sim_time(driver) + int(0.2e9), "stepping after the refusals")
    values = diagnostic_values(driver.received["/diagnostics"][-1])
    assert values["recording"] == str(b) and values["recording_error"] == ""

    proc.signal(signal.SIGINT)
    assert proc.wait() == 0, proc.log()
    assert Recording(a).complete and Recording(b).complete
    steps_a, steps_b = pose_steps(a), pose_steps(b)
    assert steps_a[0] == 0 and steps_b[0] > 0  # B starts mid-session...
    assert steps_b[0] <= steps_a[-1] + 1  # ...where A stopped
    assert int(Recording(b).metadata["physics_node"][STARTED_AT_STEP]) == steps_b[0] - 1
    assert Recording(b).attachment(name=HISTORY_NAME) is not None
    for path in (a, b):
        assert_opens_in_both_readers(path)
        assert_resimulates(path)


def test_record_set_to_nothing_stops_and_a_new_file_starts_after_a_write_fault(tmp_path):
    """RLIMIT_FSIZE (as `ulimit -f`) fails the writes past 200 kB as a full
    disk would; the node, running as fast as it can, faults recording A, is
    slowed to real time and pointed at B, which stays under the limit."""
    scene = tmp_path / "switch.yaml"
    scene.write_text(SCENE)
    a, b = tmp_path / "a.mcap", tmp_path / "b.mcap"
    limit = 200_000
    log_path = tmp_path / "node.log"

    def small_files():
        import resource

        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    log = open(log_path, "wb")
    proc = subprocess.Popen(
        [sys.executable, "-m", "physics_node.main", "--scene", scene, "--record", a, "--rtf", "0"],
        cwd=REPO, env=node_env(), stdout=log, stderr=subprocess.STDOUT, preexec_fn=small_files,
        start_new_session=True,
    )
    driver = Driver("recording_fault")
    driver.listen(Clock, "/clock", CLOCK_QOS)
    driver.listen(DiagnosticArray, "/diagnostics")
    try:
        driver.spin_until(lambda: "stopped:" in log_path.read_text(errors="replace"), 90.0, "the write fault")
        driver.spin_until(lambda: driver.received["/diagnostics"] and diagnostic_values(
            driver.received["/diagnostics"][-1])["recording_error"], 10.0, "the fault in /diagnostics")
        assert [r.successful for r in set_param(driver, real_time_factor=1.0, record=str(b))] == [True, True]
        push(driver, "ball", "impulse", (0.2, 0, 1.0))
        run_until(driver, sim_time(driver) + int(0.3e9), "stepping into B")
        (result,) = set_param(driver, record="")
        assert result.successful, result.reason
        driver.spin_until(lambda: diagnostic_values(driver.received["/diagnostics"][-1])["recording"] == "",
                          10.0, "no recording in /diagnostics")
        assert proc.poll() is None, log_path.read_text(errors="replace")[-3000:]
    finally:
        driver.close()
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGINT)
        status = proc.wait(60)
        log.close()
    assert status == 0, log_path.read_text(errors="replace")[-3000:]
    assert os.path.getsize(b) < limit and Recording(b).complete
    assert "Traceback" not in log_path.read_text(errors="replace")
    assert_opens_in_both_readers(b)
    assert_resimulates(b)
