"""The messages the node sends every step, built directly as CDR bytes.

rclpy turns a message object into CDR field by field through Python property
getters: tens of microseconds for one Odometry or one Marker, milliseconds for
a step of a hundred bodies. The builders here have rclpy serialize a template
once, find where each field sits (`layout`), and then each step write only
what changes (stamps, poses, twists, contact arrows) into a preallocated
buffer with numpy, for all bodies at once. The result deserializes to the
same message the object builders (`pose_array`, `BodyOdometry`,
`SceneMarkers`, `contact_cloud`) give, so it goes straight to
`Publisher.publish` and to the recording: serialized once, in bulk.

Only alignment padding may differ from rclpy's own bytes (rclpy leaves
padding uninitialised; here it is whatever the template held).
"""

import struct

import numpy as np
from rclpy.serialization import serialize_message
from rosidl_parser import definition as idl
from visualization_msgs.msg import Marker, MarkerArray

from .contacts import ContactArrays, contact_cloud, contact_points
from .frames import WORLD_FRAME, rotate_to_body
from .markers import (
    _EVENT_RGBA,
    CONTACT_ARROW_LENGTH,
    SceneMarkers,
    body_marker_rgba,
    body_marker_shape,
    contact_arrow,
    fill_body_marker,
)
from .poses import _odometry, pose_array
from .stamps import NS_PER_S, time_msg

# Encapsulation header of little-endian plain CDR, as rmw_fastrtps writes it.
CDR_LE = b"\x00\x01\x00\x00"
HEADER_BYTES = len(CDR_LE)

_PRIMITIVE_SIZE = {
    **dict.fromkeys(("boolean", "octet", "char", "int8", "uint8"), 1),
    **dict.fromkeys(("wchar", "int16", "uint16", "short", "unsigned short"), 2),
    **dict.fromkeys(("int32", "uint32", "long", "unsigned long", "float"), 4),
    **dict.fromkeys(("int64", "uint64", "long long", "unsigned long long", "double"), 8),
}


class CdrLayoutError(ValueError):
    """The CDR rules assumed here do not describe what rclpy wrote."""


def _align(offset, size):
    return (offset + size - 1) // size * size


def _primitive_size(t):
    size = _PRIMITIVE_SIZE.get(t.typename)
    if size is None:
        raise CdrLayoutError(f"no CDR size for {t.typename!r}")
    return size


def layout(msg):
    """(offsets, size) of `msg` in plain CDR: `offsets` maps each field's path
    (field names and sequence indexes, e.g. ("poses", 3, "position", "x")) to
    its offset from the CDR origin (just after the encapsulation header). For
    a string or sequence the offset is that of its length word; for a fixed
    array, that of its first element. `size` is the serialized length
    without the header."""
    offsets = {}
    size = _walk_message(msg, 0, (), offsets)
    return offsets, size


def _walk_message(msg, offset, path, out):
    # A message type without strings or sequences (Pose, Vector3, Time, ...)
    # always lays out the same from a given offset modulo 8 (the largest
    # alignment): walked once, then shifted. A PoseArray of 10,000 poses
    # took 0.4 s to walk field by field.
    start = offset % 8
    key = (type(msg), start)
    fixed = _FIXED_LAYOUTS.get(key, _UNSEEN)
    if fixed is _UNSEEN:
        fixed = _FIXED_LAYOUTS[key] = _fixed_layout(msg, start)
    if fixed is None:
        return _walk_fields(msg, offset, path, out)
    rows, end = fixed
    base = offset - start
    for sub, at in rows:
        out[path + sub] = base + at
    return base + end


def _walk_fields(msg, offset, path, out):
    for name, slot in zip(msg.get_fields_and_field_types(), msg.SLOT_TYPES):
        offset = _walk_value(getattr(msg, name), slot, offset, path + (name,), out)
    return offset


_FIXED_LAYOUTS = {}  # (message class, offset % 8) -> (field offsets, end) or None
_UNSEEN = object()


def _fixed_layout(msg, start):
    """((path, offset) pairs, end) of `msg` laid out from `start`, if its type
    has no strings or sequences at any depth; else None."""
    if not _is_fixed(msg):
        return None
    out = {}
    end = _walk_fields(msg, start, (), out)
    return tuple(out.items()), end


