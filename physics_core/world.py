"""The World: a frozen Model, a mutable State, and the step as named stages.

`World.step(n)` reads top to bottom (Box2D's b2World_Step style):

    impulses   – pending user impulses, once (only when some are pending)
    per step, per substep (`world.substeps` of them, h = dt / substeps):
      integrate  – the scene's integrator over the declared force effects
      <contact stages> – only when the scene declares `contacts`
    finite     – after every stage: refuse NaN/inf, naming the stage and the bodies

The n steps run as one compiled loop (step_loop.py), each stage its own
compiled function; each stage, and each force effect inside `integrate`,
is timed into `world.profile` (seconds, cumulative) and
`world.last_step_profile` (the last call's, per step).

Sub-steps: `world.substeps = max(scene substeps, world.spring_substeps)`.
`spring_substeps` is computed once from the scene's springs so that the
stiffest one is integrated with ω h ≤ 0.5, ω = √(K/m_eff), and its damper
with (C/m_eff) h ≤ 0.5 (effects/springs.py); a k = 1e6 N/m spring on 1 kg at
dt = 1/240 s gets 9 sub-steps instead of blowing up. Scenes without springs
keep the scene's count.
"""
from collections import defaultdict
from time import perf_counter

import numpy as np

from .adaptive import (ADAPTIVE, adaptive_data, clear_call, new_stats, read_stats, restart,
                       unused_adaptive)
from .body_set import parse_new_body, with_body, without_body
from .body_view import BodyView
from .collision.contact_substep import STAGE_NAMES
from .command_limits import STATE_LIMIT
from .contact_events import ContactEvents
from .cycle_clock import seconds_per_cycle
from .effects.springs import stable_substeps
from .errors import CommandError, NonFiniteStateError
from .finite import non_finite_bodies
from .free_rotation import RowSplit, isotropic_rows
from .isolation import freeze_rows, frozen_model
from .integration import (EFFECT_NAMES, INTEGRATOR_CODES, N_EFFECTS, can_make_torque, forces,
                          integration_data, integration_profile, integration_work)
from .state import State
from .step_inputs import compiled_entry, pack, same_arrays, state_arrays
from .step_loop import FAILED_INTEGRATE, FINITE, FORCES, INTEGRATE, no_contacts, run_steps
from .world_commands import CommandsMixin
from .world_reading import ReadingMixin


