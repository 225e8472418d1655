"""The World: a frozen Model, a mutable State, and the step as named stages.

`World.step()` reads top to bottom (Box2D's b2World_Step style):

    impulses   – pending user impulses, once (only when some are pending)
    per substep (`world.substeps` of them, h = dt / substeps):
      integrate  – the scene's integrator over the declared force effects
      <contact stages> – only when the scene declares `contacts`
    finite     – refuse NaN/inf: report the body instead of propagating it

Each stage, and each force effect inside `integrate`, is timed into
`world.profile` (seconds, cumulative) and `world.last_step_profile`.

Sub-steps: `world.substeps = max(scene substeps, world.spring_substeps)`.
`spring_substeps` is computed once from the scene's springs so that the
stiffest one is integrated with ω h ≤ 0.5, ω = √(K/m_eff), and its damper
with (C/m_eff) h ≤ 0.5 (effects/springs.py); a k = 1e6 N/m spring on 1 kg at
dt = 1/240 s gets 9 sub-steps instead of blowing up. Scenes without springs
keep the scene's count.
"""
import math
from collections import defaultdict
from time import perf_counter

import numpy as np

from . import quaternion as qt
from .body_view import BodyView
from .contact_events import ContactEvents
from .effects import Kinematics, build_force_effects, potential_energy
from .effects.springs import makes_torque, stable_substeps
from .errors import CommandError, NonFiniteStateError
from .free_rotation import RowSplit, isotropic_rows
from .integrators import INTEGRATORS
from .shapes import BOX
from .state import State
from .vec3 import cross


