"""Where kinetic friction moves a sliding body within its substep (COURSE.md 2 and 4).

A contact that slides all through the substep at its kinetic bound is a
force of constant size, μ_k F_N against the slip (COURSE.md 2), and a
constant acceleration a moves a body by v h + ½ a h² in h (COURSE.md 4:
Δp = v0 t + ½ a t²), half of the a h² a velocity-then-position step gives
it. The correct stage (push_out.py) moves every body by its velocity change
times h; for the part of that change that came from such a friction
impulse it moves by half, so a box sliding to a stop covers v0² / (2 μ_k g)
to within a dt² term instead of falling v0 dt / 2 short.

Only the impulses at the kinetic bound after the solve count: an unsaturated
one (a contact that sticks, or stops within the substep) is not a constant
force over the whole substep. Only translation: the normal impulses that
balance friction's torque about the centre move the body in full, and
halving only one of the two would turn a sliding box a little every substep.
Bounces and bodies the ccd stage moved back keep their own motion rule.
"""
from numba import njit

from .contact_layout import BODY_A, BODY_B, DIR, INV_MASS_A, INV_MASS_B, LAM, MU, SLIDING, STRIDE
from .manifold_friction import COUNT, FIRST, IMA, IMB, L, M_LAM, M_MU_K, M_SLIDING
from .scratch import take_rows

# how close to the bound a solved impulse counts as on it: the cap sets it to
# the bound times |u| / sqrt(|u|² + 1e-300), equal to rounding
_ON_BOUND = 1.0 - 1e-9


@njit(cache=True, inline="always")
def _add(out, a, b, ima, imb, fx, fy, fz):
    """Velocity change of an impulse f on b (−f on a), into out."""
    out[a, 0] -= ima * fx
    out[a, 1] -= ima * fy
    out[a, 2] -= ima * fz
    out[b, 0] += imb * fx
    out[b, 1] += imb * fy
    out[b, 2] += imb * fz


@njit(cache=True, inline="always")
def _row(R, I, c, out):
    """A single-point contact's friction, if it slid at μ_k λ_n."""
    l1, l2 = R[c, LAM + 1], R[c, LAM + 2]
    lim = R[c, MU] * R[c, LAM]
    if I[c, SLIDING] == 0 or lim <= 0.0 or l1 * l1 + l2 * l2 < (lim * _ON_BOUND) ** 2:
        return
    d = DIR + STRIDE
    _add(out, I[c, BODY_A], I[c, BODY_B], R[c, INV_MASS_A], R[c, INV_MASS_B],
         l1 * R[c, d] + l2 * R[c, d + STRIDE], l1 * R[c, d + 1] + l2 * R[c, d + STRIDE + 1],
         l1 * R[c, d + 2] + l2 * R[c, d + STRIDE + 2])


@njit(cache=True, inline="always")
def _anchor(R, I, M, MI, k, out):
    """A manifold's anchor friction, if it slid at μ_k Σλ_n."""
    first, count = MI[k, FIRST], MI[k, COUNT]
    ln = 0.0
    for c in range(first, first + count):
        ln += R[c, LAM]
    l0, l1 = M[k, M_LAM], M[k, M_LAM + 1]
    lim = M[k, M_MU_K] * ln
    if MI[k, M_SLIDING] == 0 or lim <= 0.0 or l0 * l0 + l1 * l1 < (lim * _ON_BOUND) ** 2:
        return
    _add(out, I[first, BODY_A], I[first, BODY_B], M[k, IMA], M[k, IMB],
         l0 * M[k, L] + l1 * M[k, L + STRIDE], l0 * M[k, L + 1] + l1 * M[k, L + STRIDE + 1],
         l0 * M[k, L + 2] + l1 * M[k, L + STRIDE + 2])


@njit(cache=True, inline="always")
def kinetic_velocity_change(R, I, M, MI, n, store):
    """(n, 3) each body's velocity change from friction at its kinetic bound
    (the solve's final impulses, before the collision pass's are added);
    (0, 3) when no contact slides. In the substep's scratch (scratch.py)."""
    sliding = False
    for k in range(len(MI)):
        sliding |= MI[k, M_SLIDING] != 0
    if not sliding:
        return take_rows(store, 0, 3)
    out = take_rows(store, n, 3)
    out[:] = 0.0
    for k in range(len(MI)):
        if MI[k, COUNT] < 2:
            _row(R, I, MI[k, FIRST], out)
        else:
            _anchor(R, I, M, MI, k, out)
    return out
