"""Vectorised unit-quaternion algebra, (w, x, y, z) order, arrays of shape (n, 4).

Orientation is kept as unit quaternions (COURSE.md section 3) because they
compose without drift of the rotation axes and renormalise cheaply.

Each array function has a compiled one-body twin at the end of the module
(`rotate_one`, `integrate_one`, ...) for the loops over bodies of the
integrate stage.
"""
import math

import numpy as np
from numba import njit

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


# ---- one body at a time, compiled --------------------------------------------
# The same formulas for a single body, with quaternions as 4-tuples (w, x, y, z)
# and vectors as 3-tuples, for the compiled loops over bodies of the integrate
# stage (integrators.py, free_rotation.py, effects/). Each is written with the
# operations of its array version above, in the same order, so both round alike.
# They are inlined where they are called (inline="always"): called, each
# passed its tuples through memory, and the integrate stage's loop over
# 1,000 spinning spheres took 168 µs a substep against 62 inlined (the
# same bits).

@njit(cache=True, inline="always")
def cross_one(a, b):
    """a × b for two 3-tuples (vec3.cross)."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@njit(cache=True, inline="always")
def _rotate_by(w, u, v):
    t = cross_one(u, v)
    t = (2.0 * t[0], 2.0 * t[1], 2.0 * t[2])
    c = cross_one(u, t)
    return (v[0] + w * t[0] + c[0], v[1] + w * t[1] + c[1], v[2] + w * t[2] + c[2])


@njit(cache=True, inline="always")
def rotate_one(q, v):
    """`rotate` for one body: v from body to world frame, q v q*."""
    return _rotate_by(q[0], (q[1], q[2], q[3]), v)


@njit(cache=True, inline="always")
def rotate_inverse_one(q, v):
    """`rotate_inverse` for one body: v from world to body frame, q* v q."""
    return _rotate_by(q[0], (-q[1], -q[2], -q[3]), v)


@njit(cache=True, inline="always")
def multiply_one(p, q):
    """Hamilton product p ⊗ q of two 4-tuples (`multiply`)."""
    pw, px, py, pz = p
    qw, qx, qy, qz = q
    return (pw * qw - px * qx - py * qy - pz * qz,
            pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw)


@njit(cache=True, inline="always")
def normalize_one(q):
    """q / |q| (`normalize`)."""
    n = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    return (q[0] / n, q[1] / n, q[2] / n, q[3] / n)


@njit(cache=True, inline="always")
def from_rotation_vector_one(phi):
    """`from_rotation_vector` for one rotation vector (exact map, Taylor branch near 0)."""
    angle = math.sqrt(phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2])
    half = 0.5 * angle
    k = 0.5 - angle * angle / 48.0 if angle < 1e-8 else math.sin(half) / angle
    return (math.cos(half), phi[0] * k, phi[1] * k, phi[2] * k)


@njit(cache=True, inline="always")
def integrate_one(q, omega, dt):
    """`integrate` for one body: q advanced by world ω over dt (COURSE.md 3, 4)."""
    r = from_rotation_vector_one((omega[0] * dt, omega[1] * dt, omega[2] * dt))
    return normalize_one(multiply_one(r, q))


@njit(cache=True, inline="always")
def derivative_one(q, omega):
    """`derivative` for one body: dq/dt = ½ (0, ω) ⊗ q."""
    d = multiply_one((0.0, omega[0], omega[1], omega[2]), q)
    return (0.5 * d[0], 0.5 * d[1], 0.5 * d[2], 0.5 * d[3])


@njit(cache=True, inline="always")
def to_matrix_one(q):
    """`to_matrix` for one body: the rows of R (body → world) as three 3-tuples."""
    w, x, y, z = q
    xx, yy, zz = x * x, y * y, z * z
    xy, xz, yz = x * y, x * z, y * z
    wx, wy, wz = w * x, w * y, w * z
    return ((1 - 2 * (yy + zz), 2 * (xy - wz), 2 * (xz + wy)),
            (2 * (xy + wz), 1 - 2 * (xx + zz), 2 * (yz - wx)),
            (2 * (xz - wy), 2 * (yz + wx), 1 - 2 * (xx + yy)))


@njit(cache=True, inline="always")
def row3(a, i):
    """Row i of an (n, 3) array as a 3-tuple."""
    return (a[i, 0], a[i, 1], a[i, 2])


@njit(cache=True, inline="always")
def row4(a, i):
    """Row i of an (n, 4) array as a 4-tuple."""
    return (a[i, 0], a[i, 1], a[i, 2], a[i, 3])
