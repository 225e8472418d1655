"""What compiled collision detection reads about the shapes, packed once per
model, and the pose arithmetic its kernels share (COURSE.md 5: detection
needs each body's shape and pose to find point, normal and depth).

`Geometry.from_model(model)` packs the frozen shape data into four
contiguous arrays (a jitted call pays per argument, so few and flat):

    kind       (n,)   int64    shapes.py code: SPHERE, BOX or PLANE
    dims       (n, 8) float64  [radius, hx, hy, hz, plane nx, ny, nz, plane offset]
    is_static  (n,)   bool
    reach      (n,)   float64  bounding-sphere radius about the centre (0 for planes)

The @njit helpers below repeat numpy's arithmetic operation for operation,
so the compiled detector gives the numpy detector's bits (manifold.detect):

- a 3-term sum that numpy's einsum takes over a contiguous axis comes out
  as (x0 + x2) + x1 (its SIMD loop adds lanes 0 and 2, then lane 1), over a
  strided axis as (x0 + x1) + x2: `dot_lanes` and `dot_seq`;
- quaternion → matrix and rotations are quaternion.py's formulas;
- `fma` is the fused multiply-add (one rounding) that OpenBLAS uses in the
  products numpy's matmul hands it (broad phase plane heights, grid.py).

Those orders were measured against numpy 2.4 with its AVX2/AVX-512 einsum
loops and OpenBLAS 0.3.31 on x86-64; a numpy built otherwise may round a
sum differently in the last bit (the tests allow 1e-12 m).
"""
from dataclasses import dataclass

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic

from ..shapes import BOX, PLANE, SPHERE

# columns of `dims`
RADIUS, HALF, NORMAL, OFFSET = 0, 1, 4, 7
DIMS = 8

__all__ = ["Geometry", "bounding_radius", "RADIUS", "HALF", "NORMAL", "OFFSET", "SPHERE", "BOX", "PLANE",
           "fma", "dot_lanes", "dot_seq", "quat_matrix", "body_axes", "rotate",
           "rotate_inverse", "sign", "clip"]


@dataclass(frozen=True)
class Geometry:
    kind: np.ndarray        # (n,) int64 shape code
    dims: np.ndarray        # (n, 8) float64, columns RADIUS, HALF..HALF+2, NORMAL..NORMAL+2, OFFSET
    is_static: np.ndarray   # (n,) bool
    reach: np.ndarray       # (n,) float64 bounding radius, m

    @property
    def n(self) -> int:
        return len(self.kind)

    @classmethod
    def from_model(cls, model) -> "Geometry":
        n = model.n
        dims = np.zeros((n, DIMS))
        dims[:, RADIUS] = model.radius
        dims[:, HALF:HALF + 3] = model.half_extents
        dims[:, NORMAL:NORMAL + 3] = model.plane_normal
        dims[:, OFFSET] = model.plane_offset
        # fresh writable copies: the compiled code then sees one array type
        # (a model's frozen arrays are read-only, another type to numba)
        return cls(kind=np.array(model.shape_type, dtype=np.int64),
                   dims=dims, is_static=np.array(model.is_static, dtype=np.bool_),
                   reach=bounding_radius(model.shape_type, model.radius, model.half_extents))


def bounding_radius(shape_type, radius, half_extents) -> np.ndarray:
    """(n,) radius of the sphere about the centre that holds each body: r, |h|,
    0 for planes (broadphase.bounding_radius's numpy calls, so its bits)."""
    r = np.where(shape_type == SPHERE, radius, np.linalg.norm(half_extents, axis=1))
    return np.array(np.where(shape_type == PLANE, 0.0, r), dtype=np.float64)


@intrinsic
def fma(typingctx, a, b, c):
    """a * b + c with one rounding (llvm.fma: the hardware instruction on x86-64 with FMA3)."""
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, signature, args):
        d = ir.DoubleType()
        fn = cgutils.get_or_insert_function(builder.module, ir.FunctionType(d, [d, d, d]), "llvm.fma.f64")
        return builder.call(fn, args)
    return sig, codegen


@njit(cache=True)
def dot_lanes(a0, a1, a2, b0, b1, b2):
    """a · b summed as numpy's einsum sums a contiguous axis of length 3."""
    return (a0 * b0 + a2 * b2) + a1 * b1


@njit(cache=True)
def dot_seq(a0, a1, a2, b0, b1, b2):
    """a · b summed in order, as numpy's einsum sums a strided axis."""
    return (a0 * b0 + a1 * b1) + a2 * b2


@njit(cache=True)
def quat_matrix(w, x, y, z):
    """R(q) (quaternion.to_matrix) as a 9-tuple, row-major: R[i][j] at 3 i + j."""
    xx, yy, zz = x * x, y * y, z * z
    xy, xz, yz = x * y, x * z, y * z
    wx, wy, wz = w * x, w * y, w * z
    return (1 - 2 * (yy + zz), 2 * (xy - wz), 2 * (xz + wy),
            2 * (xy + wz), 1 - 2 * (xx + zz), 2 * (yz - wx),
            2 * (xz - wy), 2 * (yz + wx), 1 - 2 * (xx + yy))


@njit(cache=True, inline="always")
def body_axes(w, x, y, z, out, row):
    """out[row + i] = body axis i in the world frame (column i of R(q))."""
    r = quat_matrix(w, x, y, z)
    for i in range(3):
        for m in range(3):
            out[row + i, m] = r[3 * m + i]


@njit(cache=True)
def _turn(w, x, y, z, vx, vy, vz):
    # v + w t + u × t with t = 2 (u × v) (quaternion.rotate, u = (x, y, z))
    tx = 2.0 * (y * vz - z * vy)
    ty = 2.0 * (z * vx - x * vz)
    tz = 2.0 * (x * vy - y * vx)
    return (vx + w * tx + (y * tz - z * ty), vy + w * ty + (z * tx - x * tz),
            vz + w * tz + (x * ty - y * tx))


@njit(cache=True)
def rotate(w, x, y, z, vx, vy, vz):
    """q v q*: body → world (quaternion.rotate), q = (w, x, y, z)."""
    return _turn(w, x, y, z, vx, vy, vz)


@njit(cache=True)
def rotate_inverse(w, x, y, z, vx, vy, vz):
    """q* v q: world → body (quaternion.rotate_inverse negates the vector part)."""
    return _turn(w, -x, -y, -z, vx, vy, vz)


@njit(cache=True)
def sign(x):
    """+1 or -1, +1 at zero (narrow_box._sign: a fixed choice, never 0)."""
    return -1.0 if x < 0.0 else 1.0


@njit(cache=True)
def clip(x, lo, hi):
    """np.clip for lo < hi with lo, hi != 0 (its max-then-min; NaN passes
    through), written as two selects so it compiles without branches."""
    y = lo if x < lo else x
    return hi if y > hi else y
