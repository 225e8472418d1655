"""Contact events of one step, as a structure of arrays (one row per event)."""
from dataclasses import dataclass, fields

import numpy as np

BEGIN, PERSIST, END = 0, 1, 2


@dataclass(frozen=True)
class ContactEvents:
    point: np.ndarray             # (k, 3) world contact point, m
    normal: np.ndarray            # (k, 3) unit normal, pointing from body_a towards body_b
    impulse: np.ndarray           # (k,) normal impulse over the step, N·s
    friction_impulse: np.ndarray  # (k,) magnitude of the tangential impulse, N·s
    normal_speed: np.ndarray      # (k,) approach speed before the solve, m/s (> 0 closing)
    depth: np.ndarray             # (k,) penetration depth, m
    body_a: np.ndarray            # (k,) scene index
    body_b: np.ndarray            # (k,) scene index
    event: np.ndarray             # (k,) uint8: 0 begin, 1 persist, 2 end

    def __len__(self):
        return len(self.body_a)

    @classmethod
    def empty(cls) -> "ContactEvents":
        z3 = np.zeros((0, 3))
        z = np.zeros(0)
        zi = np.zeros(0, dtype=np.int64)
        return cls(point=z3, normal=z3, impulse=z, friction_impulse=z, normal_speed=z,
                   depth=z, body_a=zi, body_b=zi, event=np.zeros(0, dtype=np.uint8))

    def as_dict(self):
        return {f.name: getattr(self, f.name) for f in fields(self)}
