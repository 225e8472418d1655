"""Recordings made by the node process: read back by an independent reader
(rosbags), re-simulated bit for bit, and still usable after `kill -9`."""

import shutil
import signal
import time
from pathlib import Path

import numpy as np
import pytest
from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap.writer import Writer
from test_node_support import DEADLINE_SCALE, FREE_SCENE, Driver, NodeProcess, run_cli

from geometry_msgs.msg import PoseArray, WrenchStamped
from nav_msgs.msg import Odometry
from rclpy.serialization import deserialize_message, serialize_message
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import PointCloud2
from std_srvs.srv import Empty, Trigger
from visualization_msgs.msg import MarkerArray

from msg_adapters import contacts_from_cloud, time_ns, wrench_stamped
from physics_node.recording_reader import Recording, recover

rosbags = pytest.importorskip("rosbags")
from rosbags.highlevel import AnyReader  # noqa: E402
from rosbags.rosbag2 import Reader  # noqa: E402

# A spinning box under gravity with a thruster in its own axes: the held
# body-frame wrench turns with it, so replay must redo that exactly.
SPIN_SCENE = """\
dt: 0.005
integrator: semi_implicit_euler
gravity: [0, 0, -9.81]
bodies:
  - name: ball
    shape: {type: sphere, radius: 0.1}
    mass: 2.0
    position: [0, 0, 1]
  - name: box
    shape: {type: box, half_extents: [0.2, 0.1, 0.1]}
    mass: 4.0
    position: [1, 0, 1]
    angular_velocity: [0.3, 0.1, 2.0]
"""
DURATION = 1.0


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    """One recorded session with commands before and after a reset, manual
    steps and a free run to the end of `duration`."""
    workdir = tmp_path_factory.mktemp("recording")
    scene = workdir / "spin.yaml"
    scene.write_text(SPIN_SCENE)
    path = workdir / "session.mcap"
    args = ["--scene", scene, "--record", path, "--paused", "--rtf", "0", "--duration", DURATION, "--odometry", "all"]
    with NodeProcess(args, workdir) as node, Driver() as driver:
        driver.listen(MarkerArray, "/physics/markers")  # markers are sent (and recorded) while someone reads them
        node.wait_until_up()
        thrust = driver.wait_for_subscriber(WrenchStamped, "/physics/box/wrench")
        kick = driver.wait_for_subscriber(WrenchStamped, "/physics/ball/impulse")
        # each acknowledged before the next request, so the node has it by then
        driver.publish_acked(thrust, wrench_stamped((5.0, 0, 0), (0, 0, 0.2), frame_id="box"))
        driver.publish_acked(kick, wrench_stamped((0, 1.0, 4.0), (0.1, 0, 0)))
        driver.publish_acked(kick, wrench_stamped((float("nan"), 0, 0)))  # dropped, so never recorded
        for _ in range(5):
            assert driver.call(Trigger, "/physics/step").success
        driver.call(Empty, "/reset_simulation")
        driver.publish_acked(kick, wrench_stamped((0.5, 0, 0), frame_id="ball"))
        driver.publish_acked(thrust, wrench_stamped((0, 2.0, 0), frame_id="box"))
        # it runs to --duration and exits at once: its reply can go with the
        # process (it did, on a loaded machine), so wait on the exit instead
        driver.send_request(Empty, "/unpause_physics")
        assert node.wait(30.0) == 0, node.log()
    return path, scene


