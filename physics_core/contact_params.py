"""Settings of the `contacts` effect: collision detection and response.

Every key of `effects.contacts` in a scene, with its unit and default. All are
optional; `contacts: {}` gives the defaults below. The stages that use them
live in physics_core/collision (see its __init__ for the order).
"""
from dataclasses import dataclass

RESTITUTION_COMBINES = ("effective_mass", "mean", "min", "max")


@dataclass(frozen=True)
class ContactParams:
    # -- velocity solver (COURSE.md 5, impulses; Box2D's sequential impulses) --
    iterations: int = 8                  # velocity-solver sweeps over all contacts per (sub)step, each
                                         # visiting the contacts one after the other in key order
    velocity_tolerance: float = 1e-4     # m/s; sweeps stop early once none changes a contact's
                                         # relative velocity by more than this (0: always all sweeps);
                                         # where the shock sweep runs, sweeps converging fast go on
                                         # to 1/100 of it, and sweeps whose change has stalled stop
                                         # (contact_stages.solve_stage)
    warm_start: float = 1.0              # fraction of last substep's impulses applied first, 0..1
    static_friction_speed: float = 0.01  # m/s; a contact slipping slower than this is held by static
                                         # friction (μ_s), faster it slides with μ_k (COURSE.md 5)
    margin: float = 0.001                # m; pairs closer than this are kept as (speculative) contacts
    shock_propagation: bool = True       # a last sweep from the ground up, each body resting on what
                                         # holds it: stacks and mass ratios (shock_propagation.py)
    resting_block: bool = True           # in that sweep, a body resting on one support through three or
                                         # more points is solved at once (collision/resting_block.py)
    # -- restitution (COURSE.md 5, coefficient of restitution, resting contact) --
    restitution_threshold: float = 0.5   # m/s; approach speeds below this bounce with C_R = 0
    restitution_ramp: float = 0.0        # m/s; C_R grows linearly from 0 over this band above the
                                         # threshold (0: switched on at once)
    restitution_combine: str = "effective_mass"   # how two bodies' C_R make the pair's (collision/restitution.py)
    restitution_iterations: int = 32     # sweeps of the collision pass at most: pairwise bounces are
                                         # repeated until no contact approaches faster than the threshold
    # -- position correction (split impulse: moves positions, adds no velocity) --
    position_iterations: int = 4         # sweeps of the position (pseudo-velocity) solver per (sub)step
    slop: float = 0.005                  # m; penetration left alone (keeps resting contacts warm)
    correction_rate: float = 0.2         # fraction of the remaining penetration removed per (sub)step
    max_correction_speed: float = 1.0    # m/s; cap on the push-out rate (position only, never velocity)
    # -- continuous collision (COURSE.md 5, time of collision by bisection) --
    ccd: bool = True                     # time-of-impact for fast bodies so thin walls are not crossed
    ccd_threshold: float = 0.5           # a body is fast when any of its points moves more than this
                                         # fraction of its smallest half extent (or radius) in one (sub)step
    ccd_iterations: int = 30             # bisection halvings of [t, t + h] at most (more while the
                                         # pose found is still beyond the margin: it must touch)
    ccd_tolerance: float = 1e-4          # fraction of the (sub)step: bisection stops when the bracket
                                         # [t0, t1] is shorter (the body is left apart, at t0)
    # -- sleep (Box2D: bodies at rest leave the solver) --
    sleep: bool = True                   # freeze bodies at rest until touched or commanded
    sleep_linear_speed: float = 0.05     # m/s; below this (and the angular one) a body counts as at rest
    sleep_angular_speed: float = 0.1     # rad/s
    sleep_time: float = 0.5              # s; an island sleeps when all its bodies rested this long


CONTACT_KEYS = set(ContactParams.__dataclass_fields__)


def parse_contacts(r) -> ContactParams:
    """Read `effects.contacts` from a validate.Reader."""
    r.only(CONTACT_KEYS)
    d = ContactParams()
    return ContactParams(
        iterations=r.number("iterations", d.iterations, min=1, max=1000, integer=True),
        velocity_tolerance=r.number("velocity_tolerance", d.velocity_tolerance, min=0.0),
        warm_start=r.number("warm_start", d.warm_start, min=0.0, max=1.0),
        static_friction_speed=r.number("static_friction_speed", d.static_friction_speed, min=0.0),
        margin=r.number("margin", d.margin, min=0.0, max=1.0),
        restitution_threshold=r.number("restitution_threshold", d.restitution_threshold, min=0.0),
        restitution_ramp=r.number("restitution_ramp", d.restitution_ramp, min=0.0),
        restitution_combine=r.string("restitution_combine", d.restitution_combine,
                                     choices=RESTITUTION_COMBINES),
        restitution_iterations=r.number("restitution_iterations", d.restitution_iterations, min=0,
                                        max=1000, integer=True),
        shock_propagation=r.boolean("shock_propagation", d.shock_propagation),
        resting_block=r.boolean("resting_block", d.resting_block),
        position_iterations=r.number("position_iterations", d.position_iterations, min=0, max=1000,
                                     integer=True),
        slop=r.number("slop", d.slop, min=0.0),
        correction_rate=r.number("correction_rate", d.correction_rate, min=0.0, max=1.0),
        max_correction_speed=r.number("max_correction_speed", d.max_correction_speed, min=0.0),
        ccd=r.boolean("ccd", d.ccd),
        ccd_threshold=r.number("ccd_threshold", d.ccd_threshold, positive=True),
        ccd_iterations=r.number("ccd_iterations", d.ccd_iterations, min=1, max=60, integer=True),
        ccd_tolerance=r.number("ccd_tolerance", d.ccd_tolerance, positive=True),
        sleep=r.boolean("sleep", d.sleep),
        sleep_linear_speed=r.number("sleep_linear_speed", d.sleep_linear_speed, min=0.0),
        sleep_angular_speed=r.number("sleep_angular_speed", d.sleep_angular_speed, min=0.0),
        sleep_time=r.number("sleep_time", d.sleep_time, min=0.0),
    )
