"""The World's commands (INTERFACE.md Python API): held forces and torques,
one-shot impulses. Every argument is checked before the state is touched,
so a refused command (CommandError) leaves no trace, not even its valid half.
"""
import numpy as np

from . import quaternion as qt
from .command_limits import (MAX_ANGULAR_IMPULSE, MAX_FORCE, MAX_IMPULSE, MAX_POINT_DISTANCE,
                             MAX_TORQUE, magnitude)
from . import shapes
from .errors import CommandError
from .vec3 import cross


class CommandsMixin:
    def _body_index(self, name) -> int:
        i = self.model.index.get(name)
        if i is None:
            raise CommandError(f"unknown body {name!r}; bodies are: {', '.join(self.model.names)}")
        if self.model.is_static[i]:
            raise CommandError(f"body {name!r} is static: forces and impulses do not move it")
        return i

    @staticmethod
    def _vec(value, what, limit=None, unit="") -> np.ndarray:
        try:
            v = np.array(value, dtype=float).reshape(3)
        except (TypeError, ValueError, OverflowError):
            raise CommandError(f"{what}: expected 3 numbers, got {str(value)[:80]!r}") from None
        if not np.all(np.isfinite(v)):
            raise CommandError(f"{what}: expected finite numbers, got {v.tolist()}")
        if limit is not None and not magnitude(v) <= limit:
            raise CommandError(f"{what}: magnitude {magnitude(v):.3g} {unit} is beyond the limit "
                               f"{limit:g} {unit} (physics_core.command_limits)")
        return v

    def _point(self, i, point, what):
        p = self._vec(point, what)
        if not magnitude(p - self.state.pos[i]) <= MAX_POINT_DISTANCE:
            raise CommandError(f"{what}: {magnitude(p - self.state.pos[i]):.3g} m from the body, beyond "
                               f"the limit {MAX_POINT_DISTANCE:g} m (physics_core.command_limits)")
        return p

    def apply_force(self, name, force, point=None):
        """Hold a force (N, world frame) on a body until replaced; zero clears it.

        With a world `point`, the force acts there: the point is fixed to the
        body (stored in body axes) so τ = r × F follows the body as it turns."""
        i = self._body_index(name)
        f = self._vec(force, f"force on {name!r}", MAX_FORCE, "N")
        # Validate every argument before touching the state: a refused command
        # must leave no trace (not even its valid half).
        p = None if point is None else self._point(i, point, f"point of force on {name!r}")
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
        self.state.user_torque[i] = self._vec(torque, f"torque on {name!r}", MAX_TORQUE, "N·m")
        self.state.has_user_torque = True
        self.wake(i)

    def apply_impulse(self, name, impulse, point=None):
        """A linear impulse (N·s, world frame), applied once at the next step.

        At a world `point`, it also adds the angular impulse r × J."""
        i = self._body_index(name)
        j = self._vec(impulse, f"impulse on {name!r}", MAX_IMPULSE, "N·s")
        p = None if point is None else self._point(i, point, f"point of impulse on {name!r}")
        s = self.state
        s.impulse[i] += j
        if p is not None:
            s.angular_impulse[i] += cross(p - s.pos[i], j)
        s.has_pending_impulse = True
        self.wake(i)

    def apply_angular_impulse(self, name, angular_impulse):
        """An angular impulse (N·m·s, world frame), applied once at the next step."""
        i = self._body_index(name)
        self.state.angular_impulse[i] += self._vec(angular_impulse, f"angular impulse on {name!r}",
                                                   MAX_ANGULAR_IMPULSE, "N·m·s")
        self.state.has_pending_impulse = True
        self.wake(i)

    def clear_loads(self):
        """Let go of every held force and torque and drop pending impulses."""
        s = self.state
        for a in (s.user_force, s.user_force_offset, s.user_torque, s.impulse, s.angular_impulse):
            a[:] = 0.0
        s.has_user_force = s.has_user_torque = s.has_pending_impulse = False

    def _apply_impulses(self):
        """Δv = J/m, ΔL = r × J + angular impulse (COURSE.md 3, angular impulse)."""
        s = self.state
        s.vel += s.impulse * self.inv_mass
        L = (s.angular_impulse if not s.omega.any() else
             qt.rotate(s.quat, self.inertia * qt.rotate_inverse(s.quat, s.omega)) + s.angular_impulse)
        s.omega[:] = qt.rotate(s.quat, self.inv_inertia * qt.rotate_inverse(s.quat, L))
        s.impulse[:] = 0.0
        s.angular_impulse[:] = 0.0
        s.has_pending_impulse = False

    def set_body_state(self, name, position=None, orientation=None, velocity=None, angular_velocity=None):
        """Teleport a body between steps: any of its position (m), orientation
        (unit quaternion w, x, y, z, body → world), velocity (m/s) and angular
        velocity (rad/s, world frame); None keeps that part. A static body
        takes a new pose but no motion (a plane keeps its pose: its normal and
        offset). Held loads stay; the body is woken. Everything is checked
        before anything is written (CommandError)."""
        i = self.model.index.get(name)
        if i is None:
            raise CommandError(f"unknown body {name!r}; bodies are: {', '.join(self.model.names)}")
        new = self._checked_body_state(i, name, position, orientation, velocity, angular_velocity)
        s = self.state
        for key, value in new.items():
            getattr(s, key)[i] = value
        if not self.model.is_static[i]:
            self.wake(i)

    def _checked_body_state(self, i, name, position, orientation, velocity, angular_velocity):
        new = {}
        for key, value in (("pos", position), ("vel", velocity), ("omega", angular_velocity)):
            if value is not None:
                new[key] = self._vec(value, f"{key} of {name!r}")
        if orientation is not None:
            new["quat"] = _unit_quaternion(orientation, name)
        if not self.model.is_static[i]:
            return new
        if np.any(new.get("vel", 0.0)) or np.any(new.get("omega", 0.0)):
            raise CommandError(f"body {name!r} is static: it takes a pose but no velocity")
        if self.model.shape_type[i] == shapes.PLANE and ("pos" in new or "quat" in new):
            raise CommandError(f"body {name!r} is a plane: its normal and offset are its pose and are fixed")
        return new


# |q| may differ from 1 by this much and is then normalised (float32 senders)
UNIT_QUATERNION_TOLERANCE = 1e-6


def _unit_quaternion(value, name):
    try:
        q = np.array(value, dtype=float).reshape(4)
    except (TypeError, ValueError):
        raise CommandError(f"orientation of {name!r}: expected 4 numbers (w, x, y, z), got {value!r}") from None
    norm = float(np.sqrt(q @ q)) if np.all(np.isfinite(q)) else float("nan")
    if not abs(norm - 1.0) <= UNIT_QUATERNION_TOLERANCE:
        raise CommandError(f"orientation of {name!r}: expected a unit quaternion, got {q.tolist()} (|q| = {norm:.9g})")
    return q if norm == 1.0 else q / norm
