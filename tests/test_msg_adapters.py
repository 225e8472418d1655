"""Conversions between engine arrays and ROS messages, and the schema text
rosbag2-style recordings carry for each type."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseArray, WrenchStamped
from nav_msgs.msg import Odometry
from rclpy.serialization import deserialize_message, serialize_message
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import PointCloud2, PointField
from std_msgs.msg import String
from visualization_msgs.msg import Marker, MarkerArray

from msg_adapters import (
    ContactArrays,
    arrays_from_pose_array,
    body_markers,
    cloud_to_structured,
    contact_cloud,
    contacts_from_cloud,
    diagnostic_array,
    diagnostic_values,
    message_class,
    odometry,
    pose_array,
    ros2msg_schema,
    rotate_to_body,
    rotate_to_world,
    scene_markers,
    sim_time_ns,
    state_from_odometry,
    time_msg,
    time_ns,
    to_world_axes,
    type_name,
    wrench_arrays,
    wrench_stamped,
)
from msg_adapters.schema import SEPARATOR

finite = st.floats(allow_nan=False, allow_infinity=False, width=64)
vec3 = arrays(np.float64, 3, elements=st.floats(-1e3, 1e3))
QUARTER_TURN_Z = np.array([np.sqrt(0.5), 0.0, 0.0, np.sqrt(0.5)])


@st.composite
def unit_quaternions(draw):
    q = draw(arrays(np.float64, 4, elements=st.floats(-1, 1)))
    norm = np.linalg.norm(q)
    if norm < 1e-3:
        return np.array([1.0, 0, 0, 0])
    return q / norm


# -- frames and time ---------------------------------------------------------


@given(unit_quaternions(), vec3)
def test_body_and_world_rotations_are_inverse(q, v):
    assert np.allclose(rotate_to_body(q, rotate_to_world(q, v)), v, atol=1e-9)
    assert np.linalg.norm(rotate_to_world(q, v)) == pytest.approx(np.linalg.norm(v), abs=1e-9)


def test_quarter_turn_about_z_sends_x_to_y():
    assert np.allclose(rotate_to_world(QUARTER_TURN_Z, [1, 0, 0]), [0, 1, 0])


@given(st.integers(0, 2**62))
def test_time_message_round_trip(ns):
    assert time_ns(time_msg(ns)) == ns


def test_sim_time_rounds_to_the_nearest_nanosecond():
    assert sim_time_ns(0.0041666667) == 4166667
    assert sim_time_ns(3 * 0.01) == 30_000_000


# -- poses and odometry ----------------------------------------------------------


@settings(max_examples=50, deadline=None)  # the first call loads the type support
@given(arrays(np.float64, (3, 3), elements=finite), arrays(np.float64, (3, 4), elements=finite))
def test_pose_array_keeps_every_bit(pos, quat):
    msg = deserialize_message(serialize_message(pose_array(pos, quat, 123)), PoseArray)
    back_pos, back_quat = arrays_from_pose_array(msg)
    assert np.array_equal(back_pos.view(np.uint64), pos.view(np.uint64))
    assert np.array_equal(back_quat.view(np.uint64), quat.view(np.uint64))
    assert msg.header.frame_id == "world" and time_ns(msg.header.stamp) == 123


def test_pose_array_orders_quaternion_as_ros_does():
    msg = pose_array(np.zeros((1, 3)), np.array([[0.1, 0.2, 0.3, 0.4]]), 0)
    o = msg.poses[0].orientation
    assert (o.x, o.y, o.z, o.w) == (0.2, 0.3, 0.4, 0.1)


def test_odometry_twist_is_in_the_body_frame():
    vel = np.array([0.0, 2.0, 0.0])  # world +y = the turned body's own +x
    omega = np.array([0.0, 0.0, 0.5])
    msg = odometry("box", np.array([1.0, 2, 3]), QUARTER_TURN_Z, vel, omega, 5)
    assert msg.child_frame_id == "box" and msg.header.frame_id == "world"
    lin = msg.twist.twist.linear
    assert (lin.x, lin.y, lin.z) == pytest.approx((2.0, 0.0, 0.0), abs=1e-12)
    assert msg.twist.twist.angular.z == pytest.approx(0.5)


@settings(deadline=None)
@given(unit_quaternions(), vec3, vec3, vec3)
def test_odometry_round_trip(q, p, v, w):
    pos, quat, vel, omega = state_from_odometry(odometry("b", p, q, v, w, 0))
    assert np.array_equal(pos, p) and np.array_equal(quat, q)
    assert np.allclose(vel, v, atol=1e-9) and np.allclose(omega, w, atol=1e-9)


# -- wrenches ---------------------------------------------------------------------


def test_wrench_round_trip_and_frames():
    msg = wrench_stamped([1, 2, 3], [4, 5, 6], frame_id="box", stamp_ns=7)
    frame, force, torque = wrench_arrays(msg)
    assert frame == "box" and force.tolist() == [1, 2, 3] and torque.tolist() == [4, 5, 6]
    assert to_world_axes("world", "box", QUARTER_TURN_Z, force, torque)[0].tolist() == [1, 2, 3]
    assert to_world_axes("", "box", QUARTER_TURN_Z, force, torque)[0].tolist() == [1, 2, 3]
    f, t = to_world_axes("box", "box", QUARTER_TURN_Z, np.array([1.0, 0, 0]), np.array([0, 1.0, 0]))
    assert np.allclose(f, [0, 1, 0]) and np.allclose(t, [-1, 0, 0])
    assert to_world_axes("ball", "box", QUARTER_TURN_Z, force, torque) is None


# -- contacts ----------------------------------------------------------------------


def _contacts(k, seed=0):
    rng = np.random.default_rng(seed)
    return ContactArrays(
        point=rng.normal(size=(k, 3)),
        normal=rng.normal(size=(k, 3)),
        impulse=rng.random(k),
        friction_impulse=rng.random(k),
        normal_speed=rng.normal(size=k),
        body_a=rng.integers(0, 10, k),
        body_b=rng.integers(0, 10, k),
        event=rng.integers(0, 3, k).astype(np.uint8),
    )


def test_contact_cloud_fields_and_round_trip():
    c = _contacts(5)
    msg = deserialize_message(serialize_message(contact_cloud(c, 42)), PointCloud2)
    fields = {f.name: f.datatype for f in msg.fields}
    for name in ("x", "y", "z", "normal_x", "normal_y", "normal_z", "impulse", "normal_speed"):
        assert name in fields
    assert fields["body_a"] == fields["body_b"] == PointField.UINT32
    assert fields["event"] == PointField.UINT8
    assert msg.width == 5 and msg.height == 1 and msg.row_step == 5 * msg.point_step
    back = contacts_from_cloud(msg)
    assert np.allclose(back.point, c.point, atol=1e-6)  # float32 geometry
    assert np.array_equal(back.impulse, c.impulse)  # float64 physics
    assert np.array_equal(back.normal_speed, c.normal_speed)
    assert np.array_equal(back.friction_impulse, c.friction_impulse)
    assert np.array_equal(back.body_a, c.body_a) and np.array_equal(back.body_b, c.body_b)
    assert np.array_equal(back.event, c.event)


def test_empty_contact_cloud():
    msg = contact_cloud(_contacts(0), 0)
    assert msg.width == 0 and len(msg.data) == 0
    assert len(contacts_from_cloud(msg)) == 0


def test_generic_decoder_reads_a_foreign_big_endian_cloud():
    dtype = np.dtype([("x", ">f4"), ("y", ">f4"), ("z", ">f4"), ("i", ">u2")])
    pts = np.array([(1, 2, 3, 7), (4, 5, 6, 9)], dtype=dtype)
    msg = PointCloud2(height=1, width=2, is_bigendian=True, point_step=dtype.itemsize, row_step=2 * dtype.itemsize)
    msg.fields = [
        PointField(name="x", offset=0, datatype=PointField.FLOAT32, count=1),
        PointField(name="y", offset=4, datatype=PointField.FLOAT32, count=1),
        PointField(name="z", offset=8, datatype=PointField.FLOAT32, count=1),
        PointField(name="i", offset=12, datatype=PointField.UINT16, count=1),
    ]
    msg.data = pts.tobytes()
    out = cloud_to_structured(msg)
    assert out["x"].tolist() == [1, 4] and out["i"].tolist() == [7, 9]


# -- markers --------------------------------------------------------------------------


class _Model:
    names = ("ground", "ball", "crate")
    shape_type = np.array([2, 0, 1])
    radius = np.array([0.0, 0.1, 0.0])
    half_extents = np.array([[0, 0, 0], [0, 0, 0], [0.2, 0.15, 0.1]], dtype=float)
    plane_normal = np.array([[0, 0, 1], [0, 0, 1], [0, 0, 1]], dtype=float)
    plane_offset = np.array([0.5, 0.0, 0.0])
    is_static = np.array([True, False, False])


def test_body_markers_one_per_body_with_shape_and_size():
    pos = np.array([[0, 0, 0], [0, 0, 1], [1, 0, 0.5]], dtype=float)
    quat = np.tile([1.0, 0, 0, 0], (3, 1))
    markers = body_markers(_Model, pos, quat, 0).markers
    assert [(m.id, m.ns, m.text) for m in markers] == [(0, "ground", "ground"), (1, "ball", "ball"), (2, "crate", "crate")]
    assert [m.type for m in markers] == [Marker.CUBE, Marker.SPHERE, Marker.CUBE]
    assert markers[1].scale.x == pytest.approx(0.2)
    assert (markers[2].scale.x, markers[2].scale.y, markers[2].scale.z) == pytest.approx((0.4, 0.3, 0.2))
    # The plane's slab has its top face on the plane z = 0.5.
    assert markers[0].pose.position.z + markers[0].scale.z / 2 == pytest.approx(0.5)
    assert markers[2].pose.position.x == 1.0


def test_scene_markers_clear_then_draw_bodies_and_contact_arrows():
    pos = np.zeros((3, 3))
    quat = np.tile([1.0, 0, 0, 0], (3, 1))
    msg = scene_markers(_Model, pos, quat, _contacts(2), 0)
    assert msg.markers[0].action == Marker.DELETEALL
    assert len(msg.markers) == 1 + 3 + 2
    arrows = msg.markers[4:]
    assert all(m.type == Marker.ARROW and m.ns == "contacts" and len(m.points) == 2 for m in arrows)


# -- diagnostics ------------------------------------------------------------------------


def test_diagnostic_values_round_trip():
    msg = diagnostic_array(5, "physics: simulation", "/physics", 0, "running", {"a": 1.5, "b": 3, "c": True})
    assert diagnostic_values(msg) == {"a": "1.5", "b": "3", "c": "true"}
    assert msg.status[0].name == "physics: simulation"


# -- schema text --------------------------------------------------------------------------

RECORDED_TYPES = [
    PoseArray,
    Odometry,
    PointCloud2,
    MarkerArray,
    Clock,
    DiagnosticArray,
    WrenchStamped,
    String,
]


def _parse_schema(text, name):
    """Types as rosbags reads them from a recording's schema text."""
    from rosbags.typesys.msg import get_types_from_msg

    sections = text.split(SEPARATOR + "\n")
    types = dict(get_types_from_msg(sections[0], name))
    for section in sections[1:]:
        head, _, body = section.partition("\n")
        pkg, short = head.removeprefix("MSG: ").split("/")
        types.update(get_types_from_msg(body, f"{pkg}/msg/{short}"))
    return types


