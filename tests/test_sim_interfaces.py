"""The simulator standard (simulation_interfaces) and /tf, as a client of the
standard sees them: a separate `physics-node` process driven from here
through the standard's services and action. One node process (recording)
serves the module; each test starts from a paused world reset with
ResetSimulation SCOPE_ALL."""

import numpy as np
import pytest
from test_node_support import FREE_DT_NS, FREE_SCENE, LATCHED, Driver, NodeProcess, run_cli

from geometry_msgs.msg import PoseArray, WrenchStamped
from rclpy.action import ActionClient
from rclpy.qos import QoSProfile, ReliabilityPolicy
from simulation_interfaces import srv
from simulation_interfaces.action import SimulateSteps
from simulation_interfaces.msg import EntityFilters, EntityState, Result, SimulationState, SimulatorFeatures, SpawnEntity
from tf2_msgs.msg import TFMessage
from visualization_msgs.msg import MarkerArray

from msg_adapters import arrays_from_pose_array, time_ns
from physics_core import load_scene

NS = "/physics"
# test_node_support's free scene with gravity and a static ground (no contacts: free fall)
SCENE = FREE_SCENE.replace("integrator: semi_implicit_euler\n", "integrator: semi_implicit_euler\ngravity: earth\n") + """\
  - name: ground
    shape: {type: plane, normal: [0, 0, 1], offset: 0.0}
    static: true
"""
BOX = "name: crate\nshape: {type: box, half_extents: [0.1, 0.2, 0.3]}\nmass: 3.0\n"
OK = Result.RESULT_OK


@pytest.fixture(scope="module")
def sim(tmp_path_factory):
    workdir = tmp_path_factory.mktemp("sim_interfaces")
    scene = workdir / "free.yaml"
    scene.write_text(SCENE)
    recording = workdir / "session.mcap"
    node = NodeProcess(["--scene", scene, "--rtf", "1", "--paused", "--record", recording], workdir)
    driver = Driver("sim_client")
    try:
        driver.listen(PoseArray, f"{NS}/poses")
        driver.listen(TFMessage, "/tf")
        driver.listen(TFMessage, "/tf_static", LATCHED)
        driver.listen(MarkerArray, f"{NS}/bodies", LATCHED)
        call(driver, "get_simulator_features", timeout=60.0)  # waits until the node is up
        call(driver, "step_simulation", timeout=120.0)  # a cold kernel cache compiles on the first step
        yield node, driver, recording
    finally:
        driver.close()
        node.stop()


def call(driver, service, timeout=10.0, **fields):
    kind = getattr(srv, "".join(part.capitalize() for part in service.split("_")))
    return driver.call(kind, f"{NS}/{service}", timeout=timeout, request=kind.Request(**fields))


def fresh(driver):
    reply = call(driver, "reset_simulation", scope=255)
    assert reply.result.result == OK, reply.result.error_message
    driver.spin_for(0.1)
    for box in driver.received.values():
        if box is not driver.received["/tf_static"] and box is not driver.received[f"{NS}/bodies"]:
            box.clear()


def spawn(driver, text=BOX, name="", z=2.0, frame="", **fields):
    request = {"name": name, "resource_string": text, **fields}
    reply = call(driver, "spawn_entity", **request, initial_pose=_pose_stamped(frame, z))
    return reply


def _pose_stamped(frame, z):
    from geometry_msgs.msg import PoseStamped

    p = PoseStamped()
    p.header.frame_id = frame
    p.pose.position.z = z
    return p


def entity_state(driver, name):
    reply = call(driver, "get_entity_state", entity=name)
    assert reply.result.result == OK, reply.result.error_message
    return reply.state


def vec(v):
    return np.array([v.x, v.y, v.z])


def test_features_list_what_is_supported_and_the_spawn_format(sim):
    _, driver, _ = sim
    f = call(driver, "get_simulator_features").features
    assert f.spawn_formats == ["physics_node/body"]
    for feature in (SimulatorFeatures.SPAWNING, SimulatorFeatures.DELETING, SimulatorFeatures.STEP_SIMULATION_ACTION,
                    SimulatorFeatures.ENTITY_STATE_SETTING, SimulatorFeatures.SIMULATION_RESET_SPAWNED):  # fmt: skip
        assert feature in f.features
    assert SimulatorFeatures.NAMED_POSES not in f.features  # not offered, so not claimed


