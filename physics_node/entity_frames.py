"""Poses and twists of bodies seen from a reference frame: `world` (or an
empty frame id) or another body.

A body F at (p_F, q_F) moving with (v_F, ω_F) sees a body B at
    p = R_Fᵀ (p_B − p_F),        q = q_F* ⊗ q_B,
    v = R_Fᵀ (v_B − v_F − ω_F × (p_B − p_F)),    ω = R_Fᵀ (ω_B − ω_F),
the position, orientation and velocities of B relative to F in F's axes (the
velocity as an observer fixed to F measures it). `to_world` is the inverse.
"""

from dataclasses import dataclass

import numpy as np

from msg_adapters.frames import WORLD_FRAME, rotate_to_body, rotate_to_world
from physics_core.quaternion import multiply_one


class FrameError(LookupError):
    """A reference frame that is neither `world` nor a body."""


@dataclass
class Motion:
    """Pose and twist; orientation is (w, x, y, z)."""

    pos: np.ndarray
    quat: np.ndarray
    vel: np.ndarray
    omega: np.ndarray


def is_world(frame):
    return frame in ("", WORLD_FRAME)


def body_motion(world, name):
    i = world.model.index[name]
    s = world.state
    return Motion(s.pos[i].copy(), s.quat[i].copy(), s.vel[i].copy(), s.omega[i].copy())


def frame_motion(world, frame):
    """Motion of the reference `frame`, or None for the world frame."""
    if is_world(frame):
        return None
    if frame not in world.model.index:
        raise FrameError(f"unknown reference frame {frame!r}: use 'world' (or empty) or a body name")
    return body_motion(world, frame)


def _multiply(p, q):
    return np.array(multiply_one(np.asarray(p, dtype=float), np.asarray(q, dtype=float)), dtype=float)


def _conjugate(q):
    return np.array([q[0], -q[1], -q[2], -q[3]])


def to_frame(motion, frame):
    """`motion` (world) as seen from `frame` (a Motion, or None for world)."""
    if frame is None:
        return motion
    r = motion.pos - frame.pos
    relative_vel = motion.vel - frame.vel - np.cross(frame.omega, r)
    return Motion(
        rotate_to_body(frame.quat, r),
        _multiply(_conjugate(frame.quat), motion.quat),
        rotate_to_body(frame.quat, relative_vel),
        rotate_to_body(frame.quat, motion.omega - frame.omega),
    )


def to_world(motion, frame):
    """`motion` given in `frame` (a Motion, or None for world) in world terms."""
    if frame is None:
        return motion
    r = rotate_to_world(frame.quat, motion.pos)
    return Motion(
        frame.pos + r,
        _multiply(frame.quat, motion.quat),
        frame.vel + np.cross(frame.omega, r) + rotate_to_world(frame.quat, motion.vel),
        frame.omega + rotate_to_world(frame.quat, motion.omega),
    )
