"""A frozen copy of the numpy integrate stage, as it was before the Numba kernels.

Test-only reference for tests/test_integration_kernels.py: physics_core's
quaternion.py, vec3.py, free_rotation.py, integrators.py and effects/*.py
(commit b6010ed), concatenated into one module with their own names kept
apart (`gravity_make`, `drag_make`, ...). The formulas are the originals'
(COURSE.md 2, 3, 4), unchanged but for one adaptation marked in `_rows` (it
accepts the World's RowSplit); nothing here is used by the engine.
"""
import math
import warnings

import numpy as np

from physics_core.shapes import BOX, SPHERE


# ==== vec3.py ===============================================================

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


# ==== quaternion.py (qt_*) ==================================================

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


# ==== free_rotation.py ======================================================

_SEQUENCE = ((0, 0.5), (1, 0.5), (2, 1.0), (1, 0.5), (0, 0.5))

# q ⊗ e_i for the unit pure quaternion along body axis i is a signed permutation of q:
# q ⊗ (c, s e_i) = c q + s (q ⊗ e_i).
_Q_PERM = tuple(np.array(p) for p in ((1, 0, 3, 2), (2, 3, 0, 1), (3, 2, 1, 0)))
_Q_SIGN = (np.array([-1.0, 1.0, 1.0, -1.0]), np.array([-1.0, -1.0, 1.0, 1.0]),
           np.array([-1.0, 1.0, -1.0, 1.0]))
# L × e_i, also a signed permutation: (L × e_i)_j = L_k, (L × e_i)_k = −L_j, with (i, j, k) cyclic.
_L_PERM = tuple(np.array(p) for p in ((0, 2, 1), (2, 1, 0), (1, 0, 2)))
_L_SIGN = (np.array([0.0, 1.0, -1.0]), np.array([-1.0, 0.0, 1.0]), np.array([1.0, -1.0, 0.0]))
_L_OFF_AXIS = (np.array([0.0, 1.0, 1.0]), np.array([1.0, 0.0, 1.0]), np.array([1.0, 1.0, 0.0]))


def isotropic_rows(inertia: np.ndarray) -> np.ndarray:
    """Bodies whose three principal moments are equal (to 1e-12 relative)."""
    return np.ptp(inertia, axis=1) <= 1e-12 * np.max(np.abs(inertia), axis=1)


class RowSplit:
    """The bodies of a scene split once into isotropic and other rows, so a
    step does no per-row test: with every body isotropic (a scene of spheres
    and cubes) the splitting below never runs."""

    def __init__(self, isotropic):
        isotropic = np.asarray(isotropic, dtype=bool)
        self.n = len(isotropic)
        self.iso = np.flatnonzero(isotropic)
        self.aniso = np.flatnonzero(~isotropic)
        self.all_iso = len(self.aniso) == 0
        self.no_iso = len(self.iso) == 0


def _rows(isotropic) -> RowSplit:
    # (adapted: any RowSplit-like object, so the World's own RowSplit is accepted)
    return isotropic if hasattr(isotropic, "aniso") else RowSplit(isotropic)


def world_momentum(q, inertia, omega, isotropic):
    """L = I_w ω. For an isotropic body I_w = I 1 in any pose (COURSE.md 3),
    so L = I ω without turning ω into the body frame and back."""
    return _world_diagonal(q, inertia, omega, _rows(isotropic))


def world_velocity(q, inv_inertia, L, isotropic):
    """ω = I_w⁻¹ L (the inverse of world_momentum)."""
    return _world_diagonal(q, inv_inertia, L, _rows(isotropic))


def _world_diagonal(q, diagonal, v, rows):
    """R diag(d) Rᵀ v per body: the principal-axis diagonal `d` applied in
    world axes; isotropic rows need only d v."""
    out = diagonal[:, :1] * v
    if not rows.all_iso:
        a = rows.aniso
        qa = q[a]
        out[a] = rotate(qa, diagonal[a] * rotate_inverse(qa, v[a]))
    return out


