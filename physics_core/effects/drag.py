"""Fluid drag (COURSE.md 2): linear F = -b v, quadratic F = -½ ρ |v|² C_d A v̂,
and `reynolds`, which picks one per body from its Reynolds number.

Reynolds mode: Re = ρ |v| L / μ with L the shape's characteristic length
(shapes.characteristic_length). Below `reynolds_threshold` (default 1, the
limit of Stokes flow) the drag is linear with b = 3π μ L (Stokes' law) unless
the body gives its own b; above, quadratic.

A box without a given area uses its exact projected area along v̂:
A = 4 (|v̂_x| h_y h_z + |v̂_y| h_x h_z + |v̂_z| h_x h_y) in body axes.
"""
import numpy as np

from .. import quaternion as qt
from ..shapes import BOX, SPHERE


def make(model):
    p = model.effects["drag"]
    idx = np.flatnonzero(~model.is_static & (model.shape_type != 2))
    all_bodies = len(idx) == model.n
    sel = slice(None) if all_bodies else idx
    L = model.char_length[idx]
    b_default = 3.0 * np.pi * p.viscosity * L if p.model == "reynolds" else np.full(len(idx), p.b)
    b = np.where(np.isnan(model.drag_b[idx]), b_default, model.drag_b[idx])[:, None]
    area_given = ~np.isnan(model.drag_area[idx])
    sphere_area = np.pi * model.radius[idx] ** 2
    fixed_area = np.where(area_given, model.drag_area[idx], sphere_area)
    box_rows = np.flatnonzero((model.shape_type[idx] == BOX) & ~area_given)
    h = model.half_extents[idx][box_rows]
    face = 4.0 * np.stack([h[:, 1] * h[:, 2], h[:, 0] * h[:, 2], h[:, 0] * h[:, 1]], axis=1)
    half_rho_cd = 0.5 * p.fluid_density * model.drag_cd[idx]

    def quadratic_coeff(kin, v, speed):
        """½ ρ C_d A |v| per body, so that F = -coeff · v."""
        if len(box_rows):
            area = fixed_area.copy()
            vb = qt.rotate_inverse(kin.quat[sel][box_rows], v[box_rows])
            sp = np.maximum(speed[box_rows], 1e-300)
            area[box_rows] = np.einsum("ij,ij->i", np.abs(vb), face) / sp
        else:
            area = fixed_area
        return half_rho_cd * area * speed

    if p.model == "linear":
        def apply(kin, force, torque):
            force[sel] -= b * kin.vel[sel]
    elif p.model == "quadratic":
        def apply(kin, force, torque):
            v = kin.vel[sel]
            speed = np.sqrt(np.einsum("ij,ij->i", v, v))
            force[sel] -= quadratic_coeff(kin, v, speed)[:, None] * v
    else:
        re_factor = p.fluid_density * L / p.viscosity

        def apply(kin, force, torque):
            v = kin.vel[sel]
            speed = np.sqrt(np.einsum("ij,ij->i", v, v))
            laminar = (re_factor * speed) < p.reynolds_threshold
            coeff = np.where(laminar, b[:, 0], quadratic_coeff(kin, v, speed))
            force[sel] -= coeff[:, None] * v
    return apply
