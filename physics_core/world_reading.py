"""Reading a World: named bodies, time, energy and momenta (COURSE.md 6)."""
import numpy as np

from . import quaternion as qt
from .body_view import BodyView
from .effects import potential_energy
from .vec3 import cross


class ReadingMixin:
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