class World:
    def __init__(self, model):
        self.model = model
        self.state = State.from_initial(model.initial)
        self.contacts = ContactEvents.empty()
        self.profile = defaultdict(float)
        self.last_step_profile = {}
        self.last_step_seconds = 0.0
        self._prof = {}   # the current step's timings; forces() may also be called between steps
        self._force_effects = build_force_effects(model)
        self._timed_effects = [("force:" + name, apply) for name, apply in self._force_effects]
        self.spring_substeps = stable_substeps(model, model.dt)
        self.substeps = max(model.substeps, self.spring_substeps)
        self._integrate = INTEGRATORS[model.integrator]
        self.isotropic = isotropic_rows(model.inertia)   # free rotation is exact for these
        self.rotation_rows = RowSplit(self.isotropic)    # ... and needs no splitting
        self._contact_stages = []
        if "contacts" in model.effects:
            from .collision import build_contact_stages
            self._contact_stages = build_contact_stages(model)
        # Effects whose forces can turn a body; with none of these, no commanded
        # torque and no spin, the rotational update is skipped. Contacts change
        # ω directly (not through forces), so the test is made per substep.
        self._model_torque = bool(
            makes_torque(model)
            or ("buoyancy" in model.effects and np.any(model.shape_type == BOX)))
        self.refresh_awake()

    # ---- the pipeline -------------------------------------------------
    @property
    def stage_names(self):
        """Names of the stages this scene's step runs, in order (promise 3)."""
        names = ["impulses", "integrate"]
        names += [f"force:{n}" for n, _ in self._force_effects]
        names += [n for n, _ in self._contact_stages]
        return names + ["finite"]

    def step(self, n: int = 1):
        for _ in range(int(n)):
            self._step_once()
        return self

    def _step_once(self):
        s = self.state
        start = perf_counter()
        prof = {}
        self._prof = prof
        if s.has_pending_impulse:
            self._timed("impulses", self._apply_impulses)
        h = self.model.dt / self.substeps
        for sub in range(self.substeps):
            self.substep = sub
            self.rotating = bool(self._model_torque or s.has_user_torque or s.omega.any())
            if self._contact_stages:
                # start-of-substep pose, for time of impact and contact normals (COURSE.md 5)
                self.prev_pos = s.pos.copy()
                self.prev_quat = s.quat.copy()
            t0 = perf_counter()
            self._integrate(self, h)
            prof["integrate"] = prof.get("integrate", 0.0) + perf_counter() - t0
            for name, stage in self._contact_stages:
                t0 = perf_counter()
                stage(self, h)
                prof[name] = prof.get(name, 0.0) + perf_counter() - t0
        s.step_index += 1
        s.time = s.step_index * self.model.dt
        self._timed("finite", self._check_finite)
        self.last_step_seconds = perf_counter() - start
        self.last_step_profile = prof
        for k, v in prof.items():
            self.profile[k] += v
        self.profile["step"] += self.last_step_seconds

    def _timed(self, name, fn):
        t0 = perf_counter()
        fn()
        self._prof[name] = self._prof.get(name, 0.0) + perf_counter() - t0

    def forces(self, pos, quat, vel, omega):
        """Net force and torque (world frame) on every body at a trial state."""
        F = np.zeros_like(pos)
        T = np.zeros_like(pos)
        kin = Kinematics(pos, quat, vel, omega)
        prof = self._prof
        for key, apply in self._timed_effects:
            t0 = perf_counter()
            apply(kin, F, T)
            prof[key] = prof.get(key, 0.0) + perf_counter() - t0
        s = self.state
        if s.has_user_force:
            F += s.user_force
        if s.has_user_torque:
            T += s.user_torque + cross(qt.rotate(quat, s.user_force_offset), s.user_force)
        return F, T

    def _apply_impulses(self):
        """Δv = J/m, ΔL = r × J + angular impulse (COURSE.md 3, angular impulse)."""
        s = self.state
        s.vel += s.impulse * self.inv_mass
        L = (s.angular_impulse if not s.omega.any() else
             qt.rotate(s.quat, self.inertia * qt.rotate_inverse(s.quat, s.omega)) + s.angular_impulse)
        s.omega = qt.rotate(s.quat, self.inv_inertia * qt.rotate_inverse(s.quat, L))
        s.impulse[:] = 0.0
        s.angular_impulse[:] = 0.0
        s.has_pending_impulse = False

    def _check_finite(self):
        s = self.state
        total = s.pos.sum() + s.vel.sum() + s.omega.sum() + s.quat.sum()
        if not math.isfinite(total):
            bad = ~(np.isfinite(s.pos).all(1) & np.isfinite(s.vel).all(1)
                    & np.isfinite(s.omega).all(1) & np.isfinite(s.quat).all(1))
            names = [self.model.names[i] for i in np.flatnonzero(bad)]
            raise NonFiniteStateError(
                f"step {s.step_index}: non-finite state for bodies {names[:10]}"
                + (f" (+{len(names) - 10} more)" if len(names) > 10 else "")
                + "; stage timings " + ", ".join(self._prof))

    # ---- awake set ------------------------------------------------------
    def refresh_awake(self):
        """Recompute the effective inverse mass and inertia after bodies sleep or wake.

        A sleeping body has zero inverse mass for the integrator, so forces do
        not move it and it costs nothing but array rows."""
        m = self.model
        awake = self.state.awake
        self.inv_mass = (m.inv_mass * awake)[:, None]
        self.inv_inertia = m.inv_inertia * awake[:, None]
        self.inertia = m.inertia

    def wake(self, i):
        if not self.state.awake[i]:
            self.state.awake[i] = True
            self.refresh_awake()

    # ---- commands (INTERFACE.md Python API) ------------------------------
    def _body_index(self, name) -> int:
        i = self.model.index.get(name)
        if i is None:
            raise CommandError(f"unknown body {name!r}; bodies are: {', '.join(self.model.names)}")
        if self.model.is_static[i]:
            raise CommandError(f"body {name!r} is static: forces and impulses do not move it")
        return i

    @staticmethod
    def _vec(value, what) -> np.ndarray:
        try:
            v = np.array(value, dtype=float).reshape(3)
        except (TypeError, ValueError):
            raise CommandError(f"{what}: expected 3 numbers, got {value!r}") from None
        if not np.all(np.isfinite(v)):
            raise CommandError(f"{what}: expected finite numbers, got {v.tolist()}")
        return v

    def apply_force(self, name, force, point=None):
        """Hold a force (N, world frame) on a body until replaced; zero clears it.

        With a world `point`, the force acts there: the point is fixed to the
        body (stored in body axes) so τ = r × F follows the body as it turns."""
        i = self._body_index(name)
        f = self._vec(force, f"force on {name!r}")
        # Validate every argument before touching the state: a refused command
        # must leave no trace (not even its valid half).
        p = None if point is None else self._vec(point, f"point of force on {name!r}")
        s = self.state
        s.user_force[i] = f
        s.has_user_force = True
        if p is None:
            s.user_force_offset[i] = 0.0
        else:
            s.user_force_offset[i] = qt.rotate_inverse(s.quat[i:i + 1], (p - s.pos[i])[None])[0]
            s.has_user_torque = True
        self.wake(i)

    def apply_torque(self, name, torque):
        """Hold a torque (N·m, world frame) on a body until replaced; zero clears it."""
        i = self._body_index(name)
        self.state.user_torque[i] = self._vec(torque, f"torque on {name!r}")
        self.state.has_user_torque = True
        self.wake(i)

    def apply_impulse(self, name, impulse, point=None):
        """A linear impulse (N·s, world frame), applied once at the next step.

        At a world `point`, it also adds the angular impulse r × J."""
        i = self._body_index(name)
        j = self._vec(impulse, f"impulse on {name!r}")
        p = None if point is None else self._vec(point, f"point of impulse on {name!r}")
        s = self.state
        s.impulse[i] += j
        if p is not None:
            s.angular_impulse[i] += cross(p - s.pos[i], j)
        s.has_pending_impulse = True
        self.wake(i)

    def apply_angular_impulse(self, name, angular_impulse):
        """An angular impulse (N·m·s, world frame), applied once at the next step."""
        i = self._body_index(name)
        self.state.angular_impulse[i] += self._vec(angular_impulse, f"angular impulse on {name!r}")
        self.state.has_pending_impulse = True
        self.wake(i)

    # ---- reading ---------------------------------------------------------
    def body(self, name) -> BodyView:
        i = self.model.index.get(name)
        if i is None:
            raise KeyError(f"unknown body {name!r}; bodies are: {', '.join(self.model.names)}")
        return BodyView(self, i)

    @property
    def time(self) -> float:
        return self.state.time

    @property
    def step_index(self) -> int:
        return self.state.step_index

    @property
    def dt(self) -> float:
        return self.model.dt

    def kinetic_energy(self) -> float:
        """Σ ½ m v² + ½ ω·I_w ω over dynamic bodies, J."""
        m, s = self.model, self.state
        mass = np.where(m.is_static, 0.0, m.mass)
        wb = qt.rotate_inverse(s.quat, s.omega)
        inertia = np.where(m.is_static[:, None], 0.0, m.inertia)
        return float(0.5 * np.sum(mass * np.einsum("ij,ij->i", s.vel, s.vel))
                     + 0.5 * np.sum(inertia * wb * wb))

    def energy(self) -> float:
        """Kinetic plus the potential energy of the effects in play, J (COURSE.md 6)."""
        return self.kinetic_energy() + potential_energy(self.model, self.state)

    def momentum(self) -> np.ndarray:
        m = np.where(self.model.is_static, 0.0, self.model.mass)
        return (m[:, None] * self.state.vel).sum(axis=0)

    def angular_momentum(self, about=(0.0, 0.0, 0.0)) -> np.ndarray:
        """Total L = Σ (r × m v + I_w ω) about a world point, N·m·s."""
        m, s = self.model, self.state
        mass = np.where(m.is_static, 0.0, m.mass)
        r = s.pos - np.asarray(about, dtype=float)
        spin = qt.rotate(s.quat, np.where(m.is_static[:, None], 0.0, m.inertia)
                         * qt.rotate_inverse(s.quat, s.omega))
        return (cross(r, mass[:, None] * s.vel) + spin).sum(axis=0)

    def reset(self):
        """Back to the scene's initial state at time 0 (commands cleared)."""
        self.state = State.from_initial(self.model.initial)
        self.contacts = ContactEvents.empty()
        self.refresh_awake()