def test_rosbags_decodes_every_message(session):
    path, _ = session
    with AnyReader([Path(path)]) as reader:
        topics = {c.topic: c.msgtype for c in reader.connections}
        counts = {}
        for connection, timestamp, raw in reader.messages():
            msg = reader.deserialize(raw, connection.msgtype)
            counts[connection.topic] = counts.get(connection.topic, 0) + 1
            assert msg is not None
    assert topics == {
        "/clock": "rosgraph_msgs/msg/Clock",
        "/physics/poses": "geometry_msgs/msg/PoseArray",
        "/physics/ball/odom": "nav_msgs/msg/Odometry",
        "/physics/box/odom": "nav_msgs/msg/Odometry",
        "/physics/contacts": "sensor_msgs/msg/PointCloud2",
        "/physics/markers": "visualization_msgs/msg/MarkerArray",
        "/physics/bodies": "visualization_msgs/msg/MarkerArray",
        "/physics/ball/impulse": "geometry_msgs/msg/WrenchStamped",
        "/physics/box/wrench": "geometry_msgs/msg/WrenchStamped",
        "/physics/events": "std_msgs/msg/String",
        "/tf": "tf2_msgs/msg/TFMessage",  # recorded like any output, and decoded by rosbags
        "/tf_static": "tf2_msgs/msg/TFMessage",
    } | ({"/diagnostics": "diagnostic_msgs/msg/DiagnosticArray"} if "/diagnostics" in topics else {})
    steps = round(DURATION / 0.005)
    assert counts["/physics/ball/impulse"] == 2  # the NaN one was dropped
    assert counts["/physics/box/wrench"] == 2
    assert counts["/tf"] == counts["/physics/poses"]  # every published step
    # Every step after the reset, plus the 5 manual ones, the start and the reset.
    assert counts["/clock"] == steps + 5 + 2
    with Reader(Path(path)) as reader:
        for connection in reader.connections:
            assert connection.ext.offered_qos_profiles, connection.topic


def test_file_layout_follows_rosbag2(session):
    path, scene = session
    with open(path, "rb") as f:
        reader = make_reader(f)
        header = reader.get_header()
        summary = reader.get_summary()
        assert header.profile == "ros2"
        assert {s.encoding for s in summary.schemas.values()} == {"ros2msg"}
        assert {c.message_encoding for c in summary.channels.values()} == {"cdr"}
        assert all("offered_qos_profiles" in c.metadata for c in summary.channels.values())
        stats = summary.statistics
        assert stats.message_count == sum(stats.channel_message_counts.values()) > 0
        assert stats.chunk_count >= 1 and summary.chunk_indexes
        attachments = list(reader.iter_attachments())
        metadata = {m.name: m.metadata for m in reader.iter_metadata()}
    assert [a.name for a in attachments] == ["spin.yaml"]
    assert attachments[0].data.decode() == Path(scene).read_text()
    session_info = metadata["physics_node"]
    assert session_info["param.real_time_factor"] == "0.0"
    assert session_info["param.duration"] == repr(DURATION)
    assert session_info["engine_version"]
    assert session_info["node"] == "/physics"


def test_commands_are_logged_at_the_step_that_applied_them(session):
    path, _ = session
    rec = Recording(path)
    commands = [m for m in rec.messages() if m.topic.endswith(("/wrench", "/impulse"))]
    # Before the reset: applied at the first manual step; after it: at the
    # first step of the free run. Both are step 0 at sim time 0. (Two topics
    # do not keep their relative order in transit, so compare as sets.)
    before, after = commands[:2], commands[2:]
    expected = {("/physics/box/wrench", 0, 0), ("/physics/ball/impulse", 0, 0)}
    assert {(m.topic, m.sequence, m.log_time) for m in before} == expected
    assert {(m.topic, m.sequence, m.log_time) for m in after} == expected
    poses = [m for m in rec.messages() if m.topic == "/physics/poses"]
    for m in poses:
        assert time_ns(deserialize_message(m.data, PoseArray).header.stamp) == m.log_time


def test_resimulate_matches_bit_for_bit(session):
    path, _ = session
    result = run_cli("physics_node.replay", [path, "--resimulate"])
    assert result.returncode == 0, result.stdout + result.stderr
    assert result.stdout.startswith("match:")
    assert "1 resets" in result.stdout


