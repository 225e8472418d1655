"""The node as users run it: a separate `physics-node` process driven over ROS.

One node process serves the whole module; each test starts from a paused,
reset world, so the tests do not depend on one another.
"""

import math
import signal

import numpy as np
import pytest
from test_node_support import DEADLINE_SCALE, FREE_DT_NS, FREE_SCENE, Driver, NodeProcess

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PoseArray, WrenchStamped
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_srvs.srv import Empty, Trigger

from msg_adapters import arrays_from_pose_array, diagnostic_values, state_from_odometry, time_ns, wrench_stamped

DT = FREE_DT_NS / 1e9
CLOCK_QOS = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
BALL_MASS, BOX_MASS = 2.0, 4.0
BALL_START = np.array([0.0, 0.0, 1.0])
BOX_START = np.array([1.0, 0.0, 1.0])


@pytest.fixture(scope="module")
def sim(tmp_path_factory):
    workdir = tmp_path_factory.mktemp("node")
    scene = workdir / "free.yaml"
    scene.write_text(FREE_SCENE)
    node = NodeProcess(["--scene", scene, "--rtf", "2", "--paused"], workdir)
    driver = Driver()
    try:
        driver.listen(PoseArray, "/physics/poses")
        driver.listen(Odometry, "/physics/ball/odom")
        driver.listen(Odometry, "/physics/box/odom")
        driver.listen(Clock, "/clock", CLOCK_QOS)
        driver.listen(DiagnosticArray, "/diagnostics")
        driver.call(Trigger, "/physics/step", timeout=60.0)  # waits until the node is up (a condition, not a sleep)
        yield node, driver
    finally:
        driver.close()
        node.stop()


STATE_TOPICS = ("/clock", "/physics/poses", "/physics/ball/odom", "/physics/box/odom")


def stamp_of(msg):
    return time_ns(msg.clock if isinstance(msg, Clock) else msg.header.stamp)


def settle_reset(driver):
    """Wait until the reset's own messages (stamped 0) are the newest on every
    state topic, then empty the inboxes. Each topic arrives in the order it
    was sent, so whatever the node sent before the reset has come by then
    and cannot be mistaken for what a test steps next."""
    boxes = [driver.received[t] for t in STATE_TOPICS]
    driver.spin_until(lambda: all(box and stamp_of(box[-1]) == 0 for box in boxes), 10.0,
                      "the reset's messages on " + ", ".join(STATE_TOPICS))
    newest = {t: box[-1] for t, box in zip(STATE_TOPICS, boxes)}
    for box in driver.received.values():
        box.clear()
    return newest


def fresh(driver):
    """Paused, reset, nothing left in the inboxes."""
    driver.call(Empty, "/pause_physics")
    for box in driver.received.values():
        box.clear()
    driver.call(Empty, "/reset_simulation")
    settle_reset(driver)


def step(driver, n):
    for _ in range(n):
        reply = driver.call(Trigger, "/physics/step")
        assert reply.success, reply.message


def latest(driver, topic, stamp_ns=None, timeout=5.0):
    box = driver.received[topic]

    def arrived():
        return box and (stamp_ns is None or time_ns(box[-1].header.stamp) >= stamp_ns)

    driver.spin_until(arrived, timeout, f"{topic} at {stamp_ns} ns")
    return box[-1]


def send(driver, topic, force, torque=(0, 0, 0), frame="world"):
    """Publish a command and wait until the node has it (so the next step applies it)."""
    pub = driver.wait_for_subscriber(WrenchStamped, topic)
    driver.publish_acked(pub, wrench_stamped(force, torque, frame_id=frame))


def test_held_wrench_moves_body_by_f_over_m(sim):
    node, driver = sim
    fresh(driver)
    force = 4.0
    a = force / BALL_MASS
    send(driver, "/physics/ball/wrench", (force, 0, 0))
    k = 10
    step(driver, k)
    odom = latest(driver, "/physics/ball/odom", k * FREE_DT_NS)
    pos, _, vel, _ = state_from_odometry(odom)
    # Semi-implicit Euler under a constant force: v_k = a k dt, x_k = a dt² k(k+1)/2.
    assert vel[0] == pytest.approx(a * k * DT, abs=1e-12)
    assert pos[0] - BALL_START[0] == pytest.approx(a * DT**2 * k * (k + 1) / 2, abs=1e-12)
    assert np.allclose(pos[1:], BALL_START[1:], atol=1e-12)

    # Running at the fixed rate, the force stays held.
    driver.call(Empty, "/unpause_physics")
    poses = latest(driver, "/physics/poses", (k + 30) * FREE_DT_NS, timeout=20.0)
    driver.call(Empty, "/pause_physics")
    # any pose will do: its own stamp says how many steps the force has acted
    n = round(time_ns(poses.header.stamp) / FREE_DT_NS)
    assert n >= k + 30, "the node should have stepped while running"
    x = arrays_from_pose_array(poses)[0][0, 0] - BALL_START[0]
    assert x == pytest.approx(a * DT**2 * n * (n + 1) / 2, rel=1e-9)
    t = n * DT
    assert abs(x - 0.5 * a * t * t) <= 0.5 * a * DT * t + 1e-12  # ½ a t² up to the O(dt) integrator term