def turn(q, omega, h):
    """q advanced by the exact exponential map of ω h; rows with ω = 0 are
    left as they are (a body at rest, or asleep, costs nothing)."""
    spin = np.flatnonzero(omega.any(axis=1))
    if len(spin) == len(q):
        return integrate(q, omega, h)
    out = q.copy()
    if len(spin):
        out[spin] = integrate(q[spin], omega[spin], h)
    return out


def advance(q, L, inv_inertia, h, isotropic):
    """(new orientation, new world ω) after a torque-free rotation of length h.

    q: (n, 4) orientations; L: (n, 3) world angular momentum, kept constant;
    inv_inertia: (n, 3) principal inverse moments (0 for frozen bodies);
    isotropic: (n,) bool or a RowSplit; those rows rotate about the fixed L at
    ω = L / I, advanced by the exact map, and only the others are split."""
    rows = _rows(isotropic)
    if rows.all_iso:
        omega = L * inv_inertia[:, :1]
        return turn(q, omega, h), omega
    if rows.no_iso:
        return _split(q, L, inv_inertia, h)
    a, i = rows.aniso, rows.iso
    out = np.empty_like(q)
    omega = np.empty_like(L)
    out[a], omega[a] = _split(q[a], L[a], inv_inertia[a], h)
    omega[i] = L[i] * inv_inertia[i, :1]
    out[i] = turn(q[i], omega[i], h)
    return out, omega


def _split(q, L, inv_inertia, h):
    """The symmetric splitting over principal axes, for every row given."""
    Lb = rotate_inverse(q, L)                          # body-frame L
    out = q
    for axis, frac in _SEQUENCE:
        half = (0.5 * frac * h) * Lb[:, axis] * inv_inertia[:, axis]
        c, s = np.cos(half)[:, None], np.sin(half)[:, None]
        # turn the body about its own axis by θ = 2·half ...
        out = c * out + s * (out.take(_Q_PERM[axis], axis=1) * _Q_SIGN[axis])
        # ... so L seen from the body turns by −θ about that axis
        c2, s2 = 1.0 - 2.0 * s * s, 2.0 * s * c
        L_cross_e = Lb.take(_L_PERM[axis], axis=1) * _L_SIGN[axis]
        Lb = Lb + (c2 - 1.0) * (Lb * _L_OFF_AXIS[axis]) + s2 * L_cross_e
    out = normalize(out)
    return out, rotate(out, inv_inertia * Lb)


# ==== effects/gravity.py ====================================================

def gravity_make(model):
    weight = np.where(model.is_static[:, None], 0.0, model.mass[:, None] * model.gravity)

    def apply(kin, force, torque):
        force += weight
    return apply


def gravity_potential(model, state) -> float:
    """U = -Σ m g·x over dynamic bodies."""
    m = np.where(model.is_static, 0.0, model.mass)
    return float(-np.sum(m * (state.pos @ model.gravity)))


# ==== effects/drag.py =======================================================

def drag_make(model):
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
            vb = rotate_inverse(kin.quat[sel][box_rows], v[box_rows])
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


# ==== effects/gravitation.py ================================================

BLOCK = 512


def gravitation_make(model):
    p = model.effects["gravitation"]
    idx = np.flatnonzero(model.mass > 0)
    m = model.mass[idx]
    eps2 = p.softening ** 2
    G = p.G

    def apply(kin, force, torque):
        x = kin.pos[idx]
        acc = np.empty_like(x)
        for s in range(0, len(idx), BLOCK):
            d = x[None, :, :] - x[s:s + BLOCK, None, :]
            r2 = np.einsum("ijk,ijk->ij", d, d) + eps2
            w = (G * (m[s:s + BLOCK, None] * m[None, :])) / (r2 * np.sqrt(r2))
            acc[s:s + BLOCK] = np.einsum("ij,ijk->ik", w, d)
        force[idx] += acc
    return apply