def test_resimulate_names_the_first_divergence(session, tmp_path):
    path, _ = session
    tampered = tmp_path / "tampered.mcap"
    target_step = 40
    with open(path, "rb") as src, open(tampered, "wb") as dst:
        reader = make_reader(src)
        writer = Writer(dst)
        writer.start(profile="ros2", library="test")
        for a in reader.iter_attachments():
            writer.add_attachment(a.create_time, a.log_time, a.name, a.media_type, a.data)
        for m in reader.iter_metadata():
            writer.add_metadata(m.name, m.metadata)
        ids = {}
        seen_reset = False
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            if channel.id not in ids:
                sid = writer.register_schema(schema.name, schema.encoding, schema.data)
                ids[channel.id] = writer.register_channel(channel.topic, channel.message_encoding, sid, channel.metadata)
            data = message.data
            seen_reset |= channel.topic == "/physics/events"
            if seen_reset and channel.topic == "/physics/poses" and message.sequence == target_step:
                poses = deserialize_message(data, PoseArray)
                poses.poses[1].position.y = np.nextafter(poses.poses[1].position.y, 1.0)  # one ulp
                data = serialize_message(poses)
            writer.add_message(ids[channel.id], message.log_time, data, message.publish_time, message.sequence)
        writer.finish()
    result = run_cli("physics_node.replay", [tampered, "--resimulate"])
    assert result.returncode == 1, result.stdout + result.stderr
    assert f"step {target_step}" in result.stdout and "'box'" in result.stdout


def test_resimulate_reports_errors_with_status_2(tmp_path):
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"not an mcap file")
    result = run_cli("physics_node.replay", [junk, "--resimulate"])
    assert result.returncode == 2
    assert result.stdout.startswith("error:")


def test_kill_9_leaves_a_readable_recording(tmp_path):
    scene = tmp_path / "free.yaml"
    scene.write_text(FREE_SCENE)
    path = tmp_path / "cut.mcap"
    with NodeProcess(["--scene", scene, "--record", path, "--rtf", "0"], tmp_path, isolated=True) as node:
        node.wait_until_up()
        deadline = time.monotonic() + 10.0 * DEADLINE_SCALE
        while Recording(path).chunk_count < 2 and time.monotonic() < deadline:
            time.sleep(0.2)
        node.signal(signal.SIGKILL)
        assert node.wait() == -signal.SIGKILL
    rec = Recording(path)
    assert not rec.complete
    assert rec.attachment(name="free.yaml") is not None
    assert "physics_node" in rec.metadata
    assert sum(1 for m in rec.messages() if m.topic == "/physics/poses") > 10

    result = run_cli("physics_node.replay", [path, "--resimulate"])
    assert result.returncode == 0, result.stdout + result.stderr
    assert "not closed cleanly" in result.stdout

    repaired = tmp_path / "repaired.mcap"
    result = run_cli("physics_node.replay", [path, "--recover", repaired])
    assert result.returncode == 0, result.stderr
    with AnyReader([repaired]) as reader:
        assert sum(1 for _ in reader.messages()) > 0


def _count(path, topic):
    """Messages on `topic` in the chunks written so far (0 before the first)."""
    try:
        return sum(1 for m in Recording(path).messages() if m.topic == topic)
    except (OSError, ValueError, McapError):  # not there yet, or its first chunk is being written
        return 0


def test_sigint_finishes_the_file_and_ros_args_set_parameters(tmp_path):
    scene = tmp_path / "free.yaml"
    scene.write_text(FREE_SCENE)
    path = tmp_path / "ctrl-c.mcap"
    args = ["--ros-args", "-p", f"scene:={scene}", "-p", f"record:={path}", "-p", "real_time_factor:=3"]
    args += ["-p", "publish_every:=4"]
    with NodeProcess(args, tmp_path, isolated=True) as node:
        node.wait_until_up()
        # wait for what is asserted below (enough clock ticks on disk), not for a time
        deadline = time.monotonic() + 30.0 * DEADLINE_SCALE
        while _count(path, "/clock") <= 8 and time.monotonic() < deadline:
            time.sleep(0.1)
        node.signal(signal.SIGINT)
        assert node.wait() == 0, node.log()
    assert Recording(path).complete
    with Reader(path) as reader:  # rosbags needs the summary: the file was finished
        counts = {c.topic: c.msgcount for c in reader.connections}
    assert counts["/clock"] > 4
    assert counts["/physics/poses"] <= counts["/clock"] // 4 + 2
    meta = Recording(path).metadata["physics_node"]
    assert meta["param.real_time_factor"] == "3.0" and meta["param.publish_every"] == "4"


