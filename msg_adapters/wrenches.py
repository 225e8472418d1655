"""WrenchStamped commands to and from (frame, force, torque) arrays.

A command's `header.frame_id` names the axes its vectors are given in:
`world` (or empty) for world axes, or the commanded body's own name for its
body axes.
"""

import numpy as np
from geometry_msgs.msg import WrenchStamped

from .frames import WORLD_FRAME, rotate_to_world
from .stamps import time_msg


def wrench_arrays(msg):
    """(frame_id, force (3,), torque (3,)) from a WrenchStamped."""
    f, t = msg.wrench.force, msg.wrench.torque
    return (
        msg.header.frame_id,
        np.array([f.x, f.y, f.z], dtype=np.float64),
        np.array([t.x, t.y, t.z], dtype=np.float64),
    )


def wrench_stamped(force, torque=(0.0, 0.0, 0.0), frame_id=WORLD_FRAME, stamp_ns=0):
    """WrenchStamped from force (N or N·s) and torque (N·m or N·m·s) vectors."""
    msg = WrenchStamped()
    msg.header.stamp = time_msg(stamp_ns)
    msg.header.frame_id = frame_id
    w = msg.wrench
    w.force.x, w.force.y, w.force.z = (float(x) for x in force)
    w.torque.x, w.torque.y, w.torque.z = (float(x) for x in torque)
    return msg


def is_world_frame(frame_id):
    return frame_id in ("", WORLD_FRAME)


def to_world_axes(frame_id, body_name, quat_wxyz, force, torque):
    """Force and torque in world axes, or None when `frame_id` is not understood."""
    if is_world_frame(frame_id):
        return force, torque
    if frame_id == body_name:
        return rotate_to_world(quat_wxyz, force), rotate_to_world(quat_wxyz, torque)
    return None
