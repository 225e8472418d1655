"""Small compiled vector and quaternion helpers for the kernels (COURSE.md 3).

Quaternions are (w, x, y, z), body → world, as in quaternion.py. Every
function works on one body's numbers (scalars and rows of arrays) so that
the kernels stay plain loops over bodies, pairs and contacts.
"""
import math

import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def dot3(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True)
def rotation_matrix(q, out):
    """out (3, 3) = R(q), mapping body axes to world axes."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    xx, yy, zz = x * x, y * y, z * z
    xy, xz, yz = x * y, x * z, y * z
    wx, wy, wz = w * x, w * y, w * z
    out[0, 0] = 1 - 2 * (yy + zz)
    out[0, 1] = 2 * (xy - wz)
    out[0, 2] = 2 * (xz + wy)
    out[1, 0] = 2 * (xy + wz)
    out[1, 1] = 1 - 2 * (xx + zz)
    out[1, 2] = 2 * (yz - wx)
    out[2, 0] = 2 * (xz - wy)
    out[2, 1] = 2 * (yz + wx)
    out[2, 2] = 1 - 2 * (xx + yy)


@njit(cache=True)
def world_inverse_inertia(q, inv_inertia, out):
    """out (3, 3) = I_w⁻¹ = R diag(I⁻¹) Rᵀ (COURSE.md 3)."""
    R = np.empty((3, 3))
    rotation_matrix(q, R)
    for i in range(3):
        for j in range(3):
            out[i, j] = (R[i, 0] * inv_inertia[0] * R[j, 0] + R[i, 1] * inv_inertia[1] * R[j, 1]
                         + R[i, 2] * inv_inertia[2] * R[j, 2])


@njit(cache=True)
def turn_quaternion(q, wx, wy, wz, h, out):
    """out = normalize(exp(ω h) ⊗ q): orientation advanced by world angular
    velocity ω over h with the exact exponential map (quaternion.integrate)."""
    px, py, pz = wx * h, wy * h, wz * h
    angle = math.sqrt(px * px + py * py + pz * pz)
    half = 0.5 * angle
    k = 0.5 - angle * angle / 48.0 if angle < 1e-8 else math.sin(half) / angle
    rw, rx, ry, rz = math.cos(half), px * k, py * k, pz * k
    qw, qx, qy, qz = q[0], q[1], q[2], q[3]
    ow = rw * qw - rx * qx - ry * qy - rz * qz
    ox = rw * qx + rx * qw + ry * qz - rz * qy
    oy = rw * qy - rx * qz + ry * qw + rz * qx
    oz = rw * qz + rx * qy - ry * qx + rz * qw
    norm = math.sqrt(ow * ow + ox * ox + oy * oy + oz * oz)
    out[0], out[1], out[2], out[3] = ow / norm, ox / norm, oy / norm, oz / norm
