"""Buoyancy F_B = ρ g V_submerged, opposite to gravity (COURSE.md 2).

The fluid fills z < surface_z. A sphere's submerged cap has the exact
volume V = π h² (3r − h) / 3 (h = depth of its lowest point, clipped to
[0, 2r]) and, by symmetry, exerts no torque. A box is split into cells³
equal sub-boxes; each cell's submerged fraction is its depth across its
vertical extent e = Σ_k |R_zk| h_k / cells, clipped to [0, 1], and its force
acts at the centroid of that submerged slice. An upright box gets its exact
volume, and a tilted box feels the restoring torque of its moving centre of
buoyancy. Optional damping stands for the fluid's viscous resistance and is
scaled by the submerged fraction.

The cell offsets and volumes are computed once (`constants`); a call is two
compiled loops, over the spheres and over the boxes (and, for a box cut by
the surface, over its cells), from `make`'s apply or from the compiled
substep (integration.py).
"""
import math

import numpy as np
from numba import njit

from ..quaternion import cross_one, row3, row4, to_matrix_one
from ..shapes import BOX, SPHERE


@njit(cache=True)
def _damp(frac, v, w, linear, angular):
    """The fluid's resistance (force, torque) on a body moving at v, ω, scaled by its
    submerged fraction; what the kernels subtract."""
    return ((linear * frac * v[0], linear * frac * v[1], linear * frac * v[2]),
            (angular * frac * w[0], angular * frac * w[1], angular * frac * w[2]))


@njit(cache=True)
def _subtract(force, torque, i, f, t):
    for k in range(3):
        force[i, k] -= f[k]
        torque[i, k] -= t[k]


@njit(cache=True)
def sphere_forces(rows, r, volume, pos, vel, omega, force, torque, surface, up, linear, angular, damped):
    """Exact cap volume π h² (3r − h) / 3 of each sphere, pushed up at its centre."""
    for s in range(len(rows)):
        i = rows[s]
        depth = min(max(surface - (pos[i, 2] - r[s]), 0.0), 2.0 * r[s])
        vol = math.pi * (depth * depth) * (3.0 * r[s] - depth) / 3.0
        for k in range(3):
            force[i, k] += vol * up[k]
        if damped:
            f, t = _damp(vol / volume[s], row3(vel, i), row3(omega, i), linear, angular)
            _subtract(force, torque, i, f, t)


@njit(cache=True)
def _cut_box(R, z, reach, cells, offsets, cell_volume, surface, up):
    """(force, torque, submerged volume) of a box cut by the surface, cell by cell:
    each cell filled over its vertical extent 2e, pushed at its slice's centroid."""
    e = reach / cells
    f0 = f1 = f2 = t0 = t1 = t2 = 0.0
    submerged = 0.0
    for c in range(len(offsets)):
        o = (offsets[c, 0], offsets[c, 1], offsets[c, 2])
        arm_x = R[0][0] * o[0] + R[0][1] * o[1] + R[0][2] * o[2]
        arm_y = R[1][0] * o[0] + R[1][1] * o[1] + R[1][2] * o[2]
        arm_z = R[2][0] * o[0] + R[2][1] * o[1] + R[2][2] * o[2]
        bottom = z + arm_z - e
        frac = min(max((surface - bottom) / (2.0 * e), 0.0), 1.0)
        # centroid of the submerged slice sits f·e above the cell's bottom
        arm_z += (frac - 1.0) * e
        vol = frac * cell_volume
        cf = (vol * up[0], vol * up[1], vol * up[2])
        t = cross_one((arm_x, arm_y, arm_z), cf)
        f0, f1, f2 = f0 + cf[0], f1 + cf[1], f2 + cf[2]
        t0, t1, t2 = t0 + t[0], t1 + t[1], t2 + t[2]
        submerged += vol
    return (f0, f1, f2), (t0, t1, t2), submerged


