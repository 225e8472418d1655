"""Row-wise 3-vector products for arrays of shape (..., 3).

`cross` is numpy's formula written out: for the few-row arrays of a small
scene, np.cross spends most of its time moving axes, and it is called
several times per sub-step (rotations, torques r × F).
"""
import numpy as np


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a × b per row, broadcasting leading axes."""
    ax, ay, az = a[..., 0], a[..., 1], a[..., 2]
    bx, by, bz = b[..., 0], b[..., 1], b[..., 2]
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = ay * bz - az * by
    out[..., 1] = az * bx - ax * bz
    out[..., 2] = ax * by - ay * bx
    return out


def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a · b per row of two (n, 3) arrays."""
    return np.einsum("ij,ij->i", a, b)
