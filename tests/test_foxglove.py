"""`physics-node --foxglove`: a client of the Foxglove WebSocket protocol
(tests/foxglove_client.py, independent of the SDK that serves) subscribes to
the scene, decodes it with the schema the server advertised, and finds the
poses `~/poses` had at the same sim time; its service calls pause, step,
play and reset the node; the server's time is sim time."""

import re

import numpy as np
from foxglove_client import FoxgloveClient, protobuf_class
from test_node_support import Driver, NodeProcess

from geometry_msgs.msg import PoseArray
from rclpy.serialization import deserialize_message
from rosgraph_msgs.msg import Clock
from std_srvs.srv import Trigger
from visualization_msgs.msg import MarkerArray

from msg_adapters import arrays_from_pose_array, sim_time_ns, time_ns
from physics_core import default_scene_path, load_scene

# The built-in scene's moving bodies and their scene indices (0 is the ground
# plane, drawn as a slab on n·x = offset, not at a pose).
BODIES = {"ball": 1, "crate": 2, "bob": 3}
DT = load_scene(default_scene_path()).dt


def _scene_poses(update):
    """(stamp ns, pos (3, 3), quat (3, 4) w,x,y,z) of the moving bodies in a decoded SceneUpdate."""
    by_id = {e.id: e for e in update.entities}
    pos, quat = [], []
    for name in BODIES:
        e = by_id[name]
        prim = (list(e.spheres) + list(e.cubes))[0]
        p, q = prim.pose.position, prim.pose.orientation
        pos.append((p.x, p.y, p.z))
        quat.append((q.w, q.x, q.y, q.z))
    stamp = by_id["ball"].timestamp
    return stamp.seconds * 1_000_000_000 + stamp.nanos, np.array(pos), np.array(quat)


def _serve(tmp_path, *args):
    node = NodeProcess(["--foxglove", "0", *args], tmp_path)
    node.wait_for_log("Foxglove server at ws://")
    url = re.search(r"Foxglove server at (ws://\S+)", node.log()).group(1)
    return node, url


def test_scene_updates_carry_the_poses_of_the_same_sim_time(tmp_path):
    node, url = _serve(tmp_path)
    with node, Driver() as driver, FoxgloveClient(url) as client:
        poses = driver.listen(PoseArray, "/physics/poses")
        client.pump_until(lambda: client.server_info is not None, 10.0, "serverInfo")
        assert {"time", "services"} <= set(client.server_info["capabilities"])
        client.subscribe("/physics/scene")
        client.subscribe("/physics/poses")  # the node's own topic, forwarded as its CDR bytes
        scene_class = protobuf_class(client.channels["/physics/scene"])

        def matched():
            ros = {time_ns(m.header.stamp): m for m in poses}
            found = []
            for _log_time, data in client.received("/physics/scene"):
                stamp, pos, quat = _scene_poses(scene_class.FromString(data))
                if stamp in ros:
                    found.append((stamp, pos, quat, ros[stamp]))
            return found

        def enough():
            # Both sides drained in turn: the ROS side at 240 poses a second.
            client.pump(0.02)
            driver.spin_for(0.05)
            return len({stamp for stamp, *_ in matched()}) >= 5

        driver.spin_until(enough, timeout=20.0, what="five scene updates with ~/poses of the same stamp")
        found = matched()
        for stamp, pos, quat, msg in found:
            ros_pos, ros_quat = arrays_from_pose_array(msg)
            rows = list(BODIES.values())
            assert np.array_equal(pos, ros_pos[rows]), stamp  # float64 end to end: the same bits
            assert np.array_equal(quat, ros_quat[rows]), stamp
        # a subscriber is sent the current scene at once, and the next step's
        # update may carry the same stamp: the same poses then, in time order
        stamps = [stamp for stamp, *_ in found]
        assert stamps == sorted(stamps)
        first = {}
        for stamp, pos, quat, _msg in found:
            if stamp in first:
                assert np.array_equal(first[stamp][0], pos) and np.array_equal(first[stamp][1], quat)
            first.setdefault(stamp, (pos, quat))
        # Log times are sim times: each forwarded ~/poses at its own header stamp.
        forwarded = client.received("/physics/poses")
        assert forwarded
        for log_time, data in forwarded[-5:]:
            msg = deserialize_message(data, PoseArray)
            assert time_ns(msg.header.stamp) == log_time


