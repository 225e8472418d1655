"""Quaternion helpers shared by the adapters.

The engine stores orientations as (w, x, y, z); ROS messages as (x, y, z, w).
Each quaternion maps body axes onto world axes: v_world = q ⊗ v_body ⊗ q*.
"""

import numpy as np

WORLD_FRAME = "world"


def _cross(a, b):
    # Written out: np.cross costs ~20 µs of axis bookkeeping per call, more
    # than the arithmetic on a few vectors, and it runs for every body and step.
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def rotate_to_world(quat_wxyz, v_body):
    """Rotate body-axis vectors into world axes (one quaternion, or one per row)."""
    q = np.asarray(quat_wxyz, dtype=np.float64)
    v = np.asarray(v_body, dtype=np.float64)
    w = q[..., :1]
    u = q[..., 1:]
    # v' = v + 2w (u × v) + 2 u × (u × v), the expanded sandwich product.
    t = 2.0 * _cross(u, v)
    return v + w * t + _cross(u, t)


def rotate_to_body(quat_wxyz, v_world):
    """Rotate world-axis vectors into body axes (inverse of rotate_to_world)."""
    q = np.asarray(quat_wxyz, dtype=np.float64)
    conj = np.concatenate([q[..., :1], -q[..., 1:]], axis=-1)
    return rotate_to_world(conj, v_world)


def quat_between_z_and(normal):
    """Unit quaternion (w, x, y, z) turning +z onto `normal` (used to lay planes)."""
    n = np.asarray(normal, dtype=np.float64)
    n = n / np.linalg.norm(n)
    z = np.array([0.0, 0.0, 1.0])
    d = float(np.dot(z, n))
    if d < -1.0 + 1e-12:
        return np.array([0.0, 1.0, 0.0, 0.0])  # half turn about x
    axis = np.cross(z, n)
    q = np.array([1.0 + d, axis[0], axis[1], axis[2]])
    return q / np.linalg.norm(q)
