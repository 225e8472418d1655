"""Body poses as tf2_msgs/TFMessage: `world` → each body (child frame = name).

`TransformsCdr` builds the message as CDR bytes for a fixed list of bodies
the way cdr.PoseArrayCdr does: rclpy serializes a template once, and each
step only the stamps and the 7 numbers of each transform are written, with
numpy, all bodies at once. The frame names are fixed per body list, so every
transform sits at the same offset every step.
"""

import numpy as np
from geometry_msgs.msg import TransformStamped
from tf2_msgs.msg import TFMessage

from .cdr import HEADER_BYTES, CdrLayoutError, _align, _ros_pose_rows, _split_stamp, packed_sequence
from .frames import WORLD_FRAME
from .stamps import time_msg


def transforms_message(names, pos, quat, stamp_ns, frame_id=WORLD_FRAME):
    """TFMessage with `frame_id` → names[i] at pos[i], quat[i] (w, x, y, z)."""
    msg = TFMessage()
    stamp = time_msg(stamp_ns)
    for name, p, q in zip(names, pos, quat):
        t = TransformStamped()
        t.header.stamp = stamp
        t.header.frame_id = frame_id
        t.child_frame_id = name
        t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = (float(v) for v in p)
        r = t.transform.rotation
        r.w, r.x, r.y, r.z = (float(v) for v in q)
        msg.transforms.append(t)
    return msg


class TransformsCdr:
    """`transforms_message` as CDR bytes for the bodies `names`."""

    def __init__(self, names, frame_id=WORLD_FRAME):
        self.names = tuple(names)
        n = len(self.names)
        data, at = packed_sequence(TFMessage, self._items(frame_id), _PATHS)
        # the message starts 4 bytes before a multiple of 8, so its CDR origin is on one
        self._store = store = np.zeros(_align(len(data) + 4, 8), dtype=np.uint8)
        store[4 : 4 + len(data)] = np.frombuffer(data, dtype=np.uint8)
        self._end = 4 + len(data)
        self._i32, self._u32, self._f64 = store.view(np.int32), store.view(np.uint32), store.view(np.float64)
        origin = 4 + HEADER_BYTES
        if np.any((origin + at[:, 1]) % 8) or np.any(at[:, 2] != at[:, 1] + 48):
            raise CdrLayoutError("TFMessage: a transform is not seven 8-byte aligned doubles in a row")
        self._stamps = (origin + at[:, 0]) // 4
        # translation (x, y, z) then rotation (x, y, z, w): seven doubles in a row
        self._rows = ((origin + at[:, 1]) // 8)[:, None] + np.arange(7)
        self._scratch = np.empty((n, 7))

    def _items(self, frame_id):
        t = TransformStamped()
        t.header.frame_id = frame_id
        t.transform.rotation.w = 1.0
        for name in self.names:
            t.child_frame_id = name
            yield t, len(name.encode())

    def build(self, pos, quat, stamp_ns):
        if len(self.names):
            sec, nanosec = _split_stamp(stamp_ns)
            self._i32[self._stamps] = sec
            self._u32[self._stamps + 1] = nanosec
            self._f64[self._rows] = _ros_pose_rows(pos, quat, self._scratch)
        return self._store[4 : self._end].tobytes()


_PATHS = (("header", "stamp", "sec"), ("transform", "translation", "x"), ("transform", "rotation", "w"))