def test_spawned_box_falls_bit_for_bit_as_physics_core_computes(sim):
    _, driver, _ = sim
    fresh(driver)
    reply = spawn(driver, z=2.5)
    assert reply.result.result == OK, reply.result.error_message
    assert reply.entity_name == "crate"
    assert call(driver, "step_simulation", steps=240).result.result == OK
    state = entity_state(driver, "crate")

    world = load_scene(_scene_dict())
    world.add_body({"name": "crate", "shape": {"type": "box", "half_extents": [0.1, 0.2, 0.3]}, "mass": 3.0,
                    "position": [0.0, 0.0, 2.5], "orientation": [1.0, 0.0, 0.0, 0.0]})  # fmt: skip
    world.step(240)
    b = world.body("crate")
    assert np.array_equal(vec(state.pose.position), b.position)
    assert np.array_equal(vec(state.twist.linear), b.velocity)
    assert time_ns(state.header.stamp) == 240 * FREE_DT_NS


def _scene_dict():
    import yaml

    return yaml.safe_load(SCENE)


def test_step_simulation_returns_after_exactly_n_steps(sim):
    _, driver, _ = sim
    fresh(driver)
    call(driver, "step_simulation", steps=7)
    before = entity_state(driver, "ball").header.stamp
    reply = call(driver, "step_simulation", steps=100)
    assert reply.result.result == OK
    after = entity_state(driver, "ball").header.stamp
    assert time_ns(after) - time_ns(before) == 100 * FREE_DT_NS


def test_set_state_teleports_and_the_next_step_starts_from_it(sim):
    _, driver, _ = sim
    fresh(driver)
    target = EntityState()
    target.pose.position.x, target.pose.position.y, target.pose.position.z = 5.0, -1.0, 3.0
    target.twist.linear.x = 2.0
    target.twist.angular.z = 0.5
    assert call(driver, "set_entity_state", entity="ball", state=target).result.result == OK
    now = entity_state(driver, "ball")
    assert vec(now.pose.position).tolist() == [5.0, -1.0, 3.0]
    assert vec(now.twist.angular).tolist() == [0.0, 0.0, 0.5]
    call(driver, "step_simulation", steps=1)
    after = entity_state(driver, "ball")
    dt = FREE_DT_NS / 1e9
    # semi-implicit Euler with no gravity in this scene: x += v dt
    assert after.pose.position.x == 5.0 + 2.0 * dt


def test_state_in_a_body_frame(sim):
    _, driver, _ = sim
    fresh(driver)
    reply = spawn(driver, name="on_box", frame="box", z=0.5)
    assert reply.result.result == OK, reply.result.error_message
    s = entity_state(driver, "on_box")
    # the box sits at (1, 0, 1) turned 90° about z: its own +z is the world's +z
    assert vec(s.pose.position) == pytest.approx([1.0, 0.0, 1.5], abs=1e-12)


def test_delete_removes_the_topics_and_the_poses_row(sim):
    _, driver, _ = sim
    fresh(driver)
    assert spawn(driver).result.result == OK
    driver.spin_until(lambda: _has_topic(driver, f"{NS}/crate/wrench"), 10.0, "crate's wrench topic")
    call(driver, "step_simulation", steps=1)
    driver.spin_until(lambda: _rows(driver) == 4, 5.0, "4 pose rows")
    bodies = driver.received[f"{NS}/bodies"]
    driver.spin_until(lambda: bodies and [m.ns for m in bodies[-1].markers] == ["ball", "box", "ground", "crate"], 5.0, "body list")

    assert call(driver, "delete_entity", entity="crate").result.result == OK
    call(driver, "step_simulation", steps=1)
    driver.spin_until(lambda: _rows(driver) == 3, 5.0, "3 pose rows")
    driver.spin_until(lambda: not _has_topic(driver, f"{NS}/crate/wrench"), 10.0, "crate's topics gone")
    driver.spin_until(lambda: [m.ns for m in bodies[-1].markers if m.action == 0] == ["ball", "box", "ground"], 5.0, "body list")
    assert call(driver, "get_entities").entities == ["ball", "box", "ground"]


def _has_topic(driver, topic):
    return topic in dict(driver.node.get_topic_names_and_types())


def _rows(driver):
    box = driver.received[f"{NS}/poses"]
    return len(arrays_from_pose_array(box[-1])[0]) if box else -1


def test_tf_carries_every_dynamic_body_with_sim_time(sim):
    _, driver, _ = sim
    fresh(driver)
    assert spawn(driver).result.result == OK
    call(driver, "step_simulation", steps=3)
    tf = driver.received["/tf"]
    driver.spin_until(lambda: tf and time_ns(tf[-1].transforms[0].header.stamp) == 3 * FREE_DT_NS, 5.0, "/tf at step 3")
    last = tf[-1]
    assert [t.child_frame_id for t in last.transforms] == ["ball", "box", "crate"]
    assert {t.header.frame_id for t in last.transforms} == {"world"}
    static = driver.received["/tf_static"]
    driver.spin_until(lambda: static and [t.child_frame_id for t in static[-1].transforms] == ["ground"], 5.0, "/tf_static")
    crate = entity_state(driver, "crate")
    assert vec(last.transforms[2].transform.translation).tolist() == vec(crate.pose.position).tolist()