def test_impulse_changes_velocity_once(sim):
    node, driver = sim
    fresh(driver)
    impulse = 3.0
    send(driver, "/physics/ball/impulse", (0, 0, impulse))
    step(driver, 4)
    latest(driver, "/physics/ball/odom", 4 * FREE_DT_NS)
    odoms = [m for m in driver.received["/physics/ball/odom"] if time_ns(m.header.stamp) > 0]
    assert [round(time_ns(m.header.stamp) / FREE_DT_NS) for m in odoms] == [1, 2, 3, 4]
    for m in odoms:
        _, _, vel, _ = state_from_odometry(m)
        assert vel == pytest.approx([0, 0, impulse / BALL_MASS], abs=1e-12)
    heights = [state_from_odometry(m)[0][2] for m in odoms]
    assert np.diff(heights) == pytest.approx([impulse / BALL_MASS * DT] * 3, abs=1e-12)


def test_body_frame_wrench_pushes_along_the_body_axis(sim):
    node, driver = sim
    fresh(driver)
    # The box is turned 90° about z: its own x axis is world +y.
    send(driver, "/physics/box/wrench", (8.0, 0, 0), frame="box")
    k = 10
    step(driver, k)
    odom = latest(driver, "/physics/box/odom", k * FREE_DT_NS)
    pos, quat, vel, _ = state_from_odometry(odom)
    a = 8.0 / BOX_MASS
    assert pos[1] - BOX_START[1] == pytest.approx(a * DT**2 * k * (k + 1) / 2, abs=1e-12)
    assert pos[0] == pytest.approx(BOX_START[0], abs=1e-12)
    assert vel == pytest.approx([0, a * k * DT, 0], abs=1e-12)
    # Odometry's twist is in the body frame: along the box's own x.
    assert odom.twist.twist.linear.x == pytest.approx(a * k * DT, abs=1e-12)
    assert odom.twist.twist.linear.y == pytest.approx(0.0, abs=1e-12)


def test_pause_stops_clock_step_advances_one_dt_reset_restores(sim):
    node, driver = sim
    fresh(driver)
    step(driver, 3)
    clocks = driver.received["/clock"]
    driver.spin_until(lambda: clocks and time_ns(clocks[-1].clock) == 3 * FREE_DT_NS, 5.0, "clock at step 3")
    driver.spin_for(0.5)
    assert {time_ns(c.clock) for c in clocks} == {FREE_DT_NS, 2 * FREE_DT_NS, 3 * FREE_DT_NS}, "paused: no ticks"

    before = time_ns(clocks[-1].clock)
    step(driver, 1)
    driver.spin_until(lambda: time_ns(clocks[-1].clock) > before, 5.0, "clock after ~/step")
    assert time_ns(clocks[-1].clock) - before == FREE_DT_NS

    driver.call(Empty, "/unpause_physics")
    refused = driver.call(Trigger, "/physics/step")
    assert not refused.success and "paused" in refused.message
    driver.spin_until(lambda: time_ns(clocks[-1].clock) > before + 20 * FREE_DT_NS, 5.0, "clock while running")

    # a held force, seen acting before the reset, must be let go by it
    send(driver, "/physics/ball/wrench", (1.0, 0, 0))
    odoms = driver.received["/physics/ball/odom"]
    driver.spin_until(lambda: odoms and state_from_odometry(odoms[-1])[2][0] > 0, 5.0, "the force acting")
    driver.call(Empty, "/pause_physics")
    driver.call(Empty, "/reset_world")
    # order by stamps, not by arrival: the reset's own messages (stamped 0)
    # come after everything the running node sent before it, topic by topic
    poses = settle_reset(driver)["/physics/poses"]
    pos, quat = arrays_from_pose_array(poses)
    assert np.array_equal(pos, [BALL_START, BOX_START])
    assert quat[0] == pytest.approx([1, 0, 0, 0])
    step(driver, 1)
    odom = latest(driver, "/physics/ball/odom", FREE_DT_NS)
    assert time_ns(odom.header.stamp) == FREE_DT_NS
    assert state_from_odometry(odom)[2] == pytest.approx([0, 0, 0], abs=0), "reset let go of every command"


