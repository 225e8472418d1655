"""Restitution of one contact: the bounce rule, its timing and its friction
(COURSE.md 5, coefficient of restitution, friction); the collision pass
that sweeps them is collision_pass.py.

A contact whose normal velocity approaches faster than
`restitution_threshold`, and whose surfaces meet within the substep, is
to separate at C_R × its approach speed (`bounce_goal`): alone, by the
course's pairwise impulse

    j = (1 + C_R) (−u_n) / W_00      (W_00 = 1/m_a + 1/m_b + rotational terms);

the points of one manifold together (collision_pass.py). Friction acts on
that same impulse: kinetic μ_k j against the slip, or, when the impulse
that stops the slip lies within μ_s j, exactly that impulse (the contact
grips). What still approaches after the pass, and everything slower than
the threshold (resting contact, C_R = 0), and every impact with C_R = 0
(all of a manifold's points are stopped together there), is left to the
sequential-impulse solve. With `restitution_ramp` > 0, C_R rises
linearly from 0 over that band above the threshold.

The pass's impulses J (normal, two tangents) are kept apart from the
solve's accumulated λ, which they would otherwise cancel (the solve drives
a separating contact's λ back to 0), and added to λ after the solve for the
events and the sleep islands; the warm start uses the solve's λ only, and
is applied after the pass (contact_stages.restitution_stage): an approach
is the bodies' own, not last substep's impulses applied again.

Time of collision (COURSE.md 5): the surfaces met a fraction τ of the
substep in, where s0 = approach·h − depth had closed; the bodies move with
the old velocity until then and with the new one after (push_out.py).
"""
import math

from numba import njit

from .contact_build import row_velocity, tangent_world
from .contact_layout import BODY_A, BODY_B, DEPTH, E, LAM, MU_K, MU_S, U0, W_TT_INV
from .sequential_impulses import apply_impulse

WHEN, SHIFT, AFTER = range(3)      # columns of impact_terms' table


@njit(cache=True)
def effective_restitution(e, approach, threshold, ramp):
    """C_R after the resting-contact rule, for an approach speed (> 0 closing)."""
    if ramp > 0.0:
        return e * min(max((approach - threshold) / ramp, 0.0), 1.0)
    return e if approach > threshold else 0.0


@njit(cache=True)
def impact(u_start, u_end, depth, h):
    """(u_n at the impact, τ) for a contact whose normal velocity went from
    u_start to u_end over the substep under the forces (constant
    acceleration a = (u_end − u_start)/h) and whose surfaces overlap by
    `depth` at its end: the gap at the start s0 = −depth − h (u_start + u_end)/2
    closes at u_imp = −√(u_start² − 2 a s0) (COURSE.md 3, uniformly
    accelerated motion), τ the fraction of the substep by then. A pair
    already touching at the start (s0 ≤ 0) has τ = 0 and u_imp = u_start."""
    s0 = -depth - 0.5 * h * (u_start + u_end)
    if not s0 > 0.0:
        return u_start, 0.0
    a = (u_end - u_start) / h
    u_imp = -math.sqrt(max(u_start * u_start - 2.0 * a * s0, 0.0))
    if abs(a) * h > 1e-12 * (abs(u_start) + abs(u_end)):
        tau = (u_imp - u_start) / (a * h)
    else:
        tau = s0 / max(-u_start * h, 1e-300)
    tau = min(max(tau, 0.0), 1.0)
    return u_start + tau * (u_end - u_start), tau


@njit(cache=True, inline="always")
def bounce_friction(R, c, a, b, jn, vel, omega):
    """Friction on a bounce impulse jn (COURSE.md 5): the tangential impulse
    that stops the slip if it lies within μ_s jn, else μ_k jn against the
    slip. Returns the two tangential impulses applied."""
    u1 = row_velocity(R, c, 1, a, b, vel, omega)
    u2 = row_velocity(R, c, 2, a, b, vel, omega)
    s1 = -(R[c, W_TT_INV] * u1 + R[c, W_TT_INV + 1] * u2)
    s2 = -(R[c, W_TT_INV + 2] * u1 + R[c, W_TT_INV + 3] * u2)
    grip = R[c, MU_S] * jn
    if not s1 * s1 + s2 * s2 <= grip * grip:
        scale = R[c, MU_K] * jn / math.sqrt(u1 * u1 + u2 * u2 + 1e-300)
        s1, s2 = -u1 * scale, -u2 * scale
    apply_impulse(R, c, 1, s1, a, b, vel, omega)
    apply_impulse(R, c, 2, s2, a, b, vel, omega)
    return s1, s2


@njit(cache=True, inline="always")
def impact_terms(R, I, vel_start, omega_start, h, w, onset):
    """onset[c] = (τ, shift, after) of contact c's first bounce, the same
    for every sweep of the pass: its impact happens at τ (`impact`), and the
    forces' change of u_n after τ (`after`) is added to the separation
    speed C_R × approach (the body keeps falling for the rest of the
    substep, not bouncing off a speed gravity gave it after the impact).
    `shift` is the physical u_n minus the integrator's: the integrators'
    velocities are staggered by (w − ½) h against the positions
    (semi-implicit Euler's is leapfrog's half-step velocity), so the
    physical one at a step boundary is u + (w − ½) a h, w = END_WEIGHT."""
    for c in range(len(R)):
        u0 = R[c, U0]                # u_n the integrator gave, before any impulse
        u_s = row_velocity(R, c, 0, I[c, BODY_A], I[c, BODY_B], vel_start, omega_start)
        shift = (w - 0.5) * (u0 - u_s)
        u_at, when = impact(u_s + shift, u0 + shift, R[c, DEPTH], h)
        onset[c, WHEN], onset[c, SHIFT], onset[c, AFTER] = when, shift, u0 + shift - u_at


@njit(cache=True, inline="always")
def bounce_goal(R, c, threshold, ramp, h, u_now, onset, target, J):
    """(goal, C_R × approach, τ) of contact c at normal velocity u_now: the
    u_n its bounce must reach, NaN if it does not bounce (it does not
    approach faster than the threshold, its surfaces do not meet within the
    substep, or C_R is 0). Its first bounce of the substep happens at the
    impact, with the approach speed at τ (impact_terms); a later one is a
    plain pairwise collision."""
    after, when, shift = 0.0, 1.0, 0.0
    if target[c] == 0.0 and J[c, 0] == 0.0:
        after, when, shift = onset[c, AFTER], onset[c, WHEN], onset[c, SHIFT]
    u_imp = u_now + shift - after    # physical, at the impact, with the impulses so far
    approach = -u_imp
    if not (approach > threshold and approach * h > -R[c, DEPTH]):
        return math.nan, 0.0, when
    e = effective_restitution(R[c, E], approach, threshold, ramp)
    if not e > 0.0:                  # an inelastic impact is the solve's (all its points at once)
        return math.nan, 0.0, when
    return e * approach + after - shift, e * approach, when


@njit(cache=True, inline="always")
def add_bounces(R, J, friction):
    """The pass's impulses into the rows' λ and the friction vectors (after
    the warm cache took the solve's own)."""
    for c in range(len(R)):
        for r in range(3):
            R[c, LAM + r] += J[c, r]
        for i in range(3):
            friction[c, i] += tangent_world(R, c, J[c, 1], J[c, 2], i)