def _is_fixed(msg):
    for name, t in zip(msg.get_fields_and_field_types(), msg.SLOT_TYPES):
        if isinstance(t, idl.NamespacedType):
            if not _is_fixed(getattr(msg, name)):
                return False
        elif not (isinstance(t, idl.BasicType) or (isinstance(t, idl.Array) and isinstance(t.value_type, idl.BasicType))):
            return False
    return True


def _walk_value(value, t, offset, path, out):
    if isinstance(t, idl.BasicType):
        size = _primitive_size(t)
        offset = _align(offset, size)
        out[path] = offset
        return offset + size
    if isinstance(t, idl.AbstractString):
        offset = _align(offset, 4)
        out[path] = offset
        return offset + 4 + len(value.encode()) + 1
    if isinstance(t, idl.NamespacedType):
        return _walk_message(value, offset, path, out)
    if isinstance(t, idl.AbstractNestedType) and not isinstance(t.value_type, idl.AbstractWString):
        count = len(value)
        if not isinstance(t, idl.Array):
            offset = _align(offset, 4)
            out[path] = offset
            offset += 4
        element = t.value_type
        if isinstance(element, idl.BasicType):
            size = _primitive_size(element)
            if count:
                offset = _align(offset, size)
            if isinstance(t, idl.Array):
                out[path] = offset
            return offset + count * size
        for i, item in enumerate(value):
            offset = _walk_value(item, element, offset, path + (i,), out)
        return offset
    raise CdrLayoutError(f"no CDR layout for {t!r} at {'.'.join(map(str, path))}")


def _checked(msg):
    """(rclpy's CDR bytes of `msg`, its layout offsets), checked against each other."""
    data = serialize_message(msg)
    offsets, size = layout(msg)
    if data[:HEADER_BYTES] != CDR_LE or len(data) != HEADER_BYTES + size:
        raise CdrLayoutError(
            f"{type(msg).__name__}: expected {HEADER_BYTES + size} bytes of little-endian CDR, "
            f"rclpy wrote {len(data)} starting {data[:HEADER_BYTES].hex()}"
        )
    return data, offsets


class _Slots:
    """Serialized messages side by side in one buffer, each one's CDR origin
    8-byte aligned, with typed views for writing fields in bulk.

    Message i spans `store[start[i]:end[i]]`; a field at origin offset `o`
    of message i sits at byte `origin[i] + o`."""

    def __init__(self, messages, serialized=None):
        """`serialized`: (CDR bytes, layout offsets) of each message, when
        already made (then `messages` is not read)."""
        if serialized is None:
            serialized = [_checked(m) for m in messages]
        self.offsets = []
        starts, ends = [], []
        at = 0
        for data, offsets in serialized:
            self.offsets.append(offsets)
            start = at + 8 - HEADER_BYTES  # origin on a multiple of 8
            starts.append(start)
            ends.append(start + len(data))
            at = _align(ends[-1], 8)
        self.store = np.zeros(max(at, 8), dtype=np.uint8)
        for start, (data, _) in zip(starts, serialized):
            self.store[start : start + len(data)] = np.frombuffer(data, dtype=np.uint8)
        self.start = np.array(starts, dtype=np.int64)
        self.end = np.array(ends, dtype=np.int64)
        self.origin = self.start + HEADER_BYTES
        self._views()

    def _views(self):
        s = self.store
        self.f64, self.f32 = s.view(np.float64), s.view(np.float32)
        self.i32, self.u32 = s.view(np.int32), s.view(np.uint32)

    def index(self, i, path, size):
        """Index of field `path` of message i in the view of `size`-byte items."""
        byte = int(self.origin[i]) + self.offsets[i][path]
        if byte % size:
            raise CdrLayoutError(f"field {path} is not {size}-byte aligned")
        return byte // size

    def stamp_index(self, i, header=("header",)):
        return self.index(i, header + ("stamp", "sec"), 4)

    def bytes(self, i=0, end=None):
        start = int(self.start[i])
        return self.store[start : int(self.end[i]) if end is None else end].tobytes()