def test_bad_commands_are_dropped_counted_and_survived(sim):
    node, driver = sim
    fresh(driver)
    driver.call(Empty, "/unpause_physics")
    nan = wrench_stamped((math.nan, 0, 0))
    inf = wrench_stamped((0, 0, 0), (0, math.inf, 0))
    wrong_frame = wrench_stamped((1, 0, 0), frame_id="nowhere")
    unknown_body = wrench_stamped((1, 0, 0))
    ball = driver.wait_for_subscriber(WrenchStamped, "/physics/ball/wrench")
    ball_impulse = driver.wait_for_subscriber(WrenchStamped, "/physics/ball/impulse")
    nobody = driver.publisher(WrenchStamped, "/physics/nobody/wrench")

    diagnostics = driver.received["/diagnostics"]

    def counted():
        ball.publish(nan)
        ball_impulse.publish(inf)
        ball.publish(wrong_frame)
        nobody.publish(unknown_body)
        if not diagnostics:
            return False
        values = diagnostic_values(diagnostics[-1])
        return (
            int(values["dropped_non_finite"]) >= 2
            and int(values["dropped_unknown_frame"]) >= 1
            and int(values["dropped_unknown_body"]) >= 1
        )

    driver.spin_until(counted, 15.0, "the drops to show in /diagnostics")
    values = diagnostic_values(diagnostics[-1])
    assert int(values["dropped_commands"]) >= 4
    assert any(m.status[0].level == DiagnosticStatus.WARN for m in diagnostics), "drops raise a warning level"
    for key in ("real_time_factor", "step_time_ms", "bodies", "contacts"):
        assert key in values
    assert values["bodies"] == "2"
    assert node.alive()
    # Still stepping, and none of the bad commands moved the ball.
    clocks = driver.received["/clock"]
    t = time_ns(clocks[-1].clock)
    driver.spin_until(lambda: time_ns(clocks[-1].clock) > t, 5.0, "clock still ticking")
    odom = latest(driver, "/physics/ball/odom")
    assert state_from_odometry(odom)[2] == pytest.approx([0, 0, 0], abs=0)
    assert "dropped a command" in node.log()


def test_a_torque_beyond_the_bound_is_dropped_not_a_halt(sim):
    """Regression: a finite torque of 1e308 N·m used to spin the ball into NaN
    and halt the whole world until a reset; beyond command_limits it is now
    dropped as out_of_range before it is queued, and the world steps on."""
    node, driver = sim
    fresh(driver)
    send(driver, "/physics/ball/wrench", (0, 0, 0), (0, 0, 1e308))
    for _ in range(5):
        reply = driver.call(Trigger, "/physics/step")
        assert reply.success, reply.message
    diagnostics = driver.received["/diagnostics"]
    driver.spin_until(
        lambda: diagnostics and int(diagnostic_values(diagnostics[-1])["dropped_out_of_range"]) >= 1,
        5.0,
        "the out-of-range drop in /diagnostics",
    )
    odom = latest(driver, "/physics/ball/odom", 5 * FREE_DT_NS)
    assert state_from_odometry(odom)[3] == pytest.approx([0, 0, 0], abs=0)  # never spun
    assert node.alive()


def _set(driver, **values):
    from rcl_interfaces.srv import SetParameters
    from rclpy.parameter import Parameter

    request = SetParameters.Request(parameters=[Parameter(k, value=v).to_parameter_msg() for k, v in values.items()])
    return [r.successful for r in driver.call(SetParameters, "/physics/set_parameters", request=request).results]


