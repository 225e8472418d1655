"""A named handle on one body: reads the live state, returns copies."""
import numpy as np


class BodyView:
    __slots__ = ("_world", "index", "name")

    def __init__(self, world, index: int):
        self._world = world
        self.index = index
        self.name = world.model.names[index]

    @property
    def position(self) -> np.ndarray:
        return self._world.state.pos[self.index].copy()

    @property
    def orientation(self) -> np.ndarray:
        """Unit quaternion (w, x, y, z), body → world."""
        return self._world.state.quat[self.index].copy()

    @property
    def velocity(self) -> np.ndarray:
        return self._world.state.vel[self.index].copy()

    @property
    def angular_velocity(self) -> np.ndarray:
        """World frame, rad/s."""
        return self._world.state.omega[self.index].copy()

    @property
    def mass(self) -> float:
        return float(self._world.model.mass[self.index])

    @property
    def inertia(self) -> np.ndarray:
        """Principal moments in the body frame, kg·m²."""
        return self._world.model.inertia[self.index].copy()

    @property
    def is_static(self) -> bool:
        return bool(self._world.model.is_static[self.index])

    @property
    def awake(self) -> bool:
        return bool(self._world.state.awake[self.index])

    def __repr__(self):
        return (f"BodyView({self.name!r}, position={self.position.tolist()}, "
                f"velocity={self.velocity.tolist()})")