class World(CommandsMixin, ReadingMixin):
    def __init__(self, model):
        self.scene_model = model          # reset() returns to these bodies
        self.state = State.from_initial(model.initial)
        self.contacts = ContactEvents.empty()
        self._profile = defaultdict(float)
        # step_loop's prof slots: totals, then the totals before the last call
        self._cycles = np.zeros(2 * (FORCES + N_EFFECTS), np.int64)
        self._last = None             # the last call's number of steps
        self._adaptive_stats = new_stats()   # adaptive.py's counters, kept across _build
        self._step_seconds = 0.0      # wall time inside world.step, cumulative
        self._last_seconds = 0.0      # and of the last call
        self._build(model)

    def _build(self, model):
        """Everything the step derives from the model (again after add/remove_body)."""
        self.model = model
        self._packed = None           # the step call's arguments (_current_inputs): packed at the next step
        self.spring_substeps = stable_substeps(model, model.dt)
        self.substeps = max(model.substeps, self.spring_substeps)
        self.isotropic = isotropic_rows(model.inertia)   # free rotation is exact for these
        self.rotation_rows = RowSplit(self.isotropic)
        self._idata = integration_data(model, self.isotropic)
        self._work = integration_work(model.n)
        if model.accuracy is not None:
            # error control keeps a stiff spring stable by itself: no spring substeps
            self.substeps = model.substeps
            self._code = ADAPTIVE
            self._adaptive = adaptive_data(model.accuracy, model.n, self._adaptive_stats)
        else:
            self._code = INTEGRATOR_CODES[model.integrator]
            self._adaptive = _NO_ADAPTIVE
        self._effects = [name for name, on in zip(EFFECT_NAMES, self._idata[0]) if on]
        # Effects whose forces can turn a body; with none of these, no held
        # torque and no spin, the rotational update is skipped (integration.py)
        self._flags = np.array([0, 0, int(can_make_torque(model))], np.int64)
        self._held = (None, None)     # the has_user_force / has_user_torque the flags hold
        self.contact_system = None
        if "contacts" in model.effects:
            from .collision import ContactSystem
            from .contact_params import ContactParams
            self.contact_system = ContactSystem(model, model.effects["contacts"] or ContactParams())
        self.refresh_awake()

    # ---- the pipeline -------------------------------------------------
    @property
    def stage_names(self):
        """Names of the stages this scene's step runs, in order (promise 3)."""
        names = ["impulses", "integrate"] + [f"force:{n}" for n in self._effects]
        if self.contact_system is not None:
            names += self.contact_system.stage_names
        return names + ["finite"]     # the checks after every stage, timed together

    def step(self, n: int = 1):
        """n fixed steps (one compiled loop); raises NonFiniteStateError if a
        stage leaves a NaN or inf, after the steps before it. The Python
        around the compiled call is kept to what each call needs (about
        0.6–0.85 µs; a resting ball's whole step is about 2.9–3.0 µs)."""
        n = int(n)
        if n <= 0:
            return self
        s = self.state
        start = perf_counter()
        if s.has_pending_impulse:
            self._apply_impulses()
            self._profile["impulses"] += perf_counter() - start
        packed = self._packed
        if packed is None or not same_arrays(packed[0], s):
            packed = self._pack()
        held = self._held
        if s.has_user_force is not held[0] or s.has_user_torque is not held[1]:
            # written only when they change: two numpy item writes were
            # about 0.14 µs of every call
            self._held = held = (s.has_user_force, s.has_user_torque)
            self._flags[0], self._flags[1] = held
        if self._code == ADAPTIVE:
            clear_call(self._adaptive[2])
        done, failed = packed[2](packed[1], n, packed[3], packed[4], packed[5])
        s.step_index += done
        s.time = s.step_index * packed[4]
        self._contacts = None           # read from the event log when asked for
        self._last_seconds = elapsed = perf_counter() - start
        self._step_seconds += elapsed
        self._last = done or 1
        if failed >= 0:
            self._raise_failed(failed)
        return self

    def _raise_failed(self, failed):
        """NonFiniteStateError naming the stage run_steps reported (`failed`)."""
        self._raise_non_finite("integrate" if failed == FAILED_INTEGRATE else STAGE_NAMES[failed])

    def _inputs(self):
        """The step loop's inputs (step_inputs.py)."""
        return self._current_inputs()[1]

    @property
    def substeps(self):
        return self._substeps

    @substeps.setter
    def substeps(self, k):
        self._substeps = int(k)
        self._packed = None           # the step call carries it (_current_inputs)

    def _current_inputs(self):
        """(state_arrays, StepInputs, the compiled run_steps for them
        (step_inputs.compiled_entry), substeps, dt, integrator code: the
        step call's arguments), packed again only when an array in them was
        replaced or the World rebuilt since the last step."""
        packed = self._packed
        if packed is not None and same_arrays(packed[0], self.state):
            return packed
        return self._pack()

    def _pack(self):
        """The step call's arguments packed anew (_current_inputs)."""
        s, cs = self.state, self.contact_system
        contacts, (warm_keys, warm_values), (ints, floats, counts), scratch = (
            cs.args() if cs is not None else _NO_CONTACTS)
        inputs = pack(self._idata, (s.pos, s.quat, s.vel, s.omega, s.awake),
                      (s.user_force, s.user_force_offset, s.user_torque, self._flags),
                      (self._inv_mass, self.inertia, self.inv_inertia), self._work, contacts,
                      warm_keys, warm_values, ints, floats, counts, scratch, self._adaptive,
                      self._cycles)
        entry = compiled_entry(run_steps, (inputs, 1, 1, 1.0, self._code))
        self._packed = (state_arrays(s), inputs, entry, self._substeps, float(self.model.dt),
                        self._code)
        return self._packed

    def _seconds(self, cycles, steps=1):
        """{stage: seconds} from step_loop's prof slots (divided by `steps`)."""
        k = seconds_per_cycle() / steps
        out = {"integrate": float(cycles[INTEGRATE] * k), "finite": float(cycles[FINITE] * k)}
        for e, name in enumerate(EFFECT_NAMES):
            if name in self._effects:
                out["force:" + name] = float(cycles[FORCES + e] * k)
        if self.contact_system is not None:
            for i in self.contact_system.stage_index:
                out[STAGE_NAMES[i]] = float(cycles[i] * k)
        return out

    @property
    def contacts(self) -> ContactEvents:
        """Contact events of the last step (ContactEvents, one row per event)."""
        if self._contacts is None:
            self._contacts = (self.contact_system.events() if self.contact_system is not None
                              else ContactEvents.empty())
        return self._contacts

    @contacts.setter
    def contacts(self, events):
        self._contacts = events

    @property
    def last_step_seconds(self):
        """Wall seconds per step of the last world.step(n) call (its mean)."""
        return self._last_seconds / self._last if self._last else 0.0

    @property
    def last_step_profile(self):
        """Seconds per stage of one step of the last world.step(n) call (its mean)."""
        if self._last is None:
            return {}
        c = self._cycles
        half = len(c) // 2
        return self._seconds(c[:half] - c[half:], self._last)

    @property
    def integration_stats(self):
        """`integrator: adaptive` only ({} otherwise), cumulative since the World
        was made: internal_steps, rejected_steps, force_evaluations,
        steps_at_min_step (accepted above tolerance), smallest_step_s,
        largest_step_s, max_local_error (the largest scaled error norm of an
        accepted step; ≤ 1 is within the tolerance, adaptive_kernels.py)."""
        return read_stats(self._adaptive_stats) if self.model.accuracy is not None else {}

    @property
    def last_step_integration_stats(self):
        """integration_stats of the last world.step(n) call, the counts per step
        (its mean) and the step sizes and error over the call."""
        if self.model.accuracy is None or self._last is None:
            return {}
        out = read_stats(self._adaptive_stats, call=True)
        steps = self._last
        for name in ("internal_steps", "rejected_steps", "force_evaluations", "steps_at_min_step"):
            out[name] = out[name] / steps
        return out

    @property
    def profile(self):
        """Seconds spent per stage since the World was made (cumulative)."""
        out = self._seconds(self._cycles)
        out.update(self._profile)
        out["step"] = self._step_seconds
        return out

    def _raise_non_finite(self, stage):
        s = self.state
        bad = non_finite_bodies(s.pos, s.quat, s.vel, s.omega)
        names = [self.model.names[i] for i in bad]
        raise NonFiniteStateError(
            f"step {s.step_index + 1}, stage {stage!r}: non-finite or out-of-range state "
            f"(NaN, inf or beyond {STATE_LIMIT:g}) for bodies "
            f"{names[:10]}" + (f" (+{len(names) - 10} more)" if len(names) > 10 else ""),
            stage=stage, bodies=bad)

    def forces(self, pos, quat, vel, omega):
        """Net force and torque (world frame) on every body at a trial state."""
        s = self.state
        F, T = np.zeros_like(pos), np.zeros_like(pos)
        forces(self._idata, *(np.ascontiguousarray(a, dtype=float) for a in (pos, quat, vel, omega)),
               s.user_force, s.user_force_offset, s.user_torque, s.has_user_force,
               s.has_user_torque, F, T, integration_profile())
        return F, T

    # ---- awake set ------------------------------------------------------
    def refresh_awake(self):
        """Recompute the effective inverse mass and inertia after bodies sleep or wake.

        A sleeping body has zero inverse mass for the integrator, so forces do
        not move it and it costs nothing but array rows. The compiled step
        updates these arrays in place when bodies sleep or wake."""
        m = self.model
        awake = self.state.awake
        self._packed = None           # the masses below are new arrays
        self._inv_mass = np.ascontiguousarray(m.inv_mass * awake)
        self.inv_mass = self._inv_mass[:, None]
        self.inv_inertia = np.ascontiguousarray(m.inv_inertia * awake[:, None])
        self.inertia = np.ascontiguousarray(m.inertia)

    def wake(self, i):
        if not self.state.awake[i]:
            self.state.awake[i] = True
            self.refresh_awake()

    def reset(self):
        """Back to the scene's own bodies and initial state at time 0 (commands cleared)."""
        # The state first: _build sizes its arrays by the state's bodies.
        self.state = State.from_initial(self.scene_model.initial)
        if self.model is not self.scene_model:
            self._build(self.scene_model)
        self.contacts = ContactEvents.empty()
        if self.contact_system is not None:
            self.contact_system.reset()
        restart(self._adaptive_stats)     # the step-size controller starts again
        self.refresh_awake()

    def isolate(self, indices):
        """Freeze bodies `indices` where they are (static from now on, velocities
        and loads cleared) until reset(); the other bodies keep their states and
        contacts. Used after a NonFiniteStateError, on a state restored to
        before the failed step (isolation.py). Returns the names frozen."""
        idx = sorted({int(i) for i in indices if not self.model.is_static[int(i)]})
        if not idx:
            return []
        freeze_rows(self.state, idx)
        self._bodies_changed(frozen_model(self.model, idx), np.arange(self.model.n))
        return [self.model.names[i] for i in idx]

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


_NO_CONTACTS = no_contacts()
_NO_ADAPTIVE = unused_adaptive()
