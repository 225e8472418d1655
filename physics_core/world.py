"""The World: a frozen Model, a mutable State, and the step as named stages.

`World.step()` reads top to bottom (Box2D's b2World_Step style):

    impulses   – pending user impulses, once (only when some are pending)
    per substep (`world.substeps` of them, h = dt / substeps):
      integrate  – the scene's integrator over the declared force effects
      <contact stages> – only when the scene declares `contacts`
    finite     – after every stage: refuse NaN/inf, naming the stage and the bodies

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
from .body_set import parse_new_body, with_body, without_body
from .body_view import BodyView
from .collision.contact_substep import STAGE_NAMES
from .contact_events import ContactEvents
from .cycle_clock import SECONDS_PER_CYCLE
from .effects import Kinematics, build_force_effects, potential_energy
from .effects.springs import makes_torque, stable_substeps
from .errors import CommandError, NonFiniteStateError
from .finite import non_finite_bodies
from .free_rotation import RowSplit, isotropic_rows
from .integrators import INTEGRATORS
from .shapes import BOX
from .state import State
from .vec3 import cross


class SubstepContext:
    """What a contact stage is given for one substep: its length h (s), its
    index and whether it is the step's last, the poses at its start (time of
    impact, COURSE.md 5) and the solver's inverse masses and inertias (zero
    for static and sleeping bodies; a stage that wakes or puts bodies to
    sleep replaces them here)."""
    __slots__ = ("h", "index", "last", "prev_pos", "prev_quat", "inv_mass", "inv_inertia")

    def __init__(self, h, index, last, prev_pos, prev_quat, inv_mass, inv_inertia):
        self.h, self.index, self.last = h, index, last
        self.prev_pos, self.prev_quat = prev_pos, prev_quat
        self.inv_mass, self.inv_inertia = inv_mass, inv_inertia


class World:
    def __init__(self, model):
        self.scene_model = model          # reset() returns to these bodies
        self.state = State.from_initial(model.initial)
        self.contacts = ContactEvents.empty()
        self._profile = defaultdict(float)
        self.last_step_profile = {}
        self.last_step_seconds = 0.0
        self._prof = {}   # the current step's timings; forces() may also be called between steps
        self._build(model)

    def _build(self, model):
        """Everything the step derives from the model (again after add/remove_body)."""
        self.model = model
        self._force_effects = build_force_effects(model)
        self._timed_effects = [("force:" + name, apply) for name, apply in self._force_effects]
        self.spring_substeps = stable_substeps(model, model.dt)
        self.substeps = max(model.substeps, self.spring_substeps)
        self._integrate = INTEGRATORS[model.integrator]
        self.isotropic = isotropic_rows(model.inertia)   # free rotation is exact for these
        self.rotation_rows = RowSplit(self.isotropic)    # ... and needs no splitting
        self.contact_system = None
        if "contacts" in model.effects:
            from .collision import ContactSystem
            from .contact_params import ContactParams
            self.contact_system = ContactSystem(model, model.effects["contacts"] or ContactParams())
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
        if self.contact_system is not None:
            names += self.contact_system.stage_names
        return names + ["finite"]     # the checks after every stage, timed together

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
            self.rotating = bool(self._model_torque or s.has_user_torque or s.omega.any())
            cs = self.contact_system
            if cs is not None:
                # start-of-substep pose, for time of impact and contact normals (COURSE.md 5)
                ctx = SubstepContext(h, sub, sub == self.substeps - 1, s.pos.copy(), s.quat.copy(),
                                     self.inv_mass[:, 0], self.inv_inertia)
            t0 = perf_counter()
            self._integrate(self, h)
            prof["integrate"] = prof.get("integrate", 0.0) + perf_counter() - t0
            self._check_finite("integrate")
            if cs is not None:
                failed = cs.substep(self, ctx)
                if failed >= 0:
                    self._check_finite(STAGE_NAMES[failed])
                # (bodies that woke or slept had their inverse masses set in place)
        s.step_index += 1
        s.time = s.step_index * self.model.dt
        if self.contact_system is not None:
            self.contacts = self.contact_system.events()
        self.last_step_seconds = perf_counter() - start
        self.last_step_profile = prof
        for k, v in prof.items():
            self._profile[k] += v
        self._profile["step"] += self.last_step_seconds

    @property
    def profile(self):
        """Seconds spent per stage since the World was made (cumulative)."""
        out = dict(self._profile)
        if self.contact_system is not None:
            for name, c in self.contact_system.timed_stages():
                out[name] = out.get(name, 0.0) + c * SECONDS_PER_CYCLE
        return out

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

    def _check_finite(self, stage):
        """Refuse NaN/inf at the end of `stage`: report the bodies instead of
        propagating them (the state is left as that stage made it)."""
        s = self.state
        t0 = perf_counter()
        bad = non_finite_bodies(s.pos, s.quat, s.vel, s.omega)
        self._prof["finite"] = self._prof.get("finite", 0.0) + perf_counter() - t0
        if len(bad):
            names = [self.model.names[i] for i in bad]
            raise NonFiniteStateError(
                f"step {s.step_index + 1}, stage {stage!r}: non-finite state for bodies "
                f"{names[:10]}" + (f" (+{len(names) - 10} more)" if len(names) > 10 else ""),
                stage=stage, bodies=bad)

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
        """Back to the scene's own bodies and initial state at time 0 (commands cleared)."""
        if self.model is not self.scene_model:
            self._build(self.scene_model)
        self.state = State.from_initial(self.model.initial)
        self.contacts = ContactEvents.empty()
        if self.contact_system is not None:
            self.contact_system.reset()
        self.refresh_awake()

    # ---- bodies added and removed between steps ----------------------------
    def add_body(self, spec) -> BodyView:
        """Add a body given with the scene's body keys (validated as in a scene
        file; SceneError names the key). It starts awake, with no loads, as the
        last body; the other bodies keep their indices, states and contacts."""
        body = parse_new_body(self.model, spec)
        n = self.model.n
        model = with_body(self.model, body)
        self.state.append_body(body["pos"], body["quat"], body["vel"], body["omega"])
        self._bodies_changed(model, np.arange(n))
        return BodyView(self, n)

    def remove_body(self, name):
        """Remove a body; the bodies after it move one index down. Its contacts
        end (an `end` event at the next step); springs attached to it go too."""
        i = self.model.index.get(name)
        if i is None:
            raise CommandError(f"unknown body {name!r}; bodies are: {', '.join(self.model.names)}")
        if self.model.n == 1:
            raise CommandError(f"cannot remove {name!r}: a world keeps at least one body")
        model = without_body(self.model, i)
        self.state.remove_body(i)
        new_index = np.arange(self.model.n) - (np.arange(self.model.n) > i)
        new_index[i] = -1
        self._bodies_changed(model, new_index)

    def _bodies_changed(self, model, new_index):
        """Rebuild the step for `model`; new_index[old body] = its new index (-1: removed)."""
        old = self.contact_system
        self._build(model)
        if old is not None and self.contact_system is not None:
            self.contact_system.bodies_changed(old, new_index)
