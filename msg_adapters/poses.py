"""Body states to and from PoseArray and Odometry.

Positions and quaternions stay float64 end to end, so a PoseArray holds the
engine's state bit for bit (replay compares them exactly).
"""

import numpy as np
from geometry_msgs.msg import Pose, PoseArray
from nav_msgs.msg import Odometry

from .frames import WORLD_FRAME, rotate_to_body, rotate_to_world
from .stamps import time_msg


def _pose(p, q):
    pose = Pose()
    pose.position.x, pose.position.y, pose.position.z = float(p[0]), float(p[1]), float(p[2])
    o = pose.orientation
    o.w, o.x, o.y, o.z = float(q[0]), float(q[1]), float(q[2]), float(q[3])
    return pose


def pose_array(pos, quat, stamp_ns, frame_id=WORLD_FRAME):
    """PoseArray of every body in scene order; `quat` rows are (w, x, y, z)."""
    msg = PoseArray()
    msg.header.stamp = time_msg(stamp_ns)
    msg.header.frame_id = frame_id
    msg.poses = [_pose(p, q) for p, q in zip(pos.tolist(), quat.tolist())]
    return msg


def arrays_from_pose_array(msg):
    """(pos (n,3), quat (n,4) as w,x,y,z) float64 arrays from a PoseArray."""
    n = len(msg.poses)
    pos = np.empty((n, 3))
    quat = np.empty((n, 4))
    for i, pose in enumerate(msg.poses):
        p, o = pose.position, pose.orientation
        pos[i] = (p.x, p.y, p.z)
        quat[i] = (o.w, o.x, o.y, o.z)
    return pos, quat


def odometry(name, pos, quat, vel, omega, stamp_ns, frame_id=WORLD_FRAME):
    """Odometry of one body.

    nav_msgs/Odometry gives the pose in `header.frame_id` and the twist in
    `child_frame_id`, so the world-frame velocities are turned into body axes.
    Covariances stay zero: the simulation knows its state exactly.
    """
    return _odometry(name, pos, quat, rotate_to_body(quat, vel), rotate_to_body(quat, omega), stamp_ns, frame_id)


def odometries(names, pos, quat, vel, omega, stamp_ns, frame_id=WORLD_FRAME):
    """Odometry of every body (rows of the state arrays), rotating all
    twists into body axes at once."""
    v_body = rotate_to_body(quat, vel).tolist()
    w_body = rotate_to_body(quat, omega).tolist()
    return [
        _odometry(name, p, q, v, w, stamp_ns, frame_id)
        for name, p, q, v, w in zip(names, pos.tolist(), quat.tolist(), v_body, w_body)
    ]


class BodyOdometry:
    """Builds `odometries` step after step, reusing one message per body."""

    def __init__(self, names, frame_id=WORLD_FRAME):
        self.names = tuple(names)
        self.frame_id = frame_id
        self._msgs = [None] * len(self.names)

    def build(self, pos, quat, vel, omega, stamp_ns):
        v_body = rotate_to_body(quat, vel).tolist()
        w_body = rotate_to_body(quat, omega).tolist()
        rows = zip(self.names, pos.tolist(), quat.tolist(), v_body, w_body)
        for i, (name, p, q, v, w) in enumerate(rows):
            self._msgs[i] = _odometry(name, p, q, v, w, stamp_ns, self.frame_id, self._msgs[i])
        return self._msgs


def _odometry(name, pos, quat, v_body, w_body, stamp_ns, frame_id, msg=None):
    if msg is None:
        msg = Odometry()
        msg.header.frame_id = frame_id
        msg.child_frame_id = name
    msg.header.stamp = time_msg(stamp_ns)
    p, o = msg.pose.pose.position, msg.pose.pose.orientation
    p.x, p.y, p.z = float(pos[0]), float(pos[1]), float(pos[2])
    o.w, o.x, o.y, o.z = float(quat[0]), float(quat[1]), float(quat[2]), float(quat[3])
    t = msg.twist.twist
    t.linear.x, t.linear.y, t.linear.z = (float(x) for x in v_body)
    t.angular.x, t.angular.y, t.angular.z = (float(x) for x in w_body)
    return msg


def state_from_odometry(msg):
    """(pos, quat wxyz, vel, omega) with velocities back in world axes."""
    p, o = msg.pose.pose.position, msg.pose.pose.orientation
    pos = np.array([p.x, p.y, p.z])
    quat = np.array([o.w, o.x, o.y, o.z])
    lin, ang = msg.twist.twist.linear, msg.twist.twist.angular
    vel = rotate_to_world(quat, [lin.x, lin.y, lin.z])
    omega = rotate_to_world(quat, [ang.x, ang.y, ang.z])
    return pos, quat, vel, omega