def packed_sequence(wrapper_class, items, paths=()):
    """CDR bytes of a `wrapper_class` message (TFMessage, MarkerArray: one
    field, a sequence of messages) holding the messages `items` yields, and
    the origin offsets of `paths` in each: an (n, len(paths)) int64 array.

    `items` yields (message, key) pairs; the message may be one object
    mutated between items, since each is serialized before the next is
    drawn, and messages with equal keys must lay out alike (e.g. their
    strings are equally long). Each item is serialized by rclpy on its own:
    alone when it starts on a multiple of 8 from the origin, else inside a
    one-item wrapper, where it starts 4 past one, so every byte is still
    rclpy's. Making 10,000 message objects to serialize them together took
    1-2 s; this takes a tenth of that. The items start 4-aligned (their first
    field is an int32, as a header's stamp is)."""
    wrappers = {}  # id(message) -> a one-item wrapper holding it
    layouts = {}  # (key, start % 8) -> offsets of `paths` from the item's start
    parts, rows, at = [], [], 4  # the count, then the items
    for msg, key in items:
        at = _align(at, 4)
        start = at % 8
        wrapper = None
        if start:
            wrapper = wrappers.get(id(msg))
            if wrapper is None:
                wrapper = wrappers[id(msg)] = _one_item(wrapper_class, msg)
        data = _item_bytes(wrapper_class, msg, start, wrapper)
        rel = layouts.get((key, start))
        if rel is None:
            offsets, _ = layout(msg if start == 0 else wrappers[id(msg)])
            prefix = () if start == 0 else (_only_field(wrapper_class), 0)
            rel = layouts[(key, start)] = [offsets[prefix + p] - (0 if start == 0 else 4) for p in paths]
        rows.append([at + r for r in rel])
        parts.append(data)
        at += len(data)
    return _join_items(parts, rows, len(paths))


def _one_item(wrapper_class, msg):
    return wrapper_class(**{_only_field(wrapper_class): [msg]})


def _item_bytes(wrapper_class, msg, start, wrapper=None):
    """rclpy's CDR of `msg` as an item of a `wrapper_class` sequence starting
    at `start` (0 or 4) modulo 8 from the origin: serialized alone, or as the
    one item of a wrapper (`wrapper`, if made already)."""
    if start == 0:
        data = serialize_message(msg)
        if data[:HEADER_BYTES] != CDR_LE:
            raise CdrLayoutError(f"{type(msg).__name__}: rclpy wrote {data[:HEADER_BYTES].hex()}, not little-endian CDR")
        return data[HEADER_BYTES:]
    return serialize_message(wrapper or _one_item(wrapper_class, msg))[HEADER_BYTES + 4 :]


def _only_field(wrapper_class):
    (field,) = wrapper_class.get_fields_and_field_types()
    return field


def _join_items(parts, rows, width):
    """The encapsulation header, the count, then the items, each padded to 4."""
    out = bytearray(CDR_LE)
    out += struct.pack("<I", len(rows))
    for data in parts:
        out += b"\0" * (-(len(out) - HEADER_BYTES) % 4)
        out += data
    return bytes(out), np.array(rows, dtype=np.int64).reshape(len(rows), width)


def _split_stamp(stamp_ns):
    return divmod(int(stamp_ns), NS_PER_S)


def _ros_pose_rows(pos, quat, out):
    """Rows (x, y, z, qx, qy, qz, qw) of geometry_msgs/Pose from engine
    positions and (w, x, y, z) quaternions, into `out` (n, 7)."""
    out[:, 0:3] = pos
    out[:, 3:6] = quat[:, 1:4]
    out[:, 6] = quat[:, 0]
    return out


def clock_cdr(stamp_ns):
    """rosgraph_msgs/Clock at `stamp_ns`."""
    sec, nanosec = _split_stamp(stamp_ns)
    return CDR_LE + struct.pack("<iI", sec, nanosec)