def test_simulate_steps_action_feedback_and_cancel(sim):
    _, driver, _ = sim
    fresh(driver)
    deep = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
    client = ActionClient(driver.node, SimulateSteps, f"{NS}/simulate_steps", feedback_sub_qos_profile=deep)
    try:
        assert client.wait_for_server(10.0)
        # the feedback topic is matched apart from the action's services: a
        # first short goal makes sure it is before the counted one
        topic = f"{NS}/simulate_steps/_action/feedback"
        driver.spin_until(lambda: driver.node.count_publishers(topic) > 0, 10.0, "feedback publisher")
        warm = client.send_goal_async(SimulateSteps.Goal(steps=3))
        driver.spin_until(warm.done, 10.0, "first goal accepted")
        warm_result = warm.result().get_result_async()
        driver.spin_until(warm_result.done, 10.0, "first goal done")
        fresh(driver)
        # rclpy's ActionClient drops feedback that arrives after the result
        # (another DDS topic, so it may): the feedback topic itself is counted
        sent = driver.listen(SimulateSteps.Impl.FeedbackMessage, topic, deep)
        sent.clear()
        feedback = []
        goal = client.send_goal_async(SimulateSteps.Goal(steps=100), feedback_callback=lambda m: feedback.append(m.feedback))
        driver.spin_until(goal.done, 10.0, "goal accepted")
        result = goal.result().get_result_async()
        driver.spin_until(result.done, 30.0, "action result")
        assert result.result().result.result.result == OK
        ours = bytes(goal.result().goal_id.uuid)
        driver.spin_until(lambda: len([m for m in sent if bytes(m.goal_id.uuid) == ours]) >= 100, 5.0, "100 feedbacks")
        mine = [m.feedback for m in sent if bytes(m.goal_id.uuid) == ours]
        assert [f.completed_steps for f in mine] == list(range(1, 101))
        assert mine[-1].remaining_steps == 0
        assert time_ns(entity_state(driver, "ball").header.stamp) == 100 * FREE_DT_NS

        feedback.clear()
        goal = client.send_goal_async(SimulateSteps.Goal(steps=1_000_000), feedback_callback=lambda m: feedback.append(m.feedback))
        driver.spin_until(goal.done, 10.0, "goal accepted")
        driver.spin_until(lambda: len(feedback) >= 5, 10.0, "some feedback")
        cancel = goal.result().cancel_goal_async()
        driver.spin_until(cancel.done, 10.0, "cancel answered")
        result = goal.result().get_result_async()
        driver.spin_until(result.done, 10.0, "cancelled result")
        assert result.result().status == 5  # GoalStatus.STATUS_CANCELED
        done = time_ns(entity_state(driver, "ball").header.stamp) // FREE_DT_NS
        assert 100 + 5 <= done < 100 + 1_000_000
    finally:
        client.destroy()


def test_each_error_code_comes_from_a_request_that_deserves_it(sim):
    _, driver, _ = sim
    fresh(driver)
    S = srv.SpawnEntity.Response
    assert spawn(driver, text="").result.result == S.NO_RESOURCE
    assert call(driver, "spawn_entity", name="x", uri="model://crate").result.result == S.UNSUPPORTED_FORMAT
    assert spawn(driver, text="shape: [unclosed").result.result == S.RESOURCE_PARSE_ERROR
    assert spawn(driver, text="name: c\nshape: {type: box}\nmass: 1").result.result == S.RESOURCE_PARSE_ERROR
    assert spawn(driver, name="bad name!").result.result == S.NAME_INVALID
    assert spawn(driver, name="ball").result.result == S.NAME_NOT_UNIQUE
    renamed = spawn(driver, name="ball", allow_renaming=True)
    assert renamed.result.result == OK and renamed.entity_name == "ball_1"
    assert spawn(driver, name="y", entity_namespace="bad ns").result.result == S.NAMESPACE_INVALID
    assert spawn(driver, name="z", frame="nowhere").result.result == Result.RESULT_NOT_FOUND
    assert spawn(driver, name="w", z=float("nan")).result.result == S.INVALID_POSE
    assert call(driver, "delete_entity", entity="ghost").result.result == Result.RESULT_NOT_FOUND
    bad = EntityState()
    bad.pose.orientation.w = 2.0
    assert call(driver, "set_entity_state", entity="ball", state=bad).result.result == srv.SetEntityState.Response.INVALID_POSE
    assert call(driver, "step_simulation", steps=0).result.result == Result.RESULT_OPERATION_FAILED
    assert call(driver, "reset_simulation", scope=8).result.result == Result.RESULT_FEATURE_UNSUPPORTED
    V = srv.SetSimulationState.Response
    paused = SimulationState(state=SimulationState.STATE_PAUSED)
    assert call(driver, "set_simulation_state", state=paused).result.result == V.ALREADY_IN_TARGET_STATE
    stopped = SimulationState(state=SimulationState.STATE_STOPPED)
    assert call(driver, "set_simulation_state", state=stopped).result.result == OK
    assert call(driver, "set_simulation_state", state=paused).result.result == V.INCORRECT_TRANSITION
    playing = SimulationState(state=SimulationState.STATE_PLAYING)
    assert call(driver, "set_simulation_state", state=playing).result.result == OK
    assert call(driver, "step_simulation", steps=1).result.result == Result.RESULT_OPERATION_FAILED  # playing
    assert call(driver, "set_simulation_state", state=paused).result.result == OK
    assert call(driver, "get_simulation_state").state.state == SimulationState.STATE_PAUSED