@pytest.mark.parametrize("cls", RECORDED_TYPES, ids=lambda c: c.__name__)
def test_schema_text_matches_the_reference_definitions(cls):
    """Same fields, in the same order and types, as rosbags' own Jazzy store."""
    from rosbags.typesys import Stores, get_typestore

    reference = get_typestore(Stores.ROS2_JAZZY).fielddefs
    parsed = _parse_schema(ros2msg_schema(cls), type_name(cls))
    assert type_name(cls) in parsed
    for name, (consts, fields) in parsed.items():
        assert fields == reference[name][1], name
        assert {c[0]: c[2] for c in consts} == {c[0]: c[2] for c in reference[name][0]}, name


@pytest.mark.parametrize("cls", RECORDED_TYPES, ids=lambda c: c.__name__)
def test_schema_text_decodes_what_rclpy_serializes(cls):
    """CDR written by rclpy decodes with a reader that knows only the schema text."""
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.EMPTY)
    store.register(_parse_schema(ros2msg_schema(cls), type_name(cls)))
    sample = cls()
    if cls is PoseArray:
        sample = pose_array(np.array([[1.0, 2, 3]]), np.array([[1.0, 0, 0, 0]]), 99)
    elif cls is PointCloud2:
        sample = contact_cloud(_contacts(3), 99)
    elif cls is String:
        sample = String(data="reset")
    decoded = store.deserialize_cdr(serialize_message(sample), type_name(cls))
    if cls is PoseArray:
        assert decoded.poses[0].position.y == 2.0 and decoded.header.stamp.nanosec == 99
    if cls is PointCloud2:
        assert decoded.width == 3 and bytes(decoded.data) == bytes(sample.data)
    if cls is String:
        assert decoded.data == "reset"