def gravitation_potential(model, state) -> float:
    """U = -Σ_{i<j} G m_i m_j / sqrt(r² + ε²), the potential of the softened force."""
    p = model.effects["gravitation"]
    idx = np.flatnonzero(model.mass > 0)
    x, m = state.pos[idx], model.mass[idx]
    cols = np.arange(len(idx))[None, :]
    total = 0.0
    for s in range(0, len(idx), BLOCK):
        d = x[None, :, :] - x[s:s + BLOCK, None, :]
        r = np.sqrt(np.einsum("ijk,ijk->ij", d, d) + p.softening ** 2)
        rows = np.arange(s, s + len(r))[:, None]
        u = p.G * m[s:s + BLOCK, None] * m[None, :] / r
        total -= float(np.sum(np.where(cols > rows, u, 0.0)))   # each pair once
    return total


# ==== effects/buoyancy.py ===================================================

def buoyancy_make(model):
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
            R = to_matrix(kin.quat[boxes])                      # (B, 3, 3)
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


# ==== effects/springs.py ====================================================

MAX_OMEGA_H = 0.5       # rad per sub-step: stable with margin; period error ≈ (ω h)²/24 ≤ 1 %
MAX_DAMPING_H = 0.5     # (C/m_eff) h: the damper removes at most about half the relative speed per sub-step
MAX_SPRING_SUBSTEPS = 1000


def effective_inverse_mass(model):
    """Upper bound of 1/m_eff each spring sees along its line, per spring (1/kg).

    At an attachment offset r the inverse mass along a unit direction u is
    1/m + (r × u)·I_w⁻¹ (r × u) ≤ 1/m + |r|² max(I⁻¹) (COURSE.md 5's impulse
    denominator); the two ends add. World and static ends count as infinite mass."""
    s = model.springs
    total = np.zeros(len(s))
    for body, local in ((s.a, s.point_a), (s.b, s.point_b)):
        on_body = body >= 0
        i = np.where(on_body, body, 0)
        inv_m = np.where(on_body, model.inv_mass[i], 0.0)
        inv_i = np.where(on_body, model.inv_inertia[i].max(axis=1), 0.0)
        total += inv_m + np.einsum("ij,ij->i", local, local) * inv_i
    return total


def stable_substeps(model, dt) -> int:
    """Sub-steps per step of length dt keeping ω h ≤ MAX_OMEGA_H and (C/m_eff) h ≤ MAX_DAMPING_H
    for every spring (1 without springs); capped at MAX_SPRING_SUBSTEPS with a warning."""
    if not len(model.springs):
        return 1
    inv_m = effective_inverse_mass(model)
    s = model.springs
    omega = np.sqrt(s.stiffness * inv_m)                 # rad/s
    rate = s.damping * inv_m                             # 1/s
    need = max(float(omega.max()) * dt / MAX_OMEGA_H, float(rate.max()) * dt / MAX_DAMPING_H, 1.0)
    n = math.ceil(need - 1e-9)
    if n > MAX_SPRING_SUBSTEPS:
        warnings.warn(f"the stiffest spring needs {n} sub-steps per step of {dt} s "
                      f"(ω = {float(omega.max()):.4g} rad/s); using {MAX_SPRING_SUBSTEPS}: "
                      "lower dt or the stiffness", RuntimeWarning, stacklevel=3)
        n = MAX_SPRING_SUBSTEPS
    return n


class _End:
    """One end (a or b) of every spring: which body, and where on it.

    A world end (index -1) holds its world point in `fixed`; a body end its
    body-frame offset in `local`. `turns` is false when every body end is at
    a centre of mass, so the rotations and r × F are skipped."""

    def __init__(self, model, body, local):
        self.on_body = body >= 0
        self.all_bodies = bool(self.on_body.all())      # common cases skip the masking
        self.no_body = not self.on_body.any()
        self.row = np.where(self.on_body, body, 0)
        self.mask = self.on_body[:, None].astype(float)
        self.local = np.where(self.on_body[:, None], local, 0.0)
        self.fixed = np.where(self.on_body[:, None], 0.0, local)
        self.still = np.zeros_like(self.fixed)
        self.turns = bool(np.any(self.local))
        self.bodies = self.row[self.on_body]

    def points(self, kin):
        """World attachment points, offsets from the centres (m) and point velocities (m/s)."""
        if self.no_body:
            return self.fixed, None, self.still
        i = self.row
        point = kin.pos[i]
        vel = kin.vel[i]
        arm = None
        if self.turns:
            arm = rotate(kin.quat[i], self.local)
            vel = vel + cross(kin.omega[i], arm)
        if not self.all_bodies:
            point = point * self.mask + self.fixed
            vel = vel * self.mask
            if arm is not None:
                arm = arm * self.mask
        return (point + arm if arm is not None else point), arm, vel

    def accumulate(self, out, value):
        """out[body] += value for the ends on bodies (several springs may share a body)."""
        if self.no_body:
            return
        np.add.at(out, self.bodies, value if self.all_bodies else value[self.on_body])


