"""The mutable state: positions, orientations, velocities and pending loads.

One row per body (structure of arrays). Angular velocity is world frame;
the integrators work internally with angular momentum L = I_w ω so that a
torque-free body keeps L exactly (COURSE.md 3).
"""
from dataclasses import dataclass, field

import numpy as np


@dataclass
class State:
    pos: np.ndarray
    quat: np.ndarray
    vel: np.ndarray
    omega: np.ndarray
    user_force: np.ndarray          # N, world frame, held
    user_force_offset: np.ndarray   # m, body frame: where the held force acts
    user_torque: np.ndarray         # N·m, world frame, held
    impulse: np.ndarray             # N·s, pending, applied once at the next step
    angular_impulse: np.ndarray     # N·m·s, pending
    awake: np.ndarray               # bool; sleeping bodies are frozen until woken
    time: float = 0.0
    step_index: int = 0
    has_pending_impulse: bool = False
    has_user_force: bool = False
    has_user_torque: bool = False
    scratch: dict = field(default_factory=dict)   # per-stage caches (contact warm starts, ...)

    ROW_FIELDS = ("pos", "quat", "vel", "omega", "user_force", "user_force_offset", "user_torque",
                  "impulse", "angular_impulse", "awake")

    def append_body(self, pos, quat, vel, omega):
        """A new body as the last row (awake, no loads). The arrays are views of
        buffers whose capacity doubles when full, so adding k bodies one at a
        time copies O(k) rows in all, not O(k²)."""
        n = len(self.pos)
        for name in self.ROW_FIELDS:
            buf = self._buffer(name)
            if len(buf) <= n:
                grown = np.zeros((max(2 * len(buf), 4),) + buf.shape[1:], buf.dtype)
                grown[:n] = buf[:n]
                buf = self._buffers[name] = grown
            buf[n] = 0
            setattr(self, name, buf[:n + 1])
        self.pos[n], self.quat[n], self.vel[n], self.omega[n] = pos, quat, vel, omega
        self.awake[n] = True

    def remove_body(self, i):
        """Drop row i; the rows after it move one place down."""
        n = len(self.pos)
        for name in self.ROW_FIELDS:
            buf = self._buffer(name)
            buf[i:n - 1] = buf[i + 1:n]
            setattr(self, name, buf[:n - 1])

    def _buffer(self, name):
        """The buffer behind field `name`; a field an integrator replaced by a
        new array becomes its own buffer (full: the next append grows it)."""
        buffers = self.__dict__.setdefault("_buffers", {})
        cur = getattr(self, name)
        buf = buffers.get(name)
        if buf is None or not (cur is buf or cur.base is buf):
            buf = buffers[name] = cur
        return buf

    @classmethod
    def from_initial(cls, initial) -> "State":
        n = len(initial["pos"])
        z = lambda: np.zeros((n, 3))
        return cls(
            pos=np.array(initial["pos"], dtype=float),
            quat=np.array(initial["quat"], dtype=float),
            vel=np.array(initial["vel"], dtype=float),
            omega=np.array(initial["omega"], dtype=float),
            user_force=z(), user_force_offset=z(), user_torque=z(),
            impulse=z(), angular_impulse=z(),
            awake=np.ones(n, dtype=bool),
        )
