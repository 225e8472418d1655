"""The physics mutations `physics-bench mutations` plants, one at a time.

Each is one line of physics_core changed the way a plausible bug would
change it (a sign, a factor, a dropped term, a swapped operand), with the
fast test files that should catch it, most likely catcher first (pytest
stops at the first failure). `old` must occur in the file exactly once, or
`occurrence` says which one is meant; it may span lines to be unique, but
only one line differs in `new`.

Stages follow the step (COURSE.md): integrate (integrators, free rotation),
forces (effects/), detect (broad and narrow phase), rows (contact rows),
solve (sequential impulses, friction, warm start), restitution (the
collision pass), correct (position correction), ccd, sleep, events.
"""
from dataclasses import dataclass


@dataclass(frozen=True)
class Mutation:
    name: str
    stage: str
    path: str           # relative to the repository root
    old: str
    new: str
    tests: tuple        # test files (relative to the repository root), most likely catcher first
    occurrence: int = 0  # which occurrence of `old` (1-based); 0: it must be unique


K = "physics_core/"
C = "physics_core/collision/"
E = "physics_core/effects/"
T = "tests/"

MUTATIONS = (
    # ---- integrate -------------------------------------------------------------------
    Mutation("explicit Euler kicks with half the force", "integrate", K + "integrator_kernels.py",
             "vel[i, k] += F[i, k] * im * h", "vel[i, k] += 0.5 * F[i, k] * im * h",
             (T + "test_integrators.py",), occurrence=1),
    Mutation("semi-implicit Euler drifts with the old velocity", "integrate", K + "integrator_kernels.py",
             "pos[i, k] += vel[i, k] * h", "pos[i, k] += (vel[i, k] - F[i, k] * im * h) * h",
             (T + "test_integrators.py", T + "test_forces.py"), occurrence=2),
    Mutation("velocity Verlet closes with a whole-step kick", "integrate", K + "integrator_kernels.py",
             "vel[i, k] = v_half[i, k] + half * F[i, k] * im",
             "vel[i, k] = v_half[i, k] + h * F[i, k] * im",
             (T + "test_integrators.py", T + "test_forces.py")),
    Mutation("RK4 weights its middle slopes 1 instead of 2", "integrate", K + "integrator_kernels.py",
             "total[i, j] = k if first else total[i, j] + 2.0 * k",
             "total[i, j] = k if first else total[i, j] + 1.0 * k",
             (T + "test_integrators.py", T + "test_forces.py")),
    Mutation("gyroscopic term dropped: every body turned as if isotropic", "integrate",
             K + "free_rotation.py",
             "    if iso:\n        return (d[0] * v[0], d[0] * v[1], d[0] * v[2])",
             "    if True:\n        return (d[0] * v[0], d[0] * v[1], d[0] * v[2])",
             (T + "test_rotation.py", T + "test_integration_kernels.py")),
    Mutation("torque kick of L has the wrong sign about x", "integrate", K + "integrator_kernels.py",
             "return (L[0] + T[i, 0] * c, L[1] + T[i, 1] * c, L[2] + T[i, 2] * c)",
             "return (L[0] - T[i, 0] * c, L[1] + T[i, 1] * c, L[2] + T[i, 2] * c)",
             (T + "test_rotation.py",)),
    Mutation("orientation turned in the body frame instead of the world frame", "integrate",
             K + "quaternion.py",
             "    return normalize_one(multiply_one(r, q))",
             "    return normalize_one(multiply_one(q, r))",
             (T + "test_rotation.py", T + "test_integration_kernels.py")),
    # ---- forces ----------------------------------------------------------------------
    Mutation("gravity 0.1 % too strong", "forces", E + "gravity.py",
             "model.mass[:, None] * model.gravity", "model.mass[:, None] * model.gravity * 1.001",
             (T + "test_forces.py",)),
    Mutation("drag pushes along the velocity", "forces", E + "drag.py",
             "force[i, k] -= coeff * v[k]", "force[i, k] += coeff * v[k]",
             (T + "test_forces.py",)),
    Mutation("Reynolds drag switches laws the wrong way round", "forces", E + "drag.py",
             "(re_factor[r] * speed) < threshold", "(re_factor[r] * speed) > threshold",
             (T + "test_forces.py",)),
    Mutation("spring damper pushes with the relative speed", "forces", E + "springs.py",
             "tension = tension + c * (", "tension = tension - c * (",
             (T + "test_forces.py",)),
    Mutation("mutual gravitation: the second body is pulled the same way", "forces", E + "gravitation.py",
             "acc[b, 0] -= w * dx", "acc[b, 0] += w * dx",
             (T + "test_forces.py",)),
    Mutation("buoyancy 10 % short of ρ g V", "forces", E + "buoyancy.py",
             "force[i, k] += vol * up[k]", "force[i, k] += 0.9 * vol * up[k]",
             (T + "test_forces.py",)),
    # ---- detect ----------------------------------------------------------------------
    Mutation("broad-phase cell half the largest small body", "detect", C + "grid.py",
             "cell = max(cell, size[r])", "cell = max(cell, 0.5 * size[r])",
             (T + "test_broadphase.py",)),
    Mutation("sphere-sphere normal points from the second to the first", "detect", C + "shape_pairs.py",
             "nx, ny, nz = dx / dist, dy / dist, dz / dist", "nx, ny, nz = -dx / dist, -dy / dist, -dz / dist",
             (T + "test_narrowphase.py", T + "test_detection_kernels.py")),
    Mutation("plane-sphere depth 1 mm short", "detect", C + "shape_pairs.py",
             "return cx - n0 * back, cy - n1 * back, cz - n2 * back, n0, n1, n2, r - h",
             "return cx - n0 * back, cy - n1 * back, cz - n2 * back, n0, n1, n2, r - h - 1e-3",
             (T + "test_narrowphase.py", T + "test_detection_kernels.py")),
    # ---- rows ------------------------------------------------------------------------
    Mutation("second tangent not orthogonal to the normal", "rows", C + "contact_build.py",
             "R[c, t2], R[c, t2 + 1], R[c, t2 + 2] = b, sign + ny * ny * a, -ny",
             "R[c, t2], R[c, t2 + 1], R[c, t2 + 2] = b, sign + ny * ny * a, ny",
             (T + "test_contact_frame.py", T + "test_collisions_friction.py")),
    Mutation("lever arm r × d with the wrong sign in x", "rows", C + "contact_build.py",
             "cx, cy, cz = ry * dz - rz * dy, rz * dx - rx * dz, rx * dy - ry * dx",
             "cx, cy, cz = rz * dy - ry * dz, rz * dx - rx * dz, rx * dy - ry * dx",
             (T + "test_collisions_rotation.py", T + "test_collisions_friction.py")),
    Mutation("speculative contacts may not close their gap", "rows", C + "contact_build.py",
             "R[c, BIAS] = -max(s0, 0.0) / h", "R[c, BIAS] = -0.0 * max(s0, 0.0) / h",
             (T + "test_collisions_restitution.py", T + "test_ccd_regressions.py", T + "test_toi.py")),
    Mutation("effective-mass restitution rule weights the wrong body", "rows", C + "contact_build.py",
             "return (k_a * e_a + k_b * e_b) / (k_a + k_b)", "return (k_b * e_a + k_a * e_b) / (k_a + k_b)",
             (T + "test_collisions_restitution.py",)),
    # ---- solve -----------------------------------------------------------------------
    Mutation("warm start loads no normal impulse", "solve", C + "warm_cache.py",
             "R[c, LAM] = old[j, WARM_NORMAL] * fraction", "R[c, LAM] = old[j, WARM_NORMAL] * 0.0",
             (T + "test_collisions_friction.py", T + "test_static_friction_manifold.py",
              T + "test_contact_hard_cases.py")),
    Mutation("normal row pulls towards its bias instead of pushing", "solve", C + "sequential_impulses.py",
             "ln = max(old_n - R[c, MASS_N] * (un - R[c, BIAS]), 0.0)",
             "ln = max(old_n - R[c, MASS_N] * (un + R[c, BIAS]), 0.0)",
             (T + "test_collisions_restitution.py", T + "test_toi.py", T + "test_ccd_regressions.py")),
    Mutation("sliding friction pushes along the slip", "solve", C + "kinetic_bound.py",
             "return x1 * scale, x2 * scale", "return -x1 * scale, -x2 * scale",
             (T + "test_collisions_friction.py",)),
    Mutation("the shock sweep keeps a layer that gained energy", "solve", C + "shock_propagation.py",
             "GAIN = 1e-4", "GAIN = 1e9",
             (T + "test_shock_energy_guard.py", T + "test_stacks_and_mass_ratios.py")),
    Mutation("the resting solve lets a point pull", "solve", C + "resting_block.py",
             "if not lam >= 0.0:", "if not lam >= -1e9:",
             (T + "test_resting_block.py",)),
    Mutation("friction cap twice μ λ_n", "solve", C + "sequential_impulses.py",
             "lim = R[c, MU] * ln", "lim = 2.0 * R[c, MU] * ln",
             (T + "test_collisions_friction.py",)),
    Mutation("manifold friction swaps μ_s and μ_k", "solve", C + "manifold_friction.py",
             "mu = M[k, M_MU_K] if sliding else M[k, M_MU_S]", "mu = M[k, M_MU_S] if sliding else M[k, M_MU_K]",
             (T + "test_static_friction_manifold.py", T + "test_collisions_friction.py")),
    Mutation("manifold twist friction dropped", "solve", C + "manifold_friction.py",
             "twist = mu * ln * M[k, RADIUS]", "twist = 0.0 * mu * ln * M[k, RADIUS]",
             (T + "test_static_friction_manifold.py", T + "test_collisions_friction.py")),
    # ---- restitution -----------------------------------------------------------------
    Mutation("bounce impulse with 0.95 C_R", "restitution", C + "bounce.py",
             "return e * approach + after - shift, e * approach, when",
             "return 0.95 * e * approach + after - shift, e * approach, when",
             (T + "test_collisions_restitution.py", T + "test_elastic_impacts.py")),
    Mutation("a manifold's points bounced in one sweep", "restitution", C + "collision_pass.py",
             "for _ in range(BLOCK_SWEEPS if end - first > 1 else 1):", "for _ in range(1):",
             (T + "test_manifold_bounce.py",)),
    Mutation("restitution threshold doubled", "restitution", C + "bounce.py",
             "return e if approach > threshold else 0.0", "return e if approach > 2.0 * threshold else 0.0",
             (T + "test_collisions_restitution.py",)),
    Mutation("bounce friction pushes along the slip", "restitution", C + "bounce.py",
             "s1, s2 = -u1 * scale, -u2 * scale", "s1, s2 = u1 * scale, u2 * scale",
             (T + "test_contact_energy_audit.py", T + "test_collisions_friction.py")),
    Mutation("a manifold's bounce friction held below μ_s", "restitution", C + "bounce_friction.py",
             "grip = M[k, M_MU_S] * ln", "grip = 0.8 * M[k, M_MU_S] * ln",
             (T + "test_bounce_friction_anchor.py",)),
    Mutation("a manifold's bounce friction shared evenly by its points", "restitution",
             C + "bounce_friction.py", "w = lam[c] / ln", "w = 1.0 / (end - first)",
             (T + "test_bounce_friction_anchor.py",)),
    Mutation("a manifold's bounce friction without its twist", "restitution", C + "bounce_friction.py",
             "store_pair(vel, omega, a, b, pair_impulses(M, k, n0, n1, n2, p))",
             "store_pair(vel, omega, a, b, pair_impulses(M, k, n0, n1, 0.0 * n2, p))",
             (T + "test_bounce_friction_anchor.py",)),
    Mutation("impact speed without the integrator's velocity stagger", "restitution", C + "bounce.py",
             "shift = (w - 0.5) * (u0 - u_s)", "shift = 0.0 * (u0 - u_s)",
             (T + "test_elastic_impacts.py", T + "test_collisions_restitution.py")),
    # ---- correct ---------------------------------------------------------------------
    Mutation("position correction pushes out the slop too", "correct", C + "push_out.py",
             "target[c] = max(min(rate * (-sep[c] - slop) / h, max_speed), 0.0)",
             "target[c] = max(min(rate * (-sep[c]) / h, max_speed), 0.0)",
             (T + "test_position_correction.py", T + "test_collisions_sleep.py")),
    Mutation("pseudo-velocity applied twice", "correct", C + "push_out.py",
             "pos[i, j] += (dV[i, j] + X[i, j]) * h if X.shape[0] else dV[i, j] * h",
             "pos[i, j] += (dV[i, j] + 2.0 * X[i, j]) * h if X.shape[0] else dV[i, j] * h",
             (T + "test_position_correction.py", T + "test_contact_hard_cases.py")),
    # ---- ccd -------------------------------------------------------------------------
    Mutation("ccd threshold eight times too high", "ccd", C + "time_of_impact.py",
             "> threshold * smallest_half_size(kind, dims, i)", "> 8.0 * threshold * smallest_half_size(kind, dims, i)",
             (T + "test_toi.py", T + "test_ccd_regressions.py")),
    Mutation("ccd allows eight times the depth before a hit", "ccd", C + "time_of_impact.py",
             "return max(start, 0.0) + threshold * thin", "return max(start, 0.0) + 8.0 * threshold * thin",
             (T + "test_toi.py", T + "test_ccd_regressions.py")),
    # ---- sleep -----------------------------------------------------------------------
    Mutation("rest test compares |v|² with an unsquared speed", "sleep", C + "sleep_islands.py",
             "v_max = linear_speed * linear_speed", "v_max = linear_speed",
             (T + "test_event_sleep_kernels.py", T + "test_collisions_sleep.py")),
    Mutation("a body deeper than the slop may fall asleep", "sleep", C + "sleep_islands.py",
             "_square(omega, i) < w_max and not unsettled[i]:", "_square(omega, i) < w_max:",
             (T + "test_event_sleep_kernels.py", T + "test_collisions_sleep.py")),
    # ---- events ----------------------------------------------------------------------
    Mutation("a contact seen last step is reported as begin again", "events", C + "event_log.py",
             "_touch_event(cur_i, cur_f, i, out_i, out_f, PERSIST)",
             "_touch_event(cur_i, cur_f, i, out_i, out_f, BEGIN)",
             (T + "test_event_sleep_kernels.py", T + "test_collisions_events.py")),
    Mutation("an ended contact is reported as persisting", "events", C + "event_log.py",
             "_put_event(rows_i, rows_f, j, out_i, out_f, r, END)",
             "_put_event(rows_i, rows_f, j, out_i, out_f, r, PERSIST)",
             (T + "test_event_sleep_kernels.py", T + "test_collisions_events.py")),
)
