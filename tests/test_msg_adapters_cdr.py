"""The CDR builders (msg_adapters.cdr) give, once deserialized, exactly the
messages the object builders give, with rclpy's byte length."""

import numpy as np
import pytest
from geometry_msgs.msg import PoseArray
from nav_msgs.msg import Odometry
from rclpy.serialization import deserialize_message, serialize_message
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import PointCloud2
from std_msgs.msg import String
from tf2_msgs.msg import TFMessage
from visualization_msgs.msg import Marker, MarkerArray

from msg_adapters import (
    BodyOdometry,
    body_markers,
    ContactArrays,
    SceneMarkers,
    contact_cloud,
    diagnostic_array,
    pose_array,
    scene_markers,
    time_msg,
)
from msg_adapters import cdr
from msg_adapters.cdr import (
    ContactCloudCdr,
    OdometryCdr,
    PoseArrayCdr,
    SceneMarkersCdr,
    body_markers_cdr,
    clock_cdr,
    layout,
)
from msg_adapters.tf import TransformsCdr, transforms_message
from physics_core import load_scene

# Names of different lengths (so messages and markers start at every
# alignment), a tilted static plane, a box and spheres.
SCENE = {
    "dt": 0.01,
    "integrator": "semi_implicit_euler",
    "bodies": [
        {"name": "floor", "shape": {"type": "plane", "normal": [0, 0.6, 0.8], "offset": -0.5}, "static": True},
        {"name": "b", "shape": {"type": "sphere", "radius": 0.1}, "mass": 1.0, "position": [0, 0, 1]},
        {"name": "crate_2", "shape": {"type": "box", "half_extents": [0.2, 0.15, 0.1]}, "mass": 2.0},
        {"name": "ball_three", "shape": {"type": "sphere", "radius": 0.3}, "mass": 1.0, "position": [1, 0, 1]},
        {"name": "wall", "shape": {"type": "box", "half_extents": [1, 0.1, 1]}, "static": True, "position": [0, 3, 1]},
    ],
}


@pytest.fixture(scope="module")
def model():
    return load_scene(SCENE).model


def _on_the_wire(msg):
    """What a subscriber decodes (float32 fields rounded)."""
    return deserialize_message(serialize_message(msg), type(msg))


def _state(rng, n):
    quat = rng.normal(size=(n, 4))
    quat /= np.linalg.norm(quat, axis=1, keepdims=True)
    return rng.normal(size=(n, 3)) * 10, quat, rng.normal(size=(n, 3)), rng.normal(size=(n, 3))


def _contacts(rng, k, n):
    normal = rng.normal(size=(k, 3))
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-12)
    return ContactArrays(
        point=rng.normal(size=(k, 3)),
        normal=normal,
        impulse=rng.random(k),
        friction_impulse=rng.random(k),
        normal_speed=rng.normal(size=k),
        body_a=rng.integers(0, n, size=k),
        body_b=rng.integers(0, n, size=k),
        event=rng.integers(0, 4, size=k),  # 3 is no event: drawn as persist
    )


def test_poses_and_odometry_match_the_object_builders(model):
    rng = np.random.default_rng(1)
    n = len(model.names)
    poses, odometry, reference = PoseArrayCdr(n), OdometryCdr(model.names), BodyOdometry(model.names)
    for stamp in (0, 1_500_000_001, 7 * 10**12 + 3):
        pos, quat, vel, omega = _state(rng, n)
        data = poses.build(pos, quat, stamp)
        assert deserialize_message(data, PoseArray) == pose_array(pos, quat, stamp)
        assert len(data) == len(serialize_message(pose_array(pos, quat, stamp)))
        built = odometry.build(pos, quat, vel, omega, stamp)
        expected = reference.build(pos, quat, vel, omega, stamp)
        assert len(built) == n
        for data, msg in zip(built, expected):
            assert deserialize_message(data, Odometry) == msg
            assert len(data) == len(serialize_message(msg))
        # only some bodies (the ones whose topic has a subscriber), in the order asked
        for rows in ([3], [4, 0, 2], list(range(n))):
            some = odometry.build(pos, quat, vel, omega, stamp, rows=rows)
            assert [deserialize_message(d, Odometry) for d in some] == [expected[i] for i in rows]


