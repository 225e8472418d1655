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
"""
import numpy as np

from .. import quaternion as qt
from ..shapes import BOX, SPHERE
from ..vec3 import cross


def make(model):
    p = model.effects["buoyancy"]
    g = model.gravity
    dynamic = ~model.is_static
    spheres = np.flatnonzero(dynamic & (model.shape_type == SPHERE))
    boxes = np.flatnonzero(dynamic & (model.shape_type == BOX))
    r = model.radius[spheres]
    k = p.cells
    # Cell centres in units of the half extents: ((2i+1)/k − 1) on each axis.
    ticks = (2.0 * np.arange(k) + 1.0) / k - 1.0
    grid = np.stack(np.meshgrid(ticks, ticks, ticks, indexing="ij"), axis=-1).reshape(-1, 3)
    h = model.half_extents[boxes]
    cell_offsets = grid[None, :, :] * h[:, None, :]             # (B, k³, 3) body frame
    cell_volume = model.volume[boxes] / k ** 3
    box_volume = model.volume[boxes]
    up_force = -p.fluid_density * g                              # per unit submerged volume

    def apply(kin, force, torque):
        if len(spheres):
            depth = np.clip(p.surface_z - (kin.pos[spheres, 2] - r), 0.0, 2.0 * r)
            vol = np.pi * depth ** 2 * (3.0 * r - depth) / 3.0
            force[spheres] += vol[:, None] * up_force
            if p.linear_damping or p.angular_damping:
                frac = (vol / model.volume[spheres])[:, None]
                force[spheres] -= p.linear_damping * frac * kin.vel[spheres]
                torque[spheres] -= p.angular_damping * frac * kin.omega[spheres]
        if len(boxes):
            R = qt.to_matrix(kin.quat[boxes])                      # (B, 3, 3)
            reach = np.einsum("bj,bj->b", np.abs(R[:, 2, :]), h)   # half the box's vertical extent
            z = kin.pos[boxes, 2]
            # Only boxes cut by the surface need the cells: one fully under water
            # feels ρ g V at its centre (no torque), one fully out feels nothing.
            under = z + reach <= p.surface_z
            cut = np.flatnonzero(~under & (z - reach < p.surface_z))
            submerged = np.where(under, box_volume, 0.0)
            if under.any():
                force[boxes[under]] += box_volume[under, None] * up_force
            if len(cut):
                arm = np.einsum("bij,bcj->bci", R[cut], cell_offsets[cut])   # (C, k³, 3) world offsets
                e = (reach[cut] / k)[:, None]                  # half the vertical extent of a cell
                bottom = z[cut, None] + arm[:, :, 2] - e
                frac = np.clip((p.surface_z - bottom) / (2.0 * e), 0.0, 1.0)   # (C, k³)
                # centroid of the submerged slice sits f·e above the cell's bottom
                arm[:, :, 2] += (frac - 1.0) * e
                vol = frac * cell_volume[cut, None]
                cell_force = vol[:, :, None] * up_force            # (C, k³, 3)
                force[boxes[cut]] += cell_force.sum(axis=1)
                torque[boxes[cut]] += cross(arm, cell_force).sum(axis=1)
                submerged[cut] = vol.sum(axis=1)
            if p.linear_damping or p.angular_damping:
                f = (submerged / box_volume)[:, None]
                force[boxes] -= p.linear_damping * f * kin.vel[boxes]
                torque[boxes] -= p.angular_damping * f * kin.omega[boxes]
    return apply