def _ends(model):
    s = model.springs
    return _End(model, s.a, s.point_a), _End(model, s.b, s.point_b)


def makes_torque(model) -> bool:
    """Whether some spring is attached away from a body's centre of mass (τ = r × F)."""
    return any(end.turns for end in _ends(model)) if len(model.springs) else False


def springs_make(model):
    s = model.springs
    k, l0, c = s.stiffness, s.rest_length, s.damping
    end_a, end_b = _ends(model)
    damped = bool(np.any(c))

    def apply(kin, force, torque):
        pa, ra, va = end_a.points(kin)
        pb, rb, vb = end_b.points(kin)
        d = pb - pa
        length = np.sqrt(dot(d, d))
        u = d / np.where(length > 0, length, 1.0)[:, None]
        tension = k * (length - l0)
        if damped:
            tension = tension + c * dot(vb - va, u)
        f = tension[:, None] * u
        end_a.accumulate(force, f)
        end_b.accumulate(force, -f)
        if ra is not None:
            end_a.accumulate(torque, cross(ra, f))
        if rb is not None:
            end_b.accumulate(torque, cross(rb, -f))
    return apply


def springs_potential(model, state) -> float:
    """U = Σ ½ K (l − l₀)²."""
    kin = Kinematics(state.pos, state.quat, state.vel, state.omega)
    end_a, end_b = _ends(model)
    length = np.linalg.norm(end_b.points(kin)[0] - end_a.points(kin)[0], axis=1)
    s = model.springs
    return float(np.sum(0.5 * s.stiffness * (length - s.rest_length) ** 2))


# ==== effects/__init__.py ===================================================

class Kinematics:
    """The body state a force is evaluated at (an integrator stage's trial state)."""
    __slots__ = ("pos", "quat", "vel", "omega")

    def __init__(self, pos, quat, vel, omega):
        self.pos, self.quat, self.vel, self.omega = pos, quat, vel, omega


def build_force_effects(model):
    """[(name, apply)] in a fixed order, for the effects this scene declares."""
    out = []
    if model.gravity is not None and model.gravity.any():
        out.append(("gravity", gravity_make(model)))
    if "gravitation" in model.effects:
        out.append(("gravitation", gravitation_make(model)))
    if "drag" in model.effects:
        out.append(("drag", drag_make(model)))
    if "buoyancy" in model.effects:
        out.append(("buoyancy", buoyancy_make(model)))
    if len(model.springs):
        out.append(("springs", springs_make(model)))
    return out


def potential_energy(model, state) -> float:
    """Potential energy (J) of the conservative effects in play (COURSE.md 6)."""
    total = 0.0
    if model.gravity is not None and model.gravity.any():
        total += gravity_potential(model, state)
    if "gravitation" in model.effects:
        total += gravitation_potential(model, state)
    if len(model.springs):
        total += springs_potential(model, state)
    return total


# ==== integrators.py ========================================================

def angular_momentum(q, inertia, omega, rows=None):
    """L = I_w ω; `rows` (RowSplit) lets isotropic bodies skip
    the two frame changes (I_w = I 1 for them)."""
    if rows is None:
        return rotate(q, inertia * rotate_inverse(q, omega))
    return world_momentum(q, inertia, omega, rows)


def angular_velocity(q, inv_inertia, L, rows=None):
    """ω = I_w⁻¹ L, with the same isotropic shortcut as angular_momentum."""
    if rows is None:
        return rotate(q, inv_inertia * rotate_inverse(q, L))
    return world_velocity(q, inv_inertia, L, rows)


