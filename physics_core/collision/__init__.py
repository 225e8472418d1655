"""Collision detection and response (COURSE.md 5), as named stages of a substep.

`ContactSystem(model, params)` (contact_system.py) holds what the stages
keep; the compiled step loop (physics_core/step_loop.py) runs them after
`integrate` in every substep through contact_substep.run, in this order,
each stage a function of contact_stages.py:

    ccd          – (ccd: true) fast bodies: time of impact by sampling and
                   bisection along the substep (time_of_impact.py); a body
                   that hits is moved back to its time of impact pose
    collide      – broad phase (broad_phase.py) and narrow phase (shape_pairs.py,
                   box_pair.py, detection.py) at the end-of-substep poses,
                   sleeping bodies that are touched woken (sleep_islands.py),
                   contact rows (contact_build.py, contact_layout.py) warm-
                   started from last substep by feature key (warm_cache.py)
    restitution  – the collision pass: bounces with C_R and friction
                   on the bounce impulse, a manifold's points together
                   (their friction at its anchor: bounce_friction.py),
                   swept until no contact approaches faster than
                   restitution_threshold (collision_pass.py, bounce.py)
    solve        – sequential impulses on the normal and friction impulses,
                   contacts in key order (sequential_impulses.py): resting
                   contact and whatever the pass left
    correct      – positions follow the velocity change; remaining overlap is
                   pushed out by pseudo-velocities (split impulse) that move
                   positions only, capped at max_correction_speed (push_out.py)
    events       – contact begin/persist/end, impulses, gathered per step
                   (event_log.py)
    sleep        – (sleep: true) islands at rest leave the solver
                   (sleep_islands.py)

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
