"""Compiled narrow-phase kernels for the pairs with a sphere or a plane
(COURSE.md 5: contact point, a normal that separates, depth): sphere–sphere,
plane–sphere, box–sphere and plane–box. Box–box is in box_pair.py.

Each kernel `kind(f, s, dims, pos, quat, margin, ws, rows, k)` takes the
two bodies in its own shape order (`f` first, `s` second, as
narrowphase.KERNELS names them), reads their rows of `dims`, `pos` and
`quat` (geometry.py), and writes contact rows into the preallocated
(cap, ROW) array `rows` from row k on: point (POINT..+2), unit normal from
`f` to `s` (NORMAL..+2), depth (DEPTH, > 0 overlapping) and the slot
(SLOT); it returns how many rows it wrote. `ws` is scratch
(box_pair.workspace). The single-row kernels are thin wrappers round a
scalar function (`*_row`) that other compiled code can call directly.

The formulas and the order of every floating-point operation are those of
narrowphase.py (geometry.py says how its einsum sums are ordered), so the
rows agree with it to the bit; slots are the same: 0 for one-row kinds, the
box vertex number (bit k set: + side along axis k) against a plane.
"""
import math

import numpy as np
from numba import njit

from .geometry import HALF, NORMAL, OFFSET, RADIUS, clip, dot_lanes, quat_matrix, rotate, rotate_inverse

TINY = 1e-12              # narrowphase._TINY: below it a distance is treated as zero
BOX_PLANE_POINTS = 4      # deepest box vertices kept against a plane (narrowphase.py)
# columns of a contact row
POINT, NORMAL_COL, DEPTH, SLOT = 0, 3, 6, 7
ROW = 8


@njit(cache=True, inline="always")
def put_row(rows, k, slot, px, py, pz, nx, ny, nz, depth):
    """Row k: point, normal, depth, slot."""
    rows[k, POINT], rows[k, POINT + 1], rows[k, POINT + 2] = px, py, pz
    rows[k, NORMAL_COL], rows[k, NORMAL_COL + 1], rows[k, NORMAL_COL + 2] = nx, ny, nz
    rows[k, DEPTH] = depth
    rows[k, SLOT] = slot


@njit(cache=True)
def sphere_sphere_row(ra, rb, fx, fy, fz, sx, sy, sz):
    """(point, normal, depth) of spheres (r_a, c_f), (r_b, c_s): normal along
    the line of centres, depth r_a + r_b - |c_s - c_f|; coincident centres
    take +z (a fixed choice, never NaN)."""
    dx, dy, dz = sx - fx, sy - fy, sz - fz
    dist = math.sqrt(dot_lanes(dx, dy, dz, dx, dy, dz))
    nx, ny, nz = 0.0, 0.0, 1.0
    if dist > TINY:
        nx, ny, nz = dx / dist, dy / dist, dz / dist
    # midway between the surface points c_f + r_a n and c_s - r_b n
    return (0.5 * ((fx + nx * ra) + (sx - nx * rb)), 0.5 * ((fy + ny * ra) + (sy - ny * rb)),
            0.5 * ((fz + nz * ra) + (sz - nz * rb)), nx, ny, nz, ra + rb - dist)


@njit(cache=True, inline="always")
def sphere_sphere(f, s, dims, pos, quat, margin, ws, rows, k):
    px, py, pz, nx, ny, nz, d = sphere_sphere_row(dims[f, RADIUS], dims[s, RADIUS], pos[f, 0], pos[f, 1],
                                                  pos[f, 2], pos[s, 0], pos[s, 1], pos[s, 2])
    put_row(rows, k, 0, px, py, pz, nx, ny, nz, d)
    return 1


@njit(cache=True)
def plane_sphere_row(n0, n1, n2, offset, r, cx, cy, cz):
    """Sphere (r, c) above the plane n·x = offset: height h = n·c - offset,
    depth r - h, normal n, point midway between c - r n and c - h n."""
    h = dot_lanes(n0, n1, n2, cx, cy, cz) - offset
    back = 0.5 * (r + h)
    return cx - n0 * back, cy - n1 * back, cz - n2 * back, n0, n1, n2, r - h


@njit(cache=True, inline="always")
def plane_sphere(f, s, dims, pos, quat, margin, ws, rows, k):
    px, py, pz, nx, ny, nz, d = plane_sphere_row(dims[f, NORMAL], dims[f, NORMAL + 1], dims[f, NORMAL + 2],
                                                 dims[f, OFFSET], dims[s, RADIUS], pos[s, 0], pos[s, 1], pos[s, 2])
    put_row(rows, k, 0, px, py, pz, nx, ny, nz, d)
    return 1


@njit(cache=True)
def _nearest_face(c0, c1, c2, h0, h1, h2):
    """(axis, side, gap) of the box face nearest a centre inside it: the
    first axis of least h - |c| (np.argmin), side +1 when c >= 0."""
    g0, g1, g2 = h0 - abs(c0), h1 - abs(c1), h2 - abs(c2)
    axis, gap, c = 0, g0, c0
    if g1 < gap:
        axis, gap, c = 1, g1, c1
    if g2 < gap:
        axis, gap, c = 2, g2, c2
    return axis, (1.0 if c >= 0.0 else -1.0), gap