def explicit_euler(sys, h):
    s = sys.state
    F, T = sys.forces(s.pos, s.quat, s.vel, s.omega)
    s.pos += s.vel * h
    s.vel += F * sys.inv_mass * h
    if sys.rotating:
        L = angular_momentum(s.quat, sys.inertia, s.omega, sys.rotation_rows) + T * h
        s.quat = turn(s.quat, s.omega, h)
        s.omega = angular_velocity(s.quat, sys.inv_inertia, L, sys.rotation_rows)


def semi_implicit_euler(sys, h):
    """v ← v + a h, then x ← x + v h with the new v (symplectic Euler)."""
    s = sys.state
    F, T = sys.forces(s.pos, s.quat, s.vel, s.omega)
    s.vel += F * sys.inv_mass * h
    s.pos += s.vel * h
    if sys.rotating:
        L = angular_momentum(s.quat, sys.inertia, s.omega, sys.rotation_rows) + T * h
        s.quat, s.omega = advance(s.quat, L, sys.inv_inertia, h, sys.rotation_rows)


def velocity_verlet(sys, h):
    """Kick ½h, drift h, kick ½h with the forces at the new positions.

    Velocity-dependent forces (drag, dampers) at the end point see the
    predicted velocity v + a h."""
    s = sys.state
    F0, T0 = sys.forces(s.pos, s.quat, s.vel, s.omega)
    a0 = F0 * sys.inv_mass
    v_half = s.vel + 0.5 * h * a0
    s.pos += v_half * h
    if sys.rotating:
        L_half = angular_momentum(s.quat, sys.inertia, s.omega, sys.rotation_rows) + 0.5 * h * T0
        s.quat, _ = advance(s.quat, L_half, sys.inv_inertia, h, sys.rotation_rows)
        omega_pred = angular_velocity(s.quat, sys.inv_inertia, L_half + 0.5 * h * T0, sys.rotation_rows)
    else:
        omega_pred = s.omega
    F1, T1 = sys.forces(s.pos, s.quat, v_half + 0.5 * h * a0, omega_pred)
    s.vel = v_half + 0.5 * h * F1 * sys.inv_mass
    if sys.rotating:
        s.omega = angular_velocity(s.quat, sys.inv_inertia, L_half + 0.5 * h * T1, sys.rotation_rows)


def rk4(sys, h):
    """Classical fourth-order Runge–Kutta on (x, q, v, L); forces re-evaluated at each stage."""
    s = sys.state
    x0, q0, v0 = s.pos, s.quat, s.vel
    rot = sys.rotating
    L0 = angular_momentum(q0, sys.inertia, s.omega, sys.rotation_rows) if rot else None

    def deriv(x, q, v, L):
        if rot:
            q = normalize(q)
            w = angular_velocity(q, sys.inv_inertia, L, sys.rotation_rows)
        else:
            w = s.omega
        F, T = sys.forces(x, q, v, w)
        dq = derivative(q, w) if rot else None
        return v, dq, F * sys.inv_mass, T

    k1 = deriv(x0, q0, v0, L0)
    k2 = deriv(*_trial(x0, q0, v0, L0, k1, 0.5 * h, rot))
    k3 = deriv(*_trial(x0, q0, v0, L0, k2, 0.5 * h, rot))
    k4 = deriv(*_trial(x0, q0, v0, L0, k3, h, rot))
    w = h / 6.0
    s.pos = x0 + w * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0])
    s.vel = v0 + w * (k1[2] + 2.0 * k2[2] + 2.0 * k3[2] + k4[2])
    if rot:
        s.quat = normalize(q0 + w * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]))
        L = L0 + w * (k1[3] + 2.0 * k2[3] + 2.0 * k3[3] + k4[3])
        s.omega = angular_velocity(s.quat, sys.inv_inertia, L, sys.rotation_rows)


def _trial(x0, q0, v0, L0, k, c, rot):
    return (x0 + c * k[0], q0 + c * k[1] if rot else q0, v0 + c * k[2],
            L0 + c * k[3] if rot else None)


INTEGRATORS = {
    "explicit_euler": explicit_euler,
    "semi_implicit_euler": semi_implicit_euler,
    "velocity_verlet": velocity_verlet,
    "rk4": rk4,
}
