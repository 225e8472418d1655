"""The contact stages of a substep, over the arrays of one World (see __init__)."""
import numpy as np

from .. import quaternion as qt
from ..alloc import keep_freed_memory
from . import contact_rows, restitution, sleep, solver
from .coloring import batches, color_contacts
from .events import EventAccumulator
from .manifold import Manifold, detect, same
from .pair_cache import PairCache
from .warm_start import WarmCache

SCRATCH_KEY = "contacts"


class ContactScratch:
    """What the contact stages keep between substeps and steps (in State.scratch,
    so World.reset() starts afresh)."""

    def __init__(self, model):
        n = model.n
        self.pairs = PairCache(model)   # broad-phase pairs kept between substeps
        self.warm = WarmCache()
        self.events = EventAccumulator()
        self.sleep = sleep.SleepState(n)
        self.rows = None          # this substep's ContactRows (None: no contact)
        self.V = None             # (n, 6) velocities being solved
        self.V0 = None            # (n, 6) velocities the integrator moved the bodies with
        self.rewound = None       # (n,) bool: bodies the ccd stage moved back this substep
        self.bounce = None        # (bodies, τ) of this substep's restitution contacts
        self.sweeps = 0           # velocity sweeps the last solve needed
        self.colour_key = None    # colouring cache: keys and awake set it was made for
        self.colour_awake = None
        self.colour = None
        self.colour_of = None     # (k,) colour of each contact of colour_key
        self.colour_in_order = False   # the colouring's order is the identity
        self.fresh_colours = 0    # colours of the last colouring from scratch
        self.row_cache = contact_rows.RowCache()   # last substep's per-contact-set arrays


def merge_tail(bounds, fraction):
    """Merge the last, sparse colours into one batch (bounds, its first row).

    Colour sizes fall off fast (a pile: 528, 353, …, 22, 5 rows), yet every
    batch costs the same fixed numpy overhead. The trailing colours holding
    at most `fraction` of the rows become one batch whose rows may share a
    body: it is solved Jacobi-style with mass splitting, as the `jacobi`
    solver is. With fraction 0 the sweep stays pure Gauss–Seidel."""
    k = int(bounds[-1])
    sizes = np.diff(bounds)
    tail = np.cumsum(sizes[::-1])[::-1]             # rows from each batch to the end
    fits = np.flatnonzero(tail <= fraction * k)
    if len(fits) == 0 or fits[0] >= len(sizes) - 1:  # nothing, or a single batch: keep
        return bounds, k
    first = int(fits[0])
    start = int(bounds[first])
    return np.append(bounds[:first + 1], k), start