def test_odometry_and_markers_go_to_topics_someone_reads(tmp_path):
    """By default a body's odometry is published (and so recorded) only while
    its topic has a subscriber, and markers only while someone reads them;
    poses and /clock always are."""
    scene = tmp_path / "free.yaml"
    scene.write_text(FREE_SCENE)
    path = tmp_path / "on-demand.mcap"
    with NodeProcess(["--scene", scene, "--record", path, "--paused"], tmp_path) as node, Driver() as driver:
        ball = driver.listen(Odometry, "/physics/ball/odom")
        node.wait_until_up()
        driver.spin_until(lambda: driver.node.count_publishers("/physics/ball/odom") > 0, 10.0, "ball odometry")
        for _ in range(3):
            assert driver.call(Trigger, "/physics/step").success
        driver.spin_until(lambda: len(ball) >= 3, 5.0, "three odometry messages of the ball")
        node.signal(signal.SIGINT)
        assert node.wait() == 0, node.log()
    counts = {}
    for m in Recording(path).messages():
        counts[m.topic] = counts.get(m.topic, 0) + 1
    assert counts["/physics/ball/odom"] >= 3
    assert "/physics/box/odom" not in counts and "/physics/markers" not in counts
    assert counts["/physics/poses"] >= 4 and counts["/clock"] >= 4


def test_replay_republishes_with_clock(session):
    path, _ = session
    with Driver() as driver:
        poses = driver.listen(PoseArray, "/physics/poses")
        clocks = driver.listen(Clock, "/clock")
        replay = NodeProcess([path, "--rate", "2", "--wait", "15"], Path(path).parent, module="physics_node.replay")
        try:
            # Keep receiving while it plays: a subscriber's unread messages
            # can go when their publisher's process exits.
            driver.spin_until(lambda: not replay.alive(), 30.0, "the replay to finish")
            assert replay.wait() == 0, replay.log()
            # it exits once its last messages are acknowledged: take them in
            driver.spin_until(lambda: clocks and time_ns(clocks[-1].clock) == round(DURATION * 1e9), 10.0,
                              "the replay's last /clock")
        finally:
            replay.stop()
    assert "replayed" in replay.log()
    assert len(poses) > 20
    stamps = [time_ns(c.clock) for c in clocks]
    assert stamps and stamps[-1] == round(DURATION * 1e9)


def test_recording_copy_is_stable(session, tmp_path):
    """Reading never modifies the file (replay works on a read-only copy)."""
    path, _ = session
    copy = tmp_path / "copy.mcap"
    shutil.copy(path, copy)
    copy.chmod(0o444)
    assert Recording(copy).complete


def test_default_scene_session_with_contacts_resimulates_exactly(tmp_path):
    """What `make run` does, for 0.8 s of sim time: the built-in scene (bodies
    falling, bouncing and hanging from a spring), recorded and re-run."""
    path = tmp_path / "recordings" / "session.mcap"
    with NodeProcess(["--record", path, "--rtf", "0", "--duration", "0.8"], tmp_path, isolated=True) as node:
        assert node.wait(60.0) == 0, node.log()
    result = run_cli("physics_node.replay", [path, "--resimulate"])
    assert result.returncode == 0, result.stdout + result.stderr
    events = []
    with AnyReader([path]) as reader:
        for connection, _, raw in reader.messages():
            msg = reader.deserialize(raw, connection.msgtype)
            if connection.topic == "/physics/contacts" and msg.width:
                cloud = deserialize_message(raw, PointCloud2)
                events += contacts_from_cloud(cloud).event.tolist()
    assert 0 in events, "the falling bodies should begin touching the ground"
