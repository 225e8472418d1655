"""A world of more bodies than `topics_on_demand_above` (physics_node/body_topics.py),
run as users run it: a separate `physics-node` process.

It has the fewest bodies that take the on-demand path (the default bound
plus one), starts without any per-body topic, steps, makes a body's odometry
publisher once someone subscribes and its wrench subscription once someone
publishes, and the held wrench accelerates the body by F/m. Every wait is
on a condition.
"""

import signal

import pytest
from test_node_support import Driver, NodeProcess

from diagnostic_msgs.msg import DiagnosticArray
from nav_msgs.msg import Odometry
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from std_srvs.srv import Empty, Trigger

from msg_adapters import diagnostic_values, state_from_odometry, time_ns, wrench_stamped
from physics_node.body_topics import ON_DEMAND_ABOVE

BODIES = ON_DEMAND_ABOVE + 1
DT = 0.01
MASS = 2.0
PUSHED = "b7"
CLOCK_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)


def scene_text():
    """BODIES free spheres at rest on a grid, no gravity: each stays put unless pushed."""
    lines = [f"dt: {DT}", "integrator: semi_implicit_euler", "bodies:"]
    for i in range(BODIES):
        lines += [
            f"  - name: b{i}",
            "    shape: {type: sphere, radius: 0.1}",
            f"    mass: {MASS}",
            f"    position: [{i % 20}.0, {i // 20}.0, 1.0]",
        ]
    return "\n".join(lines) + "\n"


@pytest.fixture(scope="module")
def large(tmp_path_factory):
    workdir = tmp_path_factory.mktemp("large")
    scene = workdir / "large.yaml"
    scene.write_text(scene_text())
    node = NodeProcess(["--scene", scene, "--rtf", "1"], workdir)
    driver = Driver("large_world")
    driver.listen(Clock, "/clock", CLOCK_QOS)
    driver.listen(DiagnosticArray, "/diagnostics")
    try:
        node.wait_until_up(60.0)
        yield node, driver
    finally:
        driver.close()
        node.stop()


def node_topics(driver):
    """The topics the node publishes or subscribes to, as this process's graph sees them."""
    from rclpy.node import NodeNameNonExistentError

    try:
        published = driver.node.get_publisher_names_and_types_by_node("physics", "/")
        subscribed = driver.node.get_subscriber_names_and_types_by_node("physics", "/")
    except NodeNameNonExistentError:  # not discovered yet
        return set()
    return {name for name, _ in published + subscribed}


def body_topics(driver):
    return {t for t in node_topics(driver) if t.count("/") == 3 and t.split("/")[2].startswith("b")}


def diagnostics(driver):
    box = driver.received["/diagnostics"]
    seen = len(box)
    driver.spin_until(lambda: len(box) > seen, 10.0, "a /diagnostics report")
    return diagnostic_values(box[-1])


def test_a_large_world_starts_stepping_without_per_body_topics(large):
    node, driver = large
    assert "made once a peer uses them" in node.log()
    clocks = driver.received["/clock"]
    driver.spin_until(lambda: clocks and time_ns(clocks[-1].clock) > 20 * DT * 1e9, 20.0, "/clock advancing")
    driver.spin_until(lambda: "/physics/poses" in node_topics(driver), 10.0, "the node's topics in the graph")
    assert body_topics(driver) == set()
    values = diagnostics(driver)
    assert values["bodies"] == str(BODIES)
    assert values["body_topics"] == "0"
    assert values["body_topics_on_demand"] == str(3 * BODIES)


def test_odometry_is_served_once_subscribed_and_a_wrench_once_published(large):
    node, driver = large
    odom = driver.listen(Odometry, f"/physics/{PUSHED}/odom")
    driver.spin_until(lambda: len(odom) >= 2, 20.0, f"/physics/{PUSHED}/odom made on demand")
    pos, _, vel, _ = state_from_odometry(odom[-1])
    assert list(pos) == [7.0, 0.0, 1.0] and not vel.any()  # at rest where the scene put it

    force = 3.0
    driver.call(Empty, "/pause_physics")
    pub = driver.wait_for_subscriber(type(wrench_stamped((0, 0, 0))), f"/physics/{PUSHED}/wrench", 20.0)
    driver.publish_acked(pub, wrench_stamped((force, 0, 0)))
    k = 5
    for _ in range(k):
        reply = driver.call(Trigger, "/physics/step")
        assert reply.success, reply.message
    last = int(reply.message.split()[1].rstrip(","))  # "step N, t = ..."

    def stepped():
        return odom and round(time_ns(odom[-1].header.stamp) / (DT * 1e9)) == last

    driver.spin_until(stepped, 10.0, f"the odometry of step {last}")
    # Semi-implicit Euler under a force held from rest, applied from the first
    # of the k steps: v = (F/m) k dt, in body axes = world axes (no turn).
    _, _, vel, _ = state_from_odometry(odom[-1])
    assert vel[0] == pytest.approx(force / MASS * k * DT, rel=1e-12)
    assert vel[1] == vel[2] == 0.0
    driver.call(Empty, "/unpause_physics")

    made = body_topics(driver)
    assert made == {f"/physics/{PUSHED}/odom", f"/physics/{PUSHED}/wrench"}, made
    values = diagnostics(driver)
    assert values["body_topics"] == "2" and values["body_topics_on_demand"] == str(3 * BODIES - 2)


def test_a_spawned_body_gets_its_topics_on_demand_and_a_deleted_one_loses_them(large):
    from simulation_interfaces import srv
    from simulation_interfaces.msg import Result

    node, driver = large
    request = srv.SpawnEntity.Request(name="late", entity_namespace="team")
    request.resource_string = f"shape: {{type: sphere, radius: 0.1}}\nmass: {MASS}\n"
    request.initial_pose.pose.position.x = -5.0
    reply = driver.call(srv.SpawnEntity, "/physics/spawn_entity", request=request)
    assert reply.result.result == Result.RESULT_OK, reply.result.error_message
    topic = "/physics/team/late/odom"
    assert not [t for t in node_topics(driver) if "/late/" in t]  # nothing made before a peer asks
    odom = driver.listen(Odometry, topic)
    driver.spin_until(lambda: odom, 20.0, f"{topic} made on demand")
    assert state_from_odometry(odom[-1])[0][0] == -5.0
    reply = driver.call(srv.DeleteEntity, "/physics/delete_entity", request=srv.DeleteEntity.Request(entity="late"))
    assert reply.result.result == Result.RESULT_OK, reply.result.error_message
    driver.spin_until(lambda: topic not in node_topics(driver), 10.0, f"{topic} gone with its body")


def test_odometry_all_is_refused_with_a_reason_on_a_large_world(large):
    from rcl_interfaces.srv import SetParameters
    from rclpy.parameter import Parameter

    node, driver = large
    request = SetParameters.Request(parameters=[Parameter("odometry", value="all").to_parameter_msg()])
    (result,) = driver.call(SetParameters, "/physics/set_parameters", request=request).results
    assert not result.successful
    assert "topics_on_demand_above" in result.reason


def test_a_large_world_stops_cleanly_on_sigint(large):
    node, driver = large
    node.signal(signal.SIGINT)
    assert node.wait() == 0, node.log()
    assert "Traceback" not in node.log()