def test_spawn_entities_reports_each_result_and_a_namespace_holds_the_topics(sim):
    _, driver, _ = sim
    fresh(driver)
    good = SpawnEntity(name="probe", entity_namespace="team/a")
    good.entity_resource.resource_string = BOX
    good.initial_pose.pose.position.z = 2.0
    empty = SpawnEntity(name="nothing")
    reply = call(driver, "spawn_entities", spawn_requests=[good, empty])
    assert reply.result.result == srv.SpawnEntities.Response.ENTITIES_SPAWN_FAILED
    assert [r.result.result for r in reply.results] == [OK, srv.SpawnEntity.Response.NO_RESOURCE]
    assert reply.results[0].entity_name == "probe"

    push = driver.wait_for_subscriber(WrenchStamped, f"{NS}/team/a/probe/wrench")
    msg = WrenchStamped()
    msg.wrench.force.x = 3.0  # N on 3 kg: 1 m/s² along x
    driver.publish_acked(push, msg)       # the node has it before the step request
    call(driver, "step_simulation", steps=10)
    assert entity_state(driver, "probe").twist.linear.x == pytest.approx(10 * FREE_DT_NS / 1e9, rel=1e-12)

    states = call(driver, "get_entities_states", filters=EntityFilters(filter="^(probe|ball)$"))
    assert states.entities == ["ball", "probe"]
    assert vec(states.states[1].pose.position).tolist() == vec(entity_state(driver, "probe").pose.position).tolist()
    assert call(driver, "get_entity_bounds", entity="probe").bounds.points[0].z == 0.3
    assert "spawned" in call(driver, "get_entity_info", entity="probe").info.tags
    assert call(driver, "get_entity_info", entity="nobody").result.result == Result.RESULT_NOT_FOUND


def test_recording_with_spawns_deletes_and_teleports_resimulates_bit_exactly(sim):
    node, driver, recording = sim
    fresh(driver)
    assert spawn(driver, name="a", z=1.0).result.result == OK
    assert spawn(driver, name="b", z=3.0).result.result == OK
    body_file = recording.parent / "sphere.yaml"
    body_file.write_text("name: from_file\nshape: {type: sphere, radius: 0.2}\nmass: 1.5\nposition: [2, 0, 1]\n")
    assert call(driver, "spawn_entity", uri=body_file.as_uri()).result.result == OK
    body_file.unlink()  # the recording keeps what was read
    call(driver, "step_simulation", steps=20)
    teleport = EntityState()
    teleport.pose.position.z = 4.0
    teleport.twist.linear.y = 1.5
    assert call(driver, "set_entity_state", entity="a", state=teleport).result.result == OK
    push = driver.wait_for_subscriber(WrenchStamped, f"{NS}/b/wrench")
    msg = WrenchStamped()
    msg.wrench.force.x = 2.0
    driver.publish_acked(push, msg)
    call(driver, "step_simulation", steps=20)
    assert call(driver, "delete_entity", entity="a").result.result == OK
    call(driver, "step_simulation", steps=10)
    assert call(driver, "reset_simulation", scope=4).result.result == OK  # spawned ones go, time goes on
    call(driver, "step_simulation", steps=10)
    node.stop()
    done = run_cli("physics_node.replay", [recording, "--resimulate"], timeout=120.0)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "match" in done.stdout