class PoseArrayCdr:
    """`pose_array` as CDR bytes, for a fixed number of bodies.

    Every Pose is 7 doubles, so the message is its head, the count, and the
    same 56 bytes n times: rclpy serializes a 2-pose template (checked to be
    laid out so), and the rest is tiled. Making 10,000 Pose objects to
    serialize took 0.3 s."""

    def __init__(self, n, frame_id=WORLD_FRAME):
        self.n = int(n)
        template = pose_array(np.zeros((2, 3)), np.tile([1.0, 0, 0, 0], (2, 1)), 0, frame_id)
        data, offsets = _checked(template)
        count_at = offsets[("poses",)]
        first, second = offsets[("poses", 0, "position", "x")], offsets[("poses", 1, "position", "x")]
        if second != first + 56 or offsets[("poses", 1, "orientation", "w")] != second + 48 or first % 8:
            raise CdrLayoutError("poses are not contiguous")
        pose = data[HEADER_BYTES + first : HEADER_BYTES + second]
        head = data[: HEADER_BYTES + (first if self.n else count_at + 4)]
        offsets = {k: v for k, v in offsets.items() if k[:1] != ("poses",) or k == ("poses",)}
        self._slots = s = _Slots((), [(head + pose * self.n, offsets)])
        s.u32[s.index(0, ("poses",), 4)] = self.n
        self._stamp = s.stamp_index(0)
        self._poses = None
        if self.n:
            at = (int(s.origin[0]) + first) // 8
            self._poses = s.f64[at : at + 7 * self.n].reshape(self.n, 7)

    def build(self, pos, quat, stamp_ns):
        s = self._slots
        s.i32[self._stamp], s.u32[self._stamp + 1] = _split_stamp(stamp_ns)
        if self.n:
            _ros_pose_rows(pos, quat, self._poses)
        return s.bytes()


class OdometryCdr:
    """`BodyOdometry.build` as a list of CDR bytes, one per body.

    Only the bodies asked for are laid out, when first asked for (a scene of
    10,000 bodies took 1 s to lay out every body's message, and the node
    serves only the odometry someone reads); the layout rules are checked on
    one message at construction, so a CdrLayoutError still comes from here."""

    def __init__(self, names, frame_id=WORLD_FRAME):
        self.names = tuple(names)
        self.frame_id = frame_id
        self._prepare((0,) if self.names else ())
        self._prepared = None  # the rows laid out, as a tuple (None: none yet)
        self._asked = _UNSEEN  # the `rows` argument they were laid out for

    def _prepare(self, rows):
        zero3, unit = [0.0] * 3, [1.0, 0.0, 0.0, 0.0]
        msgs = [_odometry(self.names[i], zero3, unit, zero3, zero3, 0, self.frame_id) for i in rows]
        self._slots = s = _Slots(msgs)
        k = len(msgs)
        self._stamp = np.array([s.stamp_index(i) for i in range(k)], dtype=np.int64)
        pose = np.array([s.index(i, ("pose", "pose", "position", "x"), 8) for i in range(k)], dtype=np.int64)
        twist = np.array([s.index(i, ("twist", "twist", "linear", "x"), 8) for i in range(k)], dtype=np.int64)
        for i in range(k):  # Pose: 7 doubles, Twist: 6, each back to back
            if s.index(i, ("pose", "pose", "orientation", "w"), 8) != pose[i] + 6 or s.index(
                i, ("twist", "twist", "angular", "z"), 8
            ) != twist[i] + 5:
                raise CdrLayoutError("odometry pose or twist is not contiguous")
        self._pose_at = pose[:, None] + np.arange(7)
        self._twist_at = twist[:, None] + np.arange(6)
        self._rows = np.empty((k, 7))
        self._twists = np.empty((k, 6))
        self._spans = list(zip(s.start.tolist(), s.end.tolist()))
        self._prepared = tuple(rows)
        self._row_array = np.asarray(self._prepared, dtype=np.int64)

    def build(self, pos, quat, vel, omega, stamp_ns, rows=None):
        """The messages of every body, or of the bodies in `rows` (scene
        indexes, in that order): only those are written and copied out."""
        if rows is not self._asked:  # the same list as last time is the same rows
            wanted = tuple(range(len(self.names))) if rows is None else tuple(rows)
            if wanted != self._prepared:
                self._prepare(wanted)
            self._asked = rows
        wanted = self._prepared
        s = self._slots
        sec, nanosec = _split_stamp(stamp_ns)
        if len(wanted) != len(self.names):
            rows = self._row_array
            pos, quat, vel, omega = pos[rows], quat[rows], vel[rows], omega[rows]
        s.i32[self._stamp] = sec
        s.u32[self._stamp + 1] = nanosec
        s.f64[self._pose_at] = _ros_pose_rows(pos, quat, self._rows)
        # linear and angular velocity turned into body axes in one call
        self._twists.reshape(-1, 2, 3)[:] = rotate_to_body(quat[:, None, :], np.stack([vel, omega], axis=1))
        s.f64[self._twist_at] = self._twists
        blob = s.store.tobytes()
        return [blob[a:b] for a, b in self._spans]