@pytest.mark.parametrize("counts", [(0, 1, 0), (3, 2, 5), (1, 40, 7, 0, 200)])
def test_scene_markers_match_the_object_builder_as_contacts_come_and_go(model, counts):
    rng = np.random.default_rng(len(counts))
    n = len(model.names)
    built = SceneMarkersCdr(model, capacity=4)  # small, so it has to grow
    for step, k in enumerate(counts):
        pos, quat, _, _ = _state(rng, n)
        contacts = _contacts(rng, k, n)
        stamp = 10**9 * step + 17
        data = built.build(pos, quat, contacts, stamp)
        expected = scene_markers(model, pos, quat, contacts, stamp)
        assert deserialize_message(data, MarkerArray) == _on_the_wire(expected)
        assert len(data) == len(serialize_message(expected))
        assert deserialize_message(data, MarkerArray) == _on_the_wire(SceneMarkers(model).build(pos, quat, contacts, stamp))


@pytest.mark.parametrize("k", [0, 1, 9])
def test_contact_cloud_and_clock_match(k):
    rng = np.random.default_rng(k)
    contacts = _contacts(rng, k, 4)
    data = ContactCloudCdr().build(contacts, 123_456_789_012)
    assert deserialize_message(data, PointCloud2) == contact_cloud(contacts, 123_456_789_012)
    assert len(data) == len(serialize_message(contact_cloud(contacts, 123_456_789_012)))
    assert deserialize_message(clock_cdr(5_000_000_007), Clock) == Clock(clock=time_msg(5_000_000_007))


@pytest.mark.parametrize(
    "msg",
    [
        String(data=""),
        String(data="abc"),
        Odometry(child_frame_id="x"),
        diagnostic_array(1, "n", "/h", 0, "ok", {"a": 1.5, "flag": True}),
        contact_cloud(ContactArrays(*(np.zeros((2, 3)),) * 2, *(np.zeros(2),) * 6), 0),
    ],
)
def test_layout_size_is_rclpys_length(msg):
    _, size = layout(msg)
    assert len(serialize_message(msg)) == 4 + size


def test_layout_offsets_point_at_the_fields():
    msg = pose_array(np.array([[1.0, 2, 3], [4, 5, 6]]), np.array([[1.0, 0, 0, 0], [0.5, 0.5, 0.5, 0.5]]), 9)
    offsets, _ = layout(msg)
    data = serialize_message(msg)[4:]
    at = offsets[("poses", 1, "position", "y")]
    assert np.frombuffer(data[at : at + 8], "<f8")[0] == 5.0
    at = offsets[("header", "stamp", "nanosec")]
    assert np.frombuffer(data[at : at + 4], "<u4")[0] == 9


def test_the_nodes_fallback_without_cdr_layouts_sends_the_same_messages(model):
    from types import SimpleNamespace

    from physics_node.outputs import _serialized_state_builder, _state_builder

    rng = np.random.default_rng(7)
    n = len(model.names)
    pos, quat, vel, omega = _state(rng, n)
    state = SimpleNamespace(pos=pos, quat=quat, vel=vel, omega=omega)
    contacts = _contacts(rng, 5, n)
    for rows, markers in ((list(range(n)), True), ([2, 0], False), ([], True)):
        fast = _state_builder(model, logger=None)(state, contacts, 42, rows, markers)
        slow = _serialized_state_builder(model)(state, contacts, 42, rows, markers)
        types = [PoseArray, PointCloud2, *[Odometry] * len(rows)] + [MarkerArray] * markers
        assert len(fast) == len(slow) == len(types)
        for a, b, cls in zip(fast, slow, types):
            assert deserialize_message(a, cls) == deserialize_message(b, cls)


