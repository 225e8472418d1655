"""Continuous collision: fast bodies stop at their time of impact (COURSE.md 5).

Detecting contacts only at the end of a substep lets a fast, thin object
pass through another within one substep. For every body that moves more
than `ccd_threshold` of its own smallest half size in the substep, toi.py
finds the first instant in [t, t + h] its path touches something (sampling
and bisection, the course's "time of collision"). A body with a hit is put
back at its pose at that instant (the earliest of its hits) and keeps its
velocity; the collide stage then finds the contact there, and the solver
treats it as starting the substep at that pose: the approach is stopped
(and bounced) at once, and the correct stage leaves the body at its time
of impact pose instead of moving it on. The rest of the substep, (1 − t) h,
is lost for that body: a small, bounded time error instead of a tunnel.
"""
import numpy as np

try:        # the C entry point of np.einsum, without the Python dispatch layer
    from numpy._core.multiarray import c_einsum as _einsum
except ImportError:     # pragma: no cover - other numpy layouts
    _einsum = np.einsum

from . import toi
from .broadphase import bounding_radius


class CcdConstants:
    """What the cheap test below needs of the model, computed once."""

    def __init__(self, model, params):
        self.twice_radius = 2.0 * bounding_radius(model)
        self.fast_beyond = params.ccd_threshold * toi.smallest_half_size(model)
        self.max_twice_radius = float(self.twice_radius.max(initial=0.0))
        smallest = float(self.fast_beyond.min(initial=np.inf))
        self.quarter_min2 = (0.49 * smallest) ** 2   # (under ½ the smallest threshold)², room for round-off


class CcdStage:
    """The ccd stage: stage(world, ctx) marks the bodies it moves back in the
    contact scratch (`rewound`), for the collide and correct stages."""

    def __init__(self, model, params, scratch):
        self.params = params
        self.consts = CcdConstants(model, params)
        self.scratch = scratch

    def __call__(self, world, ctx):
        back = rewind_fast_bodies(world, ctx.h, self.params, ctx.prev_pos, ctx.prev_quat,
                                  self.consts)
        if back is not None:
            sc = self.scratch(world)
            sc.rewound[back] = True
            sc.any_rewound = True


def ccd(world, h, params, scratch, consts=None):
    scratch.rewound = None
    back = rewind_fast_bodies(world, h, params, world.prev_pos, world.prev_quat, consts)
    if back is not None:
        rewound = np.zeros(world.model.n, bool)
        rewound[back] = True
        scratch.rewound = rewound


def rewind_fast_bodies(world, h, params, p0, q0, consts=None):
    """Indices of the bodies moved back to their time of impact (None: none)."""
    model, s = world.model, world.state
    consts = consts or CcdConstants(model, params)
    # cheap bound first: no point moves further than |Δc| + R θ, θ ≈ |ω| h (taken
    # twice, as the integrator's ω may differ within the substep); a sleeping
    # body has not moved (reach 0) and static ones have an infinite threshold
    # only if they are planes, so they are masked out below
    d = s.pos - p0
    d2 = _einsum("ij,ij->i", d, d)
    w2 = _einsum("ij,ij->i", s.omega, s.omega)
    # cheaper still, for a scene at rest: every |Δc| and every R θ under half
    # the smallest threshold means no body can be over its own
    if (d2.max(initial=0.0) <= consts.quarter_min2
            and w2.max(initial=0.0) * (consts.max_twice_radius * h) ** 2 <= consts.quarter_min2):
        return
    reach = np.sqrt(d2) + consts.twice_radius * h * np.sqrt(w2)
    over = reach > consts.fast_beyond
    if not over.any():
        return
    moving = ~model.is_static & s.awake
    if not np.count_nonzero(moving & over):
        return
    fast = moving & toi.fast_body_mask(model, p0, s.pos, params.ccd_threshold,
                                       prev_quat=q0, quat=s.quat)
    if not fast.any():
        return
    a, b = toi.swept_pairs(model, p0, q0, s.pos, s.quat, fast, params.margin)
    if not len(a):
        return
    t, hit = toi.time_of_impact(model, p0, q0, s.pos, s.quat, a, b,
                                params.ccd_iterations, params.ccd_tolerance)
    if not hit.any():
        return
    a, b, t = a[hit], b[hit], t[hit]
    first = np.full(model.n, np.inf)
    np.minimum.at(first, a, t)
    np.minimum.at(first, b, t)
    back = np.flatnonzero(np.isfinite(first) & moving)
    if not len(back):
        return
    s.pos[back], s.quat[back] = toi.interpolate_poses(p0[back], q0[back], s.pos[back],
                                                      s.quat[back], first[back])
    return back