@njit(cache=True)
def _inside_push(c0, c1, c2, h0, h1, h2, r):
    """Centre within the box: out through the nearest face, depth r + gap.
    Returns (local normal, local surface point, depth)."""
    axis, side, gap = _nearest_face(c0, c1, c2, h0, h1, h2)
    if axis == 0:
        return side, 0.0, 0.0, side * h0, c1, c2, r + gap
    if axis == 1:
        return 0.0, side, 0.0, c0, side * h1, c2, r + gap
    return 0.0, 0.0, side, c0, c1, side * h2, r + gap


@njit(cache=True)
def _sphere_in_box_frame(c0, c1, c2, h0, h1, h2, r):
    """(local normal, local surface point, depth) of a sphere at c in the box frame.

    Outside: the closest box point is c clamped to [-h, h]; the normal runs
    from it to c, depth r - distance. Inside: _inside_push."""
    q0, q1, q2 = clip(c0, -h0, h0), clip(c1, -h1, h1), clip(c2, -h2, h2)
    d0, d1, d2 = c0 - q0, c1 - q1, c2 - q2
    dist = math.sqrt(dot_lanes(d0, d1, d2, d0, d1, d2))
    if dist > TINY:
        return d0 / dist, d1 / dist, d2 / dist, q0, q1, q2, r - dist
    return _inside_push(c0, c1, c2, h0, h1, h2, r)


@njit(cache=True)
def box_sphere_row(h0, h1, h2, fx, fy, fz, w, x, y, z, r, sx, sy, sz):
    """(point, normal box → sphere, depth) of the box (h, c_f, q) and the
    sphere (r, c_s), worked in the box frame."""
    c0, c1, c2 = rotate_inverse(w, x, y, z, sx - fx, sy - fy, sz - fz)
    n0, n1, n2, u0, u1, u2, depth = _sphere_in_box_frame(c0, c1, c2, h0, h1, h2, r)
    nx, ny, nz = rotate(w, x, y, z, n0, n1, n2)
    bx, by, bz = rotate(w, x, y, z, u0, u1, u2)
    # midway between the box surface point and the sphere's, c_s - r n
    return (0.5 * ((fx + bx + sx) - nx * r), 0.5 * ((fy + by + sy) - ny * r), 0.5 * ((fz + bz + sz) - nz * r),
            nx, ny, nz, depth)


@njit(cache=True, inline="always")
def box_sphere(f, s, dims, pos, quat, margin, ws, rows, k):
    px, py, pz, nx, ny, nz, d = box_sphere_row(
        dims[f, HALF], dims[f, HALF + 1], dims[f, HALF + 2], pos[f, 0], pos[f, 1], pos[f, 2],
        quat[f, 0], quat[f, 1], quat[f, 2], quat[f, 3], dims[s, RADIUS], pos[s, 0], pos[s, 1], pos[s, 2])
    put_row(rows, k, 0, px, py, pz, nx, ny, nz, d)
    return 1


@njit(cache=True, inline="always")
def box_vertex(R, px, py, pz, h0, h1, h2, v):
    """World vertex v of a box at p (bit k of v set: + side along body axis k),
    x_i = p_i + Σ_j R_ij s_j h_j (narrowphase.box_vertices' einsum order)."""
    l0 = h0 if v & 1 else -h0
    l1 = h1 if v & 2 else -h1
    l2 = h2 if v & 4 else -h2
    return (px + dot_lanes(R[0], R[1], R[2], l0, l1, l2), py + dot_lanes(R[3], R[4], R[5], l0, l1, l2),
            pz + dot_lanes(R[6], R[7], R[8], l0, l1, l2))


@njit(cache=True, inline="always")
def deepest_vertices(heights, row, margin):
    """The up to BOX_PLANE_POINTS vertices v of greatest depth -heights[row, v]
    with depth > -margin, ties to the lower vertex (narrowphase's stable
    argsort), as a bit set over the 8 vertices."""
    picked = 0
    for _ in range(BOX_PLANE_POINTS):
        best, best_depth = -1, -np.inf
        for v in range(8):
            d = -heights[row, v]
            if (d > -margin) & (d > best_depth) & (((picked >> v) & 1) == 0):
                best, best_depth = v, d
        picked |= (1 << best) if best >= 0 else 0
    return picked


@njit(cache=True, inline="always")
def plane_box(f, s, dims, pos, quat, margin, ws, rows, k):
    """Box vertices less than `margin` above the plane, the deepest
    BOX_PLANE_POINTS of them; slot = vertex number, rows in slot order.
    Point midway between the vertex and its projection on the plane."""
    R = quat_matrix(quat[s, 0], quat[s, 1], quat[s, 2], quat[s, 3])
    n0, n1, n2 = dims[f, NORMAL], dims[f, NORMAL + 1], dims[f, NORMAL + 2]
    px, py, pz, h0, h1, h2 = pos[s, 0], pos[s, 1], pos[s, 2], dims[s, HALF], dims[s, HALF + 1], dims[s, HALF + 2]
    for v in range(8):        # heights above the plane in ws row 0, one column per vertex
        x0, x1, x2 = box_vertex(R, px, py, pz, h0, h1, h2, v)
        ws[0, v] = dot_lanes(x0, x1, x2, n0, n1, n2) - dims[f, OFFSET]
    picked = deepest_vertices(ws, 0, margin)
    count = 0
    for v in range(8):
        if (picked >> v) & 1:
            x0, x1, x2 = box_vertex(R, px, py, pz, h0, h1, h2, v)
            back = 0.5 * ws[0, v]
            put_row(rows, k + count, v, x0 - n0 * back, x1 - n1 * back, x2 - n2 * back, n0, n1, n2, -ws[0, v])
            count += 1
    return count
