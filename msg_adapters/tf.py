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

from .cdr import _ros_pose_rows, _Slots, _split_stamp
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
        template = transforms_message(self.names, np.zeros((n, 3)), np.tile([1.0, 0, 0, 0], (n, 1)), 0, frame_id)
        self._slots = s = _Slots([template])
        self._stamps = np.array([s.stamp_index(0, ("transforms", i, "header")) for i in range(n)], dtype=np.int64)
        first = [s.index(0, ("transforms", i, "transform", "translation", "x"), 8) for i in range(n)]
        # translation (x, y, z) then rotation (x, y, z, w): seven doubles in a row
        self._rows = np.array(first, dtype=np.int64)[:, None] + np.arange(7)
        self._scratch = np.empty((n, 7))

    def build(self, pos, quat, stamp_ns):
        s = self._slots
        if len(self.names):
            sec, nanosec = _split_stamp(stamp_ns)
            s.i32[self._stamps] = sec
            s.u32[self._stamps + 1] = nanosec
            s.f64[self._rows] = _ros_pose_rows(pos, quat, self._scratch)
        return s.bytes()
