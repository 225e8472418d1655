"""Contact events as a sensor_msgs/PointCloud2, and back.

One point per contact event of a step. Geometry (point, normal) is float32 as
point-cloud viewers expect; the physics quantities (impulses in N·s, normal
speed in m/s) are float64 so they survive the trip exactly.
"""

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from sensor_msgs.msg import PointCloud2, PointField

from .frames import WORLD_FRAME
from .stamps import time_msg

EVENT_BEGIN, EVENT_PERSIST, EVENT_END = 0, 1, 2

# (name, PointField datatype, byte offset); padded to 64 bytes so the float64
# members stay 8-byte aligned in every point.
CONTACT_FIELDS = (
    ("x", PointField.FLOAT32, 0),
    ("y", PointField.FLOAT32, 4),
    ("z", PointField.FLOAT32, 8),
    ("normal_x", PointField.FLOAT32, 12),
    ("normal_y", PointField.FLOAT32, 16),
    ("normal_z", PointField.FLOAT32, 20),
    ("impulse", PointField.FLOAT64, 24),
    ("friction_impulse", PointField.FLOAT64, 32),
    ("normal_speed", PointField.FLOAT64, 40),
    ("body_a", PointField.UINT32, 48),
    ("body_b", PointField.UINT32, 52),
    ("event", PointField.UINT8, 56),
)
CONTACT_POINT_STEP = 64

_NUMPY_OF_DATATYPE = {
    PointField.INT8: "i1",
    PointField.UINT8: "u1",
    PointField.INT16: "i2",
    PointField.UINT16: "u2",
    PointField.INT32: "i4",
    PointField.UINT32: "u4",
    PointField.FLOAT32: "f4",
    PointField.FLOAT64: "f8",
}


@dataclass
class ContactArrays:
    """Contact events of one step as parallel arrays (k events)."""

    point: np.ndarray  # (k, 3) m, world frame
    normal: np.ndarray  # (k, 3) unit, world frame
    impulse: np.ndarray  # (k,) N·s along the normal
    friction_impulse: np.ndarray  # (k,) N·s
    normal_speed: np.ndarray  # (k,) m/s
    body_a: np.ndarray  # (k,) scene index
    body_b: np.ndarray  # (k,) scene index
    event: np.ndarray  # (k,) 0 begin, 1 persist, 2 end

    def __len__(self):
        return len(self.impulse)


@lru_cache(maxsize=None)
def _contact_dtype(big_endian=False):
    order = ">" if big_endian else "<"
    return np.dtype(
        {
            "names": [name for name, _, _ in CONTACT_FIELDS],
            "formats": [order + _NUMPY_OF_DATATYPE[dt] for _, dt, _ in CONTACT_FIELDS],
            "offsets": [offset for _, _, offset in CONTACT_FIELDS],
            "itemsize": CONTACT_POINT_STEP,
        }
    )


def contact_points(contacts):
    """The points of a contact cloud: one 64-byte record per event, laid out
    as CONTACT_FIELDS, in a numpy structured array."""
    k = len(contacts)
    points = np.zeros(k, dtype=_contact_dtype())
    if k:
        point = np.asarray(contacts.point)
        normal = np.asarray(contacts.normal)
        for axis, suffix in enumerate("xyz"):
            points[suffix] = point[:, axis]
            points["normal_" + suffix] = normal[:, axis]
        points["impulse"] = contacts.impulse
        points["friction_impulse"] = contacts.friction_impulse
        points["normal_speed"] = contacts.normal_speed
        points["body_a"] = contacts.body_a
        points["body_b"] = contacts.body_b
        points["event"] = contacts.event
    return points


def contact_cloud(contacts, stamp_ns, frame_id=WORLD_FRAME):
    """PointCloud2 from the engine's contact events (anything with the
    ContactArrays attributes)."""
    points = contact_points(contacts)
    k = len(points)
    msg = PointCloud2()
    msg.header.stamp = time_msg(stamp_ns)
    msg.header.frame_id = frame_id
    msg.height = 1
    msg.width = k
    msg.fields = [PointField(name=n, offset=o, datatype=d, count=1) for n, d, o in CONTACT_FIELDS]
    msg.is_bigendian = False
    msg.point_step = CONTACT_POINT_STEP
    msg.row_step = CONTACT_POINT_STEP * k
    msg.data = points.tobytes()
    msg.is_dense = True
    return msg


def cloud_to_structured(msg):
    """Any PointCloud2 as a numpy structured array, one record per point,
    following the message's own field list (names, offsets, types, endianness)."""
    order = ">" if msg.is_bigendian else "<"
    names, formats, offsets = [], [], []
    for field in msg.fields:
        base = order + _NUMPY_OF_DATATYPE[field.datatype]
        names.append(field.name)
        formats.append(base if field.count <= 1 else (base, (field.count,)))
        offsets.append(field.offset)
    dtype = np.dtype({"names": names, "formats": formats, "offsets": offsets, "itemsize": msg.point_step})
    n = msg.width * msg.height
    raw = bytes(msg.data)
    if msg.height > 1 and msg.row_step != msg.point_step * msg.width:
        # Rows may carry padding; drop it row by row.
        raw = b"".join(
            raw[r * msg.row_step : r * msg.row_step + msg.point_step * msg.width] for r in range(msg.height)
        )
    return np.frombuffer(raw, dtype=dtype, count=n)


def contacts_from_cloud(msg):
    """ContactArrays from a contact PointCloud2 (the inverse of contact_cloud)."""
    pts = cloud_to_structured(msg)

    def col(name, dtype):
        return np.ascontiguousarray(pts[name], dtype=dtype)

    return ContactArrays(
        point=np.stack([col(a, np.float64) for a in ("x", "y", "z")], axis=-1).reshape(-1, 3),
        normal=np.stack([col("normal_" + a, np.float64) for a in "xyz"], axis=-1).reshape(-1, 3),
        impulse=col("impulse", np.float64),
        friction_impulse=col("friction_impulse", np.float64)
        if "friction_impulse" in pts.dtype.names
        else np.zeros(len(pts)),
        normal_speed=col("normal_speed", np.float64),
        body_a=col("body_a", np.int64),
        body_b=col("body_b", np.int64),
        event=col("event", np.uint8),
    )