@pytest.mark.parametrize("n", [0, 1, 2, 3, 50])
def test_pose_arrays_of_any_length_are_rclpys_bytes(n):
    rng = np.random.default_rng(n)
    pos, quat, _, _ = _state(rng, n)
    built = PoseArrayCdr(n).build(pos, quat, 3 * 10**9 + 11)
    expected = pose_array(pos, quat, 3 * 10**9 + 11)
    assert deserialize_message(built, PoseArray) == expected
    assert len(built) == len(serialize_message(expected))


# Names whose byte lengths give every alignment of what follows them (é is two bytes).
NAMES = ["a", "bb", "ccc", "dddd", "eeeee", "é", "s9999", "", "long_name_of_a_body_17"]


@pytest.mark.parametrize("names", [[], NAMES[:1], NAMES, NAMES[::-1] * 3])
def test_transforms_match_the_object_builder(names):
    rng = np.random.default_rng(len(names))
    pos, quat, _, _ = _state(rng, len(names))
    built = TransformsCdr(names)
    for stamp in (0, 2_000_000_003):
        data = built.build(pos, quat, stamp)
        expected = transforms_message(names, pos, quat, stamp)
        assert deserialize_message(data, TFMessage) == expected
        assert len(data) == len(serialize_message(expected))


def _many_bodies():
    """30 bodies whose names are 1-12 characters long, so markers of each
    name length start at both alignments, and a static one."""
    rng = np.random.default_rng(11)
    bodies = [{"name": "ground", "shape": {"type": "plane"}}]
    for i in range(30):
        shape = {"type": "sphere", "radius": 0.1} if i % 2 else {"type": "box", "half_extents": [0.1, 0.2, 0.3]}
        name = "b" + "x" * int(rng.integers(0, 12)) + str(i)
        bodies.append({"name": name, "shape": shape, "mass": 1.0, "static": i == 7})
    return load_scene({"dt": 0.01, "bodies": bodies}).model


@pytest.mark.parametrize("which", ["five", "thirty"])
def test_body_markers_with_deletes_match_the_object_builder(model, which):
    model = model if which == "five" else _many_bodies()
    rng = np.random.default_rng(3)
    pos, quat, _, _ = _state(rng, len(model.names))
    deleted = [(5, "gone"), (6, ""), (7, "é_long_name")]
    expected = body_markers(model, pos, quat, 77)
    for marker_id, ns in deleted:
        marker = Marker(action=Marker.DELETE, id=marker_id, ns=ns)
        marker.header.stamp = time_msg(77)
        expected.markers.append(marker)
    for gone in ((), deleted):
        data = body_markers_cdr(model, pos, quat, 77, gone)
        want = MarkerArray(markers=expected.markers[: len(model.names) + len(gone)])
        assert deserialize_message(data, MarkerArray) == _on_the_wire(want)
        assert len(data) == len(serialize_message(want))


def test_layouts_reused_for_fixed_size_types_equal_a_field_by_field_walk(model, monkeypatch):
    """The cached layouts of Pose, Time, Vector3, ... (cdr._fixed_layout) give
    the offsets a walk of every field gives, whatever offset they start at."""
    rng = np.random.default_rng(5)
    pos, quat, vel, omega = _state(rng, len(model.names))
    msgs = [
        pose_array(pos, quat, 5),
        transforms_message(NAMES, *_state(rng, len(NAMES))[:2], 6),
        scene_markers(model, pos, quat, _contacts(rng, 3, len(model.names)), 7),
        BodyOdometry(model.names).build(pos, quat, vel, omega, 8)[2],
    ]
    cached = [layout(m) for m in msgs]
    monkeypatch.setattr(cdr, "_fixed_layout", lambda msg, start: None)
    monkeypatch.setattr(cdr, "_FIXED_LAYOUTS", {})
    assert [layout(m) for m in msgs] == cached