class ContactPipeline:
    def __init__(self, model, params):
        self.model = model
        self.p = params
        self.summed = params.solver == "jacobi"
        # bodies whose principal moments are equal have I_w⁻¹ = I⁻¹ 1 in any pose
        I = model.inertia
        self.isotropic = bool(np.all(np.ptp(I, axis=1) <= 1e-12 * np.max(I, axis=1)))
        keep_freed_memory()     # the contact arrays are reallocated every substep (alloc.py)

    def stages(self):
        out = []
        if self.p.ccd:
            from .ccd_stage import CcdConstants, ccd
            consts = CcdConstants(self.model, self.p)
            out.append(("ccd", lambda world, h: ccd(world, h, self.p, self.scratch(world), consts)))
        out += [("collide", self.collide), ("solve", self.solve),
                ("restitution", self.restitution), ("correct", self.correct),
                ("events", self.events)]
        if self.p.sleep:
            out.append(("sleep", self.sleep))
        return out

    def scratch(self, world) -> ContactScratch:
        sc = world.state.scratch.get(SCRATCH_KEY)
        if sc is None:
            sc = world.state.scratch[SCRATCH_KEY] = ContactScratch(self.model)
        return sc

    @staticmethod
    def _last_substep(world):
        return world.substep == getattr(world, "substeps", world.model.substeps) - 1

    # ---- collide -----------------------------------------------------------
    def collide(self, world, h):
        model, s, p = self.model, world.state, self.p
        sc = self.scratch(world)
        if world.substep == 0:
            sc.events.reset()
        if p.sleep:
            sc.sleep.sync(s.awake)
        moving = ~model.is_static & s.awake
        if moving.any():
            m = detect(model, s.pos, s.quat, p.margin, sc.pairs)
        else:
            m = Manifold.empty()     # all asleep: nothing can start touching
        if p.sleep and len(m) and sleep.wake_touched(world, sc.sleep, m.a, m.b, m.depth, p):
            moving = ~model.is_static & s.awake
        if len(m):
            keep = moving[m.a] | moving[m.b]
            if not keep.all():
                m = m.take(keep)
        sc.rows = None
        sc.bounce = None
        if not len(m):
            sc.warm.clear()
            sc.rewound = None
            return
        order, bounds, summed_from = self._batches(sc, m, moving)
        if not sc.colour_in_order:
            m = m.take(order)
        V = contact_rows.body_velocities(s)
        sc.V0 = V.copy()
        inv_mass = world.inv_mass[:, 0]
        split = None
        if summed_from < len(m):
            # mass splitting: a body's inverse mass × its number of rows in the summed batch
            ta, tb = m.a[summed_from:], m.b[summed_from:]
            count = (np.bincount(ta[moving[ta]], minlength=model.n)
                     + np.bincount(tb[moving[tb]], minlength=model.n))
            split = np.ones((len(m), 2))
            split[summed_from:, 0] = np.maximum(count[ta], 1)
            split[summed_from:, 1] = np.maximum(count[tb], 1)
        if self.isotropic:
            iw, iso = None, world.inv_inertia[:, 0]
        else:
            iw, iso = contact_rows.world_inverse_inertia(s.quat, world.inv_inertia), None
        rows = contact_rows.build(model, m, s.pos, inv_mass, iw, iso, V, h, p, split, sc.rewound,
                                  sc.row_cache, (world.inv_mass, world.inv_inertia))
        rows.bounds = bounds
        rows.summed_from = summed_from
        rows.key_sorted = sc.colour_in_order      # detect's rows come in key order
        # a new contact starts held by static friction; from its next substep
        # on, its slip after the solve tells whether it slides
        slip = sc.warm.load(rows, p.warm_start)
        rows.sliding = slip > p.static_friction_speed      # NaN (new contact): False
        rows.mu = np.where(rows.sliding, rows.mu_k, rows.mu_s)
        sc.rows, sc.V = rows, V

    def _batches(self, sc, m, moving):
        """(order, bounds, summed_from): rows sorted by batch, the batch bounds,
        and the first row of the trailing batch solved with summed updates."""
        k = len(m)
        if self.summed:
            sc.colour_in_order = True
            return np.arange(k), np.array([0, k]), 0
        if (sc.colour is not None and same(sc.colour_key, m.key)
                and same(sc.colour_awake, moving)):
            return sc.colour
        u = np.where(moving[m.a], m.a, -1)
        w = np.where(moving[m.b], m.b, -1)
        prior = None
        if sc.colour is not None and len(sc.colour_key):
            i = np.minimum(np.searchsorted(sc.colour_key, m.key), len(sc.colour_key) - 1)
            prior = np.where(sc.colour_key[i] == m.key, sc.colour_of[i], -1)
        colour = color_contacts(u, w, self.model.n, prior)
        order, bounds = batches(colour)
        if prior is not None and len(bounds) - 1 > sc.fresh_colours + 1:
            # kept colours have fragmented: start afresh (fewer batches per sweep)
            prior = None
            colour = color_contacts(u, w, self.model.n)
            order, bounds = batches(colour)
        if prior is None:
            sc.fresh_colours = len(bounds) - 1
        sc.colour = order, *merge_tail(bounds, self.p.tail_fraction)
        sc.colour_key, sc.colour_awake, sc.colour_of = m.key, moving, colour
        sc.colour_in_order = bool(np.all(order[1:] > order[:-1]))    # no reordering to do
        return sc.colour

    # ---- solve -------------------------------------------------------------
    def solve(self, world, h):
        sc = self.scratch(world)
        rows = sc.rows
        if rows is None:
            return
        solver.warm_start(sc.V, rows, self.summed)
        sc.sweeps = solver.solve_velocities(sc.V, rows, self.p.iterations, self.summed,
                                            self.p.velocity_tolerance)
        sc.warm.store(rows, solver.tangential_slip(sc.V, rows))

    def restitution(self, world, h):
        sc = self.scratch(world)
        rows = sc.rows
        if rows is None:
            return
        sc.bounce = None
        if rows.u0[:, 0].min() >= -self.p.restitution_threshold:
            # nothing approaches faster than the threshold: every C_R is 0 (NaN: go on)
            return
        approach = -rows.u0[:, 0]
        e = restitution.effective(rows.e, approach, self.p.restitution_threshold,
                                  self.p.restitution_ramp)
        active = (e > 0.0) & (rows.lam[:, 0] > 0.0)
        sc.bounce = None
        if np.count_nonzero(active):
            solver.solve_normal_targets(sc.V, rows, e * approach, active, 1, self.summed)
            # Fraction of the substep before the surfaces met (COURSE.md 5, time of
            # collision): s0 = s_end + h·approach closes at that speed. The bodies
            # move with the old velocity until then and with the new one after.
            i = np.flatnonzero(active)
            s0 = approach[i] * h - rows.depth[i]
            tau = np.clip(s0 / np.maximum(approach[i] * h, 1e-300), 0.0, 1.0)
            sc.bounce = (np.concatenate([rows.a[i], rows.b[i]]), np.concatenate([tau, tau]))

    # ---- correct -----------------------------------------------------------
    def correct(self, world, h):
        """Velocities written back; positions moved by (v − u0) h, then overlap
        beyond `slop` pushed out by pseudo-velocities (split impulse)."""
        sc = self.scratch(world)
        rows = sc.rows
        if rows is None:
            sc.rewound = None
            return
        s, p = world.state, self.p
        V = sc.V
        dV = V - sc.V0
        s.vel[:] = V[:, :3]
        s.omega[:] = V[:, 3:]
        if sc.bounce is not None:
            # a bounce acts from its time of impact τ h on: the end pose is the
            # impact pose plus the new velocity over the rest of the substep
            body, tau = sc.bounce
            after = np.zeros(len(V))
            np.maximum.at(after, body, 1.0 - tau)
            hit = np.zeros(len(V), bool)
            hit[body] = True
            dV *= np.where(hit, after, 1.0)[:, None]
        if sc.rewound is not None:
            dV[sc.rewound] = 0.0     # moved back to their time of impact: stay there
        dsep = solver.einsum("ki,ki->k", rows.J[:, 0, :], dV.reshape(-1).take(solver.flat6(rows))) * h
        sep = dsep - rows.depth
        dX = dV
        # a push is asked for only where the overlap exceeds slop (−sep − slop > 0)
        if (p.position_iterations and p.correction_rate > 0.0 and p.max_correction_speed > 0.0
                and (sep < -p.slop).any()):
            target = np.minimum(p.correction_rate * (-sep - p.slop) / h, p.max_correction_speed)
            if np.count_nonzero(target > 0.0):
                Xp = np.zeros((len(V), 3))
                solver.solve_pseudo(Xp, rows, np.maximum(target, 0.0), p.position_iterations,
                                    self.summed)
                dX = dV.copy()
                dX[:, :3] += Xp
        s.pos += dX[:, :3] * h
        if dX[:, 3:].any():
            turn = np.flatnonzero(dX[:, 3:].any(axis=1))
            s.quat[turn] = qt.integrate(s.quat[turn], dX[turn, 3:], h)
        sc.rewound = None

    # ---- events and sleep --------------------------------------------------
    def events(self, world, h):
        sc = self.scratch(world)
        if sc.rows is not None:
            # the solve's tangential impulses, as the warm-start cache keeps them
            # (restitution and the position pass change only normal impulses)
            sc.events.add(sc.rows, sc.warm.friction if sc.warm.key is sc.rows.key else None)
        if self._last_substep(world):
            world.contacts = sc.events.finish(self._moving, world.state.awake)

    def _moving(self, awake):
        return ~self.model.is_static & awake

    def sleep(self, world, h):
        if not self._last_substep(world):
            return
        sc = self.scratch(world)
        rows = sc.rows
        if rows is None:
            ea = eb = np.zeros(0, dtype=np.int64)
        else:
            touching = (rows.depth >= 0.0) | (rows.lam[:, 0] > 0.0)
            ea, eb = rows.a[touching], rows.b[touching]
        sleep.update(world, sc.sleep, ea, eb, world.model.dt, self.p)
