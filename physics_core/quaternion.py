"""Vectorised unit-quaternion algebra, (w, x, y, z) order, arrays of shape (n, 4).

Orientation is kept as unit quaternions (COURSE.md section 3) because they
compose without drift of the rotation axes and renormalise cheaply.
"""
import numpy as np

from .vec3 import cross


def multiply(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Hamilton product p ⊗ q for arrays of quaternions (..., 4)."""
    pw, px, py, pz = p[..., 0], p[..., 1], p[..., 2], p[..., 3]
    qw, qx, qy, qz = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    out = np.empty(np.broadcast_shapes(p.shape, q.shape))
    out[..., 0] = pw * qw - px * qx - py * qy - pz * qz
    out[..., 1] = pw * qx + px * qw + py * qz - pz * qy
    out[..., 2] = pw * qy - px * qz + py * qw + pz * qx
    out[..., 3] = pw * qz + px * qy - py * qx + pz * qw
    return out


def normalize(q: np.ndarray) -> np.ndarray:
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices (n, 3, 3) mapping body axes to world axes."""
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    m = np.empty(q.shape[:-1] + (3, 3))
    xx, yy, zz = x * x, y * y, z * z
    xy, xz, yz = x * y, x * z, y * z
    wx, wy, wz = w * x, w * y, w * z
    m[..., 0, 0] = 1 - 2 * (yy + zz)
    m[..., 0, 1] = 2 * (xy - wz)
    m[..., 0, 2] = 2 * (xz + wy)
    m[..., 1, 0] = 2 * (xy + wz)
    m[..., 1, 1] = 1 - 2 * (xx + zz)
    m[..., 1, 2] = 2 * (yz - wx)
    m[..., 2, 0] = 2 * (xz - wy)
    m[..., 2, 1] = 2 * (yz + wx)
    m[..., 2, 2] = 1 - 2 * (xx + yy)
    return m


def rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate vectors v (n, 3) from body to world frame: q v q*."""
    w = q[..., :1]
    u = q[..., 1:]
    t = 2.0 * cross(u, v)
    return v + w * t + cross(u, t)


def rotate_inverse(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate vectors v (n, 3) from world to body frame: q* v q."""
    w = q[..., :1]
    u = -q[..., 1:]
    t = 2.0 * cross(u, v)
    return v + w * t + cross(u, t)


def from_rotation_vector(phi: np.ndarray) -> np.ndarray:
    """Exact exponential map: the unit quaternion of rotation vector phi (n, 3).

    Used to advance orientation by ω dt without leaving the unit sphere;
    the Taylor branch keeps small angles free of 0/0.
    """
    angle = np.linalg.norm(phi, axis=-1, keepdims=True)
    half = 0.5 * angle
    small = angle < 1e-8
    # sin(a/2)/a, with its series 1/2 - a²/48 near zero
    safe = np.where(small, 1.0, angle)
    k = np.where(small, 0.5 - angle * angle / 48.0, np.sin(half) / safe)
    out = np.empty(phi.shape[:-1] + (4,))
    out[..., :1] = np.cos(half)
    out[..., 1:] = phi * k
    return out


def integrate(q: np.ndarray, omega: np.ndarray, dt: float) -> np.ndarray:
    """Advance orientations by world-frame angular velocity over dt (COURSE.md 3, 4)."""
    return normalize(multiply(from_rotation_vector(omega * dt), q))


def derivative(q: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """dq/dt = ½ (0, ω) ⊗ q for world-frame ω (used by explicit Euler and RK4)."""
    wq = np.zeros(q.shape)
    wq[..., 1:] = omega
    return 0.5 * multiply(wq, q)