def test_services_pause_step_play_and_reset_the_node(tmp_path):
    node, url = _serve(tmp_path)
    with node, Driver() as driver, FoxgloveClient(url) as client:
        clocks = driver.listen(Clock, "/clock")
        poses = driver.listen(PoseArray, "/physics/poses")
        client.subscribe("/physics/scene")
        driver.spin_until(lambda: len(clocks) > 10, what="the node to run")
        paused = client.call("pause")
        assert paused["success"] and paused["paused"]
        # Paused for real: the ROS ~/step service only steps a paused node.
        step = driver.call(Trigger, "/physics/step")
        assert step.success, step.message
        client.times.clear()
        answer = client.call("step")
        assert answer["success"], answer
        # The server's time is the sim time of the step just taken.
        client.pump_until(lambda: sim_time_ns(answer["sim_time"]) in client.times, 5.0, "the time of the step")
        assert answer["step"] == paused["step"] + 2
        assert abs(answer["sim_time"] - answer["step"] * DT) < 1e-9
        # While paused every step's scene goes out: the one of this step has its ~/poses.
        stamp = sim_time_ns(answer["sim_time"])
        scene_class = protobuf_class(client.channels["/physics/scene"])
        client.pump_until(lambda: any(_scene_poses(scene_class.FromString(d))[0] == stamp
                                      for _, d in client.received("/physics/scene")), 5.0, "the step's scene")
        driver.spin_until(lambda: any(time_ns(m.header.stamp) == stamp for m in poses), what="the step's ~/poses")
        _, pos, quat = next(p for p in (_scene_poses(scene_class.FromString(d)) for _, d in
                                        client.received("/physics/scene")) if p[0] == stamp)
        ros_pos, ros_quat = arrays_from_pose_array(next(m for m in poses if time_ns(m.header.stamp) == stamp))
        assert np.array_equal(pos, ros_pos[list(BODIES.values())])
        assert np.array_equal(quat, ros_quat[list(BODIES.values())])
        driver.spin_for(0.3)
        before = time_ns(clocks[-1].clock)
        driver.spin_for(0.3)
        assert time_ns(clocks[-1].clock) == before == sim_time_ns(answer["sim_time"])  # no step while paused
        reset = client.call("reset")
        assert reset["success"] and reset["step"] == 0 and reset["sim_time"] == 0.0
        played = client.call("play")
        assert played["success"] and not played["paused"]
        driver.spin_until(lambda: time_ns(clocks[-1].clock) > 0.1e9, what="sim time to run again")
        refused = driver.call(Trigger, "/physics/step")
        assert not refused.success and "not paused" in refused.message


def test_a_taken_port_is_a_clear_error(tmp_path):
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        with NodeProcess(["--foxglove", port], tmp_path) as node:
            assert node.wait(30.0) == 2
            assert f"cannot serve on 127.0.0.1:{port}" in node.log()


def test_a_client_of_a_paused_node_sees_the_world_at_once(tmp_path):
    """A paused node sends nothing by itself: a client subscribing then still
    gets the scene as it is and the latched ~/bodies, as a ROS late joiner would."""
    node, url = _serve(tmp_path, "--paused")
    with node, FoxgloveClient(url) as client:
        client.pump(1.0)  # the node is up and idle; nothing is subscribed yet
        client.subscribe("/physics/scene")
        client.subscribe("/physics/bodies")
        client.pump_until(lambda: client.received("/physics/scene") and client.received("/physics/bodies"), 10.0,
                          "the current scene and the bodies")
        scene_class = protobuf_class(client.channels["/physics/scene"])
        stamp, pos, _ = _scene_poses(scene_class.FromString(client.received("/physics/scene")[-1][1]))
        assert stamp == 0
        initial = load_scene(default_scene_path()).state.pos
        assert np.array_equal(pos, initial[list(BODIES.values())])
        bodies = deserialize_message(client.received("/physics/bodies")[-1][1], MarkerArray)
        assert [m.ns for m in bodies.markers] == ["ground", *BODIES]
        assert 0 in client.times  # the server's time is the paused sim time
