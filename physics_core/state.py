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
