# Frozen copy of physics_core/effects/drag.py at commit 76bcc0d (see __init__.py); imports made absolute.
"""Fluid drag (COURSE.md 2): linear F = -b v, quadratic F = -½ ρ |v|² C_d A v̂,
and `reynolds`, which picks one per body from its Reynolds number.

Reynolds mode: Re = ρ |v| L / μ with L the shape's characteristic length
(shapes.characteristic_length). Below `reynolds_threshold` (default 1, the
limit of Stokes flow) the drag is linear with b = 3π μ L (Stokes' law) unless
the body gives its own b; above, quadratic.

A box without a given area uses its exact projected area along v̂:
A = 4 (|v̂_x| h_y h_z + |v̂_y| h_x h_z + |v̂_z| h_x h_y) in body axes.

Per-body coefficients are computed once from the model (`make`); a call is
one compiled loop over the bodies that feel drag (`drag_forces`).
"""
import math

import numpy as np
from numba import njit

from physics_core.quaternion import rotate_inverse_one, row3, row4
from physics_core.shapes import BOX

LINEAR, QUADRATIC, REYNOLDS = 0, 1, 2
MODELS = {"linear": LINEAR, "quadratic": QUADRATIC, "reynolds": REYNOLDS}


@njit(cache=True)
def _quadratic_coeff(q, v, speed, half_rho_cd, area, box, face):
    """½ ρ C_d A |v|, so that F = -coeff · v; a box without a given area takes
    its projected area along v̂ (in body axes) instead of `area`. Scalars and
    tuples only: no array passes through the per-body call."""
    if box:
        vb = rotate_inverse_one(q, v)
        sp = max(speed, 1e-300)
        area = (abs(vb[0]) * face[0] + abs(vb[1]) * face[1] + abs(vb[2]) * face[2]) / sp
    return half_rho_cd * area * speed


@njit(cache=True)
def drag_forces(kind, idx, quat, vel, force, b, area, half_rho_cd, box, face, re_factor, threshold):
    """force[i] -= coeff_i v_i for every body i in idx: coeff = b (linear, or
    laminar in reynolds mode) or ½ ρ C_d A |v| (quadratic)."""
    for r in range(len(idx)):
        i = idx[r]
        v = row3(vel, i)
        if kind == LINEAR:
            coeff = b[r]
        else:
            speed = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
            if kind == REYNOLDS and (re_factor[r] * speed) < threshold:
                coeff = b[r]
            else:
                coeff = _quadratic_coeff(row4(quat, i), v, speed, half_rho_cd[r], area[r], box[r],
                                         row3(face, r))
        for k in range(3):
            force[i, k] -= coeff * v[k]


def _coefficients(model, p, idx):
    """(b, fixed area, box rows, face areas 4 (h_y h_z, h_x h_z, h_x h_y)) per drag row."""
    L = model.char_length[idx]
    b_default = 3.0 * np.pi * p.viscosity * L if p.model == "reynolds" else np.full(len(idx), p.b)
    b = np.where(np.isnan(model.drag_b[idx]), b_default, model.drag_b[idx])
    area_given = ~np.isnan(model.drag_area[idx])
    sphere_area = np.pi * model.radius[idx] ** 2
    fixed_area = np.where(area_given, model.drag_area[idx], sphere_area)
    box = (model.shape_type[idx] == BOX) & ~area_given
    h = model.half_extents[idx]
    face = np.where(box[:, None], 4.0 * np.stack([h[:, 1] * h[:, 2], h[:, 0] * h[:, 2], h[:, 0] * h[:, 1]],
                                                  axis=1), 0.0)
    return b, fixed_area, box, face


def make(model):
    p = model.effects["drag"]
    idx = np.flatnonzero(~model.is_static & (model.shape_type != 2))
    b, fixed_area, box, face = (np.ascontiguousarray(a) for a in _coefficients(model, p, idx))
    half_rho_cd = np.ascontiguousarray(0.5 * p.fluid_density * model.drag_cd[idx])
    re_factor = np.ascontiguousarray(p.fluid_density * model.char_length[idx] / p.viscosity)
    kind, threshold = MODELS[p.model], float(p.reynolds_threshold)

    def apply(kin, force, torque):
        drag_forces(kind, idx, kin.quat, kin.vel, force, b, fixed_area, half_rho_cd, box, face,
                    re_factor, threshold)
    return apply
