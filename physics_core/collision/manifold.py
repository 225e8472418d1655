"""Contact manifolds: one row per contact point, as a structure of arrays.

What collision detection hands to the contact solver (COURSE.md 5: the
contact point, the normal that separates the bodies, and how deep they are).

Conventions every producer keeps:
- `normal` is a unit vector pointing from body `a` towards body `b`: moving
  `b` along +normal (or `a` along -normal) separates the pair.
- `a < b` when both bodies are dynamic; when one is static (every plane is)
  the static body is `a`. Static–static pairs never appear.
- `point` lies midway between the two surfaces along the normal.
- `depth > 0` is penetration; `depth <= 0` is a gap (a speculative contact,
  reported while the gap is smaller than the detection margin).
- `key = pair_id * SLOTS + slot` with `pair_id = min(a, b) * n + max(a, b)`;
  the slot names the contact feature (a box vertex, a face quadrant, ...) so
  the same contact keeps its key from step to step (warm starting, contact
  begin/persist/end events). `detect` returns rows sorted by ascending key,
  and keys are unique.
"""
from dataclasses import dataclass, fields

import numpy as np

SLOTS = 8   # contact features per pair that a key can tell apart


@dataclass
class Manifold:
    a: np.ndarray        # (k,) int64 body index
    b: np.ndarray        # (k,) int64 body index
    point: np.ndarray    # (k, 3) world contact point, m
    normal: np.ndarray   # (k, 3) unit normal from a towards b
    depth: np.ndarray    # (k,) penetration depth, m (negative: gap)
    key: np.ndarray      # (k,) int64 feature id, stable across steps

    def __len__(self):
        return len(self.a)

    @classmethod
    def empty(cls) -> "Manifold":
        zi = np.zeros(0, dtype=np.int64)
        return cls(a=zi, b=zi.copy(), point=np.zeros((0, 3)), normal=np.zeros((0, 3)),
                   depth=np.zeros(0), key=zi.copy())

    @staticmethod
    def concat(parts) -> "Manifold":
        parts = [p for p in parts if len(p)]
        if not parts:
            return Manifold.empty()
        if len(parts) == 1:
            return parts[0]
        return Manifold(**{f.name: np.concatenate([getattr(p, f.name) for p in parts])
                           for f in fields(Manifold)})

    def take(self, index) -> "Manifold":
        """The rows `index` (an index array or a boolean mask), in that order."""
        index = np.asarray(index)
        if index.dtype == bool:
            index = np.flatnonzero(index)
        return Manifold(**{f.name: getattr(self, f.name).take(index, axis=0) for f in fields(Manifold)})

    def sorted_by_key(self) -> "Manifold":
        return self.take(np.argsort(self.key, kind="stable"))


def same(x: np.ndarray, y: np.ndarray) -> bool:
    """np.array_equal for two arrays, without its Python-level conversions
    (it runs several times per substep on small arrays). For the key and
    mask arrays it is used on (no NaN), an array equals itself."""
    return x is y or (x.shape == y.shape and bool((x == y).all()))


def pair_key(a, b, n: int, slot) -> np.ndarray:
    """Feature key of contact `slot` between bodies a and b of an n-body scene."""
    a = np.asarray(a, dtype=np.int64)
    b = np.asarray(b, dtype=np.int64)
    return (np.minimum(a, b) * n + np.maximum(a, b)) * SLOTS + np.asarray(slot, dtype=np.int64)


def detect(model, pos, quat, margin: float = 0.0, pairs=None) -> Manifold:
    """Every contact with depth > -margin between the bodies of `model` at poses
    (pos (n, 3), quat (n, 4) w, x, y, z body→world); static–static pairs skipped.

    The compiled broad and narrow phase (detection.py); rows sorted by key,
    so the result is deterministic. `pairs` is accepted and ignored."""
    from .detection import Detector
    return Detector(model).detect(np.asarray(pos, dtype=float), np.asarray(quat, dtype=float),
                                  float(margin))
