"""Collision detection and response (COURSE.md 5), as named stages of a substep.

`build_contact_stages(model)` returns the stages the World runs after
`integrate` in every substep, in this order (Box2D v3's solver stages):

    ccd          – (ccd: true) fast bodies: time of impact by bisection along
                   the substep; a body that hits is moved back to its time of
                   impact pose, so a thin wall is never crossed
    collide      – broad and narrow phase at the end-of-substep poses (the
                   broad phase's pair list is kept between substeps while no
                   body moves far, pair_cache.py), wake sleeping bodies that
                   are touched, contact rows, colouring, warm start from last
                   substep (keyed by feature)
    solve        – warm start, then projected Gauss–Seidel on normal and
                   friction impulses with accumulated clamping, one graph
                   colour (a vectorised batch) at a time
    restitution  – bounce pass from the approach speed stored before the
                   solve, zero below restitution_threshold (resting contact)
    correct      – positions follow the velocity change; remaining overlap is
                   pushed out by pseudo-velocities (split impulse) that move
                   positions only, capped at max_correction_speed
    events       – contact begin/persist/end, impulses, gathered per step
    sleep        – (sleep: true) islands at rest leave the solver

Why the contacts are detected after integrating: the integrator moved every
body with its unconstrained velocity u0; a pair found overlapping (or within
`margin`) at the end pose is a contact of this substep. With s_end its
separation there, s0 = s_end − h u0_n is where it started, and the normal row
asks for v_n ≥ −max(s0, 0)/h (speculative contact: close the gap, never
cross it). After the solve every body is moved by (v − u0) h, the position
the integrator would have given with the solved velocity, so the pair ends
the substep touching, not overlapping.
"""
from .contact_system import ContactSystem

__all__ = ["ContactSystem"]