@njit(cache=True)
def box_forces(rows, half, offsets, cells, cell_volume, box_volume, pos, quat, vel, omega, force, torque,
               surface, up, linear, angular, damped):
    """A box fully under water feels ρ g V at its centre (no torque), one fully
    out nothing; one cut by the surface is integrated over its cells."""
    for b in range(len(rows)):
        i = rows[b]
        R = to_matrix_one(row4(quat, i))
        reach = abs(R[2][0]) * half[b, 0] + abs(R[2][1]) * half[b, 1] + abs(R[2][2]) * half[b, 2]
        z = pos[i, 2]
        submerged = 0.0
        if z + reach <= surface:
            submerged = box_volume[b]
            for k in range(3):
                force[i, k] += box_volume[b] * up[k]
        elif z - reach < surface:
            f, t, submerged = _cut_box(R, z, reach, cells, offsets[b], cell_volume[b], surface, up)
            for k in range(3):
                force[i, k] += f[k]
                torque[i, k] += t[k]
        if damped:
            f, t = _damp(submerged / box_volume[b], row3(vel, i), row3(omega, i), linear, angular)
            _subtract(force, torque, i, f, t)


def _cell_offsets(half, k):
    """Cell centres of every box in its body frame, (B, k³, 3): ((2i+1)/k − 1) h on each axis."""
    ticks = (2.0 * np.arange(k) + 1.0) / k - 1.0
    grid = np.stack(np.meshgrid(ticks, ticks, ticks, indexing="ij"), axis=-1).reshape(-1, 3)
    return np.ascontiguousarray(grid[None, :, :] * half[:, None, :])


def constants(model):
    """(spheres, r, sphere volume, boxes, half extents, cell offsets, cells, cell
    volume, box volume, up, surface z, linear and angular damping, damped): the
    dynamic spheres and boxes with their sizes, each box's cell centres in body
    axes (B, cells³, 3), up = −ρ g (the push per unit submerged volume) and the
    fluid's parameters, computed once per model."""
    p = model.effects["buoyancy"]
    dynamic = ~model.is_static
    spheres = np.flatnonzero(dynamic & (model.shape_type == SPHERE)).astype(np.int64)
    boxes = np.flatnonzero(dynamic & (model.shape_type == BOX)).astype(np.int64)
    half = np.array(model.half_extents[boxes], dtype=float)
    box_volume = np.array(model.volume[boxes], dtype=float)
    return (spheres, np.array(model.radius[spheres], dtype=float), np.array(model.volume[spheres], dtype=float),
            boxes, half, _cell_offsets(half, p.cells), int(p.cells), box_volume / p.cells ** 3, box_volume,
            np.array(-p.fluid_density * model.gravity, dtype=float), float(p.surface_z),
            float(p.linear_damping), float(p.angular_damping), bool(p.linear_damping or p.angular_damping))


def unused():
    """The types of `constants` with no bodies, for a scene without buoyancy."""
    rows, none = np.zeros(0, dtype=np.int64), np.zeros(0)
    return (rows, none, none.copy(), rows.copy(), np.zeros((0, 3)), np.zeros((0, 1, 3)), 1, none.copy(),
            none.copy(), np.zeros(3), 0.0, 0.0, 0.0, False)


@njit(cache=True)
def add(c, pos, quat, vel, omega, force, torque):
    """The effect's kernel on the common signature of effects/: the spheres, then the boxes."""
    spheres, r, sphere_volume, boxes, half, offsets, cells, cell_volume, box_volume, up, surface, \
        linear, angular, damped = c
    if len(spheres):
        sphere_forces(spheres, r, sphere_volume, pos, vel, omega, force, torque, surface, up, linear, angular,
                      damped)
    if len(boxes):
        box_forces(boxes, half, offsets, cells, cell_volume, box_volume, pos, quat, vel, omega, force, torque,
                   surface, up, linear, angular, damped)


def make(model):
    """apply(kin, force, torque): `add` with this model's constants (World.forces' path)."""
    c = constants(model)

    def apply(kin, force, torque):
        add(c, kin.pos, kin.quat, kin.vel, kin.omega, force, torque)
    return apply