def test_parameters_change_while_running_and_bad_values_are_refused(sim):
    node, driver = sim
    fresh(driver)
    assert _set(driver, real_time_factor=-1.0) == [False]
    assert _set(driver, publish_every=0) == [False]
    assert _set(driver, scene="/elsewhere.yaml") == [False]  # read-only while running
    assert _set(driver, real_time_factor=0, publish_every=5) == [True, True]  # an integer is fine
    clocks = driver.received["/clock"]
    assert _set(driver, paused=False) == [True]
    driver.spin_until(lambda: clocks and time_ns(clocks[-1].clock) > 50 * FREE_DT_NS, 5.0, "fast steps")
    assert _set(driver, paused=True, real_time_factor=2.0, publish_every=1) == [True, True, True]
    driver.spin_for(0.3)
    stamps = {time_ns(m.header.stamp) // FREE_DT_NS for m in driver.received["/physics/poses"]}
    assert stamps and all(k % 5 == 0 for k in stamps if k > 1)


def test_bodies_topic_is_latched_with_one_marker_per_body(sim):
    from visualization_msgs.msg import Marker, MarkerArray

    node, driver = sim
    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    box = driver.listen(MarkerArray, "/physics/bodies", latched)
    driver.spin_until(lambda: box, 10.0, "latched ~/bodies")
    markers = box[-1].markers
    assert [(m.id, m.ns, m.text) for m in markers] == [(0, "ball", "ball"), (1, "box", "box")]
    assert markers[0].type == Marker.SPHERE and markers[0].scale.x == pytest.approx(0.2)
    assert markers[1].type == Marker.CUBE and markers[1].scale.x == pytest.approx(0.4)


def test_push_and_follow_example_moves_the_body(sim):
    node, driver = sim
    fresh(driver)
    driver.call(Empty, "/unpause_physics")
    example = NodeProcess(["--body", "ball", "--force", "2", "0", "0", "--seconds", "0.3"], node.log_path.parent,
                          module="examples.push_and_follow")
    try:
        assert example.wait(30.0) == 0, example.log()
    finally:
        example.stop()
    lines = [line for line in example.log().splitlines() if line.startswith("t=")]
    assert lines, example.log()
    assert "+0.0000, +0.0000, +1.0000" not in lines[-1], "the ball should have moved along x:\n" + example.log()
    # and the node agrees: pushed and let go, the ball coasts along +x only
    odoms = driver.received["/physics/ball/odom"]
    driver.spin_until(lambda: odoms and state_from_odometry(odoms[-1])[2][0] > 0, 10.0, "the ball moving")
    _, _, vel, _ = state_from_odometry(odoms[-1])
    assert vel[1] == 0 and vel[2] == 0


def test_the_printed_one_liner_pushes_the_ball(sim):
    import subprocess

    from test_node_support import REPO, node_env

    node, driver = sim
    fresh(driver)
    log = node.log()
    assert "ros2 topic pub --once /physics/ball/impulse" in log
    one_liner = next(line.strip() for line in log.splitlines() if '-c "import rclpy' in line)
    # the one-liner returns once the node has acknowledged its impulse
    subprocess.run(one_liner, shell=True, cwd=REPO, env=node_env(), check=True, timeout=30 * DEADLINE_SCALE)
    step(driver, 1)
    odom = latest(driver, "/physics/ball/odom", FREE_DT_NS)
    assert state_from_odometry(odom)[2] == pytest.approx([2.0 / BALL_MASS, 0, 3.0 / BALL_MASS], abs=1e-12)


def test_sigterm_stops_the_node_cleanly(tmp_path):
    scene = tmp_path / "free.yaml"
    scene.write_text(FREE_SCENE)
    with NodeProcess(["--scene", scene, "--rtf", "0"], tmp_path, isolated=True) as node:
        node.wait_until_up()
        node.signal(signal.SIGTERM)
        assert node.wait() == 0, node.log()
        assert "SIGTERM: stopping" in node.log()


def test_unreadable_scene_exits_with_a_message(tmp_path):
    missing = tmp_path / "nope.yaml"
    with NodeProcess(["--scene", missing], tmp_path, isolated=True) as node:
        assert node.wait() == 2
        assert "nope.yaml" in node.log()


def test_two_runs_at_once_never_share_a_ros_domain(tmp_path):
    """Regression (two test runs shared a ROS domain): the domain came from the
    pid modulo 100, and a run once read another run's 10,000-body
    `/physics/bodies` as its own node's. A domain is now held by a lock that
    a second reservation cannot take, until every process holding it is gone
    (a node started by NodeProcess holds it too)."""
    import subprocess
    import sys

    from test_node_support import DOMAINS, reserve_domain

    first, lock = reserve_domain(str(tmp_path))
    taken = [reserve_domain(str(tmp_path)) for _ in range(DOMAINS - 1)]
    assert len({first, *(d for d, _ in taken)}) == DOMAINS
    with pytest.raises(RuntimeError, match="held by other test runs"):
        reserve_domain(str(tmp_path))
    for _, other in taken:
        other.close()
    # a child holding the lock keeps the domain after this process lets go
    child = subprocess.Popen([sys.executable, "-c", "import sys; sys.stdin.read()"],
                             stdin=subprocess.PIPE, pass_fds=(lock.fileno(),))
    try:
        lock.close()
        again, held = reserve_domain(str(tmp_path))
        assert again != first
        held.close()
    finally:
        child.communicate(b"")
    again, held = reserve_domain(str(tmp_path))      # free once the child has exited
    held.close()
    assert again == first