def body_markers_cdr(model, pos, quat, stamp_ns, deleted=(), frame_id=WORLD_FRAME):
    """`body_markers` as CDR bytes, followed by a DELETE marker (stamped, no
    frame) for each (id, ns) in `deleted`.

    Body markers differ only in their name (ns and text), id, type, pose,
    scale and colour, and lay out alike when their names are as long and
    they start at the same offset modulo 8. So rclpy serializes one marker
    of each such kind (packed_sequence), and every body's is a copy of it
    with those fields written in: 10,000 bodies in 0.1 s, where serializing
    each marker took 0.6 s and making them as objects 1.7 s."""
    m = Marker()
    m.header.stamp = time_msg(stamp_ns)
    m.header.frame_id = frame_id
    out = bytearray(CDR_LE + struct.pack("<I", len(model.names) + len(deleted)))
    kinds = {}  # (name bytes, start % 8) -> (template bytes, offsets of _BODY_FIELDS in it)
    for i, name in enumerate(model.names):
        out += b"\0" * (-(len(out) - HEADER_BYTES) % 4)
        key = (len(name.encode()), (len(out) - HEADER_BYTES) % 8)
        kind = kinds.get(key)
        if kind is None:
            fill_body_marker(m, model, i, pos, quat)
            kind = kinds[key] = _marker_kind(m, key[1])
        _write_body_marker(out, kind, model, i, pos, quat)
    if deleted:
        gone = Marker(action=Marker.DELETE)
        gone.header.stamp = time_msg(stamp_ns)
        for marker_id, ns in deleted:
            gone.id, gone.ns = int(marker_id), ns
            out += b"\0" * (-(len(out) - HEADER_BYTES) % 4)
            out += _item_bytes(MarkerArray, gone, (len(out) - HEADER_BYTES) % 8)
    return bytes(out)


_BODY_FIELDS = (("ns",), ("id",), ("type",), ("pose", "position", "x"), ("pose", "orientation", "w"),
                ("scale", "x"), ("scale", "z"), ("color", "r"), ("color", "a"), ("text",))


def _marker_kind(m, start):
    """(rclpy's bytes of marker `m` starting at `start` modulo 8, the offsets
    of _BODY_FIELDS from its start), checked to be packed as written."""
    data = _item_bytes(MarkerArray, m, start)
    offsets, _ = layout(m if start == 0 else MarkerArray(markers=[m]))
    shift = 0 if start == 0 else 4
    at = dict(zip(_BODY_FIELDS, (offsets[(() if start == 0 else ("markers", 0)) + f] - shift for f in _BODY_FIELDS)))
    # id and type: two int32; pose: 7 doubles; scale: 3 doubles; colour: 4 float32, each run unbroken
    runs = ((("id",), ("type",), 4), (("pose", "position", "x"), ("pose", "orientation", "w"), 48),
            (("scale", "x"), ("scale", "z"), 16), (("color", "r"), ("color", "a"), 12))
    aligned = (start + at[("pose", "position", "x")]) % 8 == 0 == (start + at[("scale", "x")]) % 8
    if not aligned or any(at[last] != at[first] + span for first, last, span in runs):
        raise CdrLayoutError("Marker: id, pose, scale or colour not packed as assumed")
    return data, at


def _write_body_marker(out, kind, model, i, pos, quat):
    data, at = kind
    base = len(out)
    out += data
    name = model.names[i].encode()
    marker_type, scale, p, q = body_marker_shape(model, i, pos, quat)
    for field in (("ns",), ("text",)):
        out[base + at[field] + 4 : base + at[field] + 4 + len(name)] = name
    struct.pack_into("<ii", out, base + at[("id",)], i, marker_type)
    struct.pack_into("<7d", out, base + at[("pose", "position", "x")], *p, q[1], q[2], q[3], q[0])
    struct.pack_into("<3d", out, base + at[("scale", "x")], *scale)
    struct.pack_into("<4f", out, base + at[("color", "r")], *body_marker_rgba(model, i))