def test_schema_lists_each_dependency_once():
    text = ros2msg_schema(MarkerArray)
    headers = [line for line in text.splitlines() if line.startswith("MSG: ")]
    assert len(headers) == len(set(headers))
    assert "MSG: std_msgs/Header" in headers and "MSG: builtin_interfaces/Time" in headers
    assert text.startswith("visualization_msgs/Marker[] markers\n")


def test_message_class_and_type_name_are_inverse():
    for cls in RECORDED_TYPES:
        assert message_class(type_name(cls)) is cls


def test_reusing_builders_give_the_same_messages_as_fresh_ones():
    from msg_adapters import BodyOdometry, SceneMarkers, odometries

    rng = np.random.default_rng(3)
    markers, odom = SceneMarkers(_Model), BodyOdometry(_Model.names)
    for stamp in (10, 20):
        pos, vel, omega = rng.normal(size=(3, 3)), rng.normal(size=(3, 3)), rng.normal(size=(3, 3))
        quat = rng.normal(size=(3, 4))
        quat /= np.linalg.norm(quat, axis=1, keepdims=True)
        contacts = _contacts(stamp // 10)
        # Compared as messages: CDR alignment padding is not guaranteed to be
        # zeroed, so equal messages need not serialize to equal bytes.
        assert markers.build(pos, quat, contacts, stamp) == scene_markers(_Model, pos, quat, contacts, stamp)
        assert odom.build(pos, quat, vel, omega, stamp) == odometries(_Model.names, pos, quat, vel, omega, stamp)


# Types the node does not record, for the schema builder's other spellings:
# a bounded sequence (SolidPrimitive's float64[<=3] dimensions) and bounded
# strings (FieldType's string<=255 nested_type_name), with constants.
def _other_types():
    from shape_msgs.msg import SolidPrimitive
    from type_description_interfaces.msg import FieldType

    return [SolidPrimitive, FieldType]


@pytest.mark.parametrize("cls", _other_types(), ids=lambda c: c.__name__)
def test_bounded_spellings_match_the_reference_definitions(cls):
    from rosbags.typesys import Stores, get_typestore

    reference = get_typestore(Stores.ROS2_JAZZY).fielddefs
    text = ros2msg_schema(cls)
    assert "[<=3]" in text or "string<=" in text
    parsed = _parse_schema(text, type_name(cls))
    for name, (consts, fields) in parsed.items():
        assert fields == reference[name][1], name
        assert {c[0]: c[2] for c in consts} == {c[0]: c[2] for c in reference[name][0]}, name


@pytest.mark.parametrize("value, line", [
    (True, "bool C=true"), (False, "bool C=false"), (b"\x07", "byte C=7"),
    (-(2**31), "int32 C=-2147483648"), (2**31 - 1, "int32 C=2147483647"),
    (2**31, "int64 C=2147483648"), (-(2**31) - 1, "int64 C=-2147483649"),
    (2**63 - 1, "int64 C=9223372036854775807"), (2**63, "uint64 C=9223372036854775808"),
    (0.1, "float64 C=0.1"), ("map", "string C=map"),
])
def test_constant_lines_spell_the_type_the_value_needs(value, line):
    from msg_adapters.schema import _constant_line

    assert _constant_line("C", value) == line


def test_wide_strings_are_spelled_and_an_unknown_type_is_refused_by_name():
    from rosidl_parser import definition as idl

    from msg_adapters.schema import _element_text, _field_text

    assert _element_text(idl.UnboundedWString()) == ("wstring", None)
    assert _element_text(idl.BoundedWString(7)) == ("wstring<=7", None)
    assert _field_text(idl.BoundedSequence(idl.BoundedString(5), 4)) == ("string<=5[<=4]", None)
    with pytest.raises(TypeError, match="no .msg spelling for"):
        _element_text(idl.NamedType("Mystery"))