# Marker colours of the contact events, as the float32 a ColorRGBA carries.
_EVENT_COLOURS = np.array([_EVENT_RGBA[e] for e in (0, 1, 2)], dtype=np.float32)
_PERSIST = 1


class SceneMarkersCdr:
    """`SceneMarkers.build` as CDR bytes: the DELETEALL marker, the bodies at
    their poses, one arrow per contact event.

    Contact arrows differ only in stamp, id, points and colour, and an
    arrow's layout (its padding) depends only on where it starts modulo 8.
    So the buffer holds the head (DELETEALL and bodies), the first arrows up
    to where the start alignment repeats, then that period of arrows tiled
    as often as the contacts need."""

    _FIELDS = {  # what changes in an arrow: path, item size
        "stamp": (("header", "stamp", "sec"), 4),
        "id": (("id",), 4),
        "points": (("points", 0, "x"), 8),
        "colour": (("color", "r"), 4),
    }

    def __init__(self, model, frame_id=WORLD_FRAME, capacity=64):
        objects = SceneMarkers(model, frame_id)
        self._moving = np.array(objects._moving, dtype=np.int64)
        head = [objects._clear, *objects._bodies]
        self._head = h = len(head)
        probe = 10  # arrows in the template; start alignments (0 or 4) repeat within 3
        arrows = [contact_arrow(j, np.zeros(3), np.zeros(3), _PERSIST, 0, frame_id) for j in range(probe)]
        msg = MarkerArray(markers=[*head, *arrows])
        offsets, size = layout(msg)
        data = serialize_message(msg)
        if data[:HEADER_BYTES] != CDR_LE or len(data) != HEADER_BYTES + size:
            raise CdrLayoutError("MarkerArray: the CDR layout does not match rclpy's bytes")

        def marker(i, path):
            return offsets[("markers", i) + path]

        starts = [marker(h + j, ("header", "stamp", "sec")) for j in range(probe)]
        first_at = {}
        for j, start in enumerate(starts):
            if start % 8 in first_at:
                lead, period = first_at[start % 8], j - first_at[start % 8]
                break
            first_at[start % 8] = j
        else:
            raise CdrLayoutError("contact arrows do not repeat their layout")
        # Per template arrow: origin offsets of what changes, and of its end.
        self._arrow_fields = []
        for j in range(lead + period):
            fields = {key: marker(h + j, path) for key, (path, _) in self._FIELDS.items()}
            if marker(h + j, ("points", 1, "z")) != fields["points"] + 40:
                raise CdrLayoutError("arrow points are not contiguous")
            if marker(h + j, ("color", "a")) != fields["colour"] + 12:
                raise CdrLayoutError("arrow colour is not contiguous")
            fields["end"] = marker(h + j, ("mesh_use_embedded_materials",)) + 1
            self._arrow_fields.append(fields)
        self._lead, self._period = lead, period
        self._period_start = starts[lead]
        self._period_bytes = starts[lead + period] - starts[lead]
        self._head_end = marker(h - 1, ("mesh_use_embedded_materials",)) + 1
        raw = np.frombuffer(data, dtype=np.uint8)
        self._fixed = raw[: HEADER_BYTES + self._period_start]  # head and lead arrows
        self._tile = raw[HEADER_BYTES + self._period_start : HEADER_BYTES + self._period_start + self._period_bytes]
        self._count_at = offsets[("markers",)]
        self._head_stamps = np.array([marker(i, ("header", "stamp", "sec")) for i in range(h)], dtype=np.int64)
        self._body_poses = np.array([marker(1 + i, ("pose", "position", "x")) for i in self._moving], dtype=np.int64)
        for i, at in zip(self._moving, self._body_poses):
            if marker(1 + i, ("pose", "orientation", "w")) != at + 48:
                raise CdrLayoutError("marker pose is not contiguous")
        self._rows = np.empty((len(self._moving), 7))
        self._capacity = 0
        self._grow(capacity)

    def _grow(self, capacity):
        """A buffer with room for at least `capacity` contact arrows."""
        periods = max(1, -(-(int(capacity) - self._lead) // self._period))
        capacity = self._lead + periods * self._period
        self._base = base = 8 - HEADER_BYTES  # the message starts here, its CDR origin at 8
        origin = base + HEADER_BYTES
        store = np.zeros(_align(origin + self._period_start + periods * self._period_bytes, 8), dtype=np.uint8)
        store[base : base + len(self._fixed)] = self._fixed
        store[base + len(self._fixed) : origin + self._period_start + periods * self._period_bytes] = np.tile(
            self._tile, periods
        )
        self._store = store
        self._f64, self._f32 = store.view(np.float64), store.view(np.float32)
        self._i32, self._u32 = store.view(np.int32), store.view(np.uint32)

        j = np.arange(capacity)
        template = np.minimum(j, self._lead + (j - self._lead) % self._period)  # lead arrows, then the period
        shift = np.where(j < self._lead, 0, (j - self._lead) // self._period * self._period_bytes)

        def at(key, size=1):
            byte = origin + np.array([f[key] for f in self._arrow_fields])[template] + shift
            if np.any(byte % size):
                raise CdrLayoutError(f"arrow {key} is not {size}-byte aligned")
            return byte // size

        self._arrow_end = at("end")
        self._arrow_stamp = at("stamp", 4)
        self._arrow_points = at("points", 8)[:, None] + np.arange(6)
        self._arrow_colour = at("colour", 4)[:, None] + np.arange(4)
        self._i32[at("id", 4)] = j  # ids never change
        self._head_stamp_at = (origin + self._head_stamps) // 4
        self._body_pose_at = (origin + self._body_poses)[:, None] // 8 + np.arange(7)
        self._count_index = (origin + self._count_at) // 4
        self._head_end_at = origin + self._head_end
        self._capacity = capacity

    def build(self, pos, quat, contacts, stamp_ns):
        k = len(contacts)
        if k > self._capacity:
            self._grow(max(k, 2 * self._capacity))
        sec, nanosec = _split_stamp(stamp_ns)
        self._u32[self._count_index] = self._head + k
        self._i32[self._head_stamp_at] = sec
        self._u32[self._head_stamp_at + 1] = nanosec
        if len(self._moving):
            rows = _ros_pose_rows(np.asarray(pos)[self._moving], np.asarray(quat)[self._moving], self._rows)
            self._f64[self._body_pose_at] = rows
        end = self._head_end_at
        if k:
            stamps = self._arrow_stamp[:k]
            self._i32[stamps] = sec
            self._u32[stamps + 1] = nanosec
            start = np.asarray(contacts.point, dtype=np.float64)
            tip = start + CONTACT_ARROW_LENGTH * np.asarray(contacts.normal, dtype=np.float64)
            self._f64[self._arrow_points[:k]] = np.concatenate([start, tip], axis=1)
            event = np.asarray(contacts.event).astype(np.int64)
            event = np.where((event >= 0) & (event < len(_EVENT_COLOURS)), event, _PERSIST)
            self._f32[self._arrow_colour[:k]] = _EVENT_COLOURS[event]
            end = int(self._arrow_end[k - 1])
        return self._store[self._base : end].tobytes()


class ContactCloudCdr:
    """`contact_cloud` as CDR bytes: a fixed prefix (header, size, fields,
    steps), the packed points, and `is_dense`."""

    def __init__(self, frame_id=WORLD_FRAME):
        msg = contact_cloud(ContactArrays(np.zeros((0, 3)), np.zeros((0, 3)), *(np.zeros(0),) * 6), 0, frame_id)
        self._slots = s = _Slots([msg])
        offsets = s.offsets[0]
        self._stamp = s.stamp_index(0)
        self._width = s.index(0, ("width",), 4)
        self._row_step = s.index(0, ("row_step",), 4)
        if offsets[("is_dense",)] != offsets[("data",)] + 4:
            raise CdrLayoutError("PointCloud2 data is not followed by is_dense")
        self._prefix = (int(s.start[0]), int(s.origin[0]) + offsets[("data",)])
        self._point_step = msg.point_step
        self._dense = b"\x01" if msg.is_dense else b"\x00"

    def build(self, contacts, stamp_ns):
        s = self._slots
        data = contact_points(contacts).tobytes()
        k = len(data) // self._point_step
        s.i32[self._stamp], s.u32[self._stamp + 1] = _split_stamp(stamp_ns)
        s.u32[self._width] = k
        s.u32[self._row_step] = self._point_step * k
        start, end = self._prefix
        return b"".join((s.store[start:end].tobytes(), struct.pack("<I", len(data)), data, self._dense))
