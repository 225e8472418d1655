"""Warm starting: a contact starts each substep with last substep's impulses.

Matched by Manifold key (pair and feature). The normal impulse is reused as
is; the friction impulse is kept as a world vector and projected on the new
tangent basis, so it survives a change of basis. The contact's slip speed
after the solve is kept too: it decides static or kinetic friction next
substep (friction.py). The restitution pass's
extra push is not kept: it belongs to one impact, not to the resting load.
"""
import numpy as np

try:        # the C entry point of np.einsum, without the Python dispatch layer
    from numpy._core.multiarray import c_einsum as _einsum
except ImportError:     # pragma: no cover - other numpy layouts
    _einsum = np.einsum

from .manifold import same


class WarmCache:
    """Kept in the order of the rows they came from: from one substep to the
    next the contacts are usually the same, in the same order, and then the
    impulses are read back with no search at all."""

    def __init__(self):
        self.key = np.zeros(0, dtype=np.int64)   # in row order
        self.normal = np.zeros(0)
        self.friction = np.zeros((0, 3))
        self.slip = np.zeros(0)
        self._sorted = None                      # (order, keys in ascending order), on demand

    def store(self, rows, slip):
        """Keep this substep's impulses and each contact's final slip speed (m/s)."""
        lam = rows.lam
        tan = rows.tangent
        self.slip = slip
        self.key = rows.key
        self.normal = lam[:, 0].copy()
        self.friction = lam[:, 1:2] * tan[:, 0] + lam[:, 2:3] * tan[:, 1]
        self._sorted = None

    def clear(self):
        self.__init__()

    def load(self, rows, fraction):
        """Set rows.lam from the cache (× fraction) for keys seen last substep.
        Returns each row's slip speed at the end of last substep (NaN: new contact)."""
        if len(rows) and same(self.key, rows.key):
            slip = self.slip        # only read; store() replaces it
            if fraction > 0.0:
                self._apply(rows, slice(None), slice(None), fraction)
            return slip
        slip = np.full(len(rows), np.nan)
        if not len(self.key) or not len(rows):
            return slip
        if self._sorted is None:
            order = np.argsort(self.key, kind="stable")
            self._sorted = order, self.key[order]
        order, keys = self._sorted
        i = np.minimum(np.searchsorted(keys, rows.key), len(keys) - 1)
        hit = np.flatnonzero(keys[i] == rows.key)
        if not len(hit):
            return slip
        j = order[i[hit]]
        slip[hit] = self.slip[j]
        if fraction > 0.0:
            self._apply(rows, hit, j, fraction)
        return slip

    def _apply(self, rows, hit, j, fraction):
        f = self.friction[j]
        tan = rows.tangent[hit]
        lam = rows.lam
        lam[hit, 0] = self.normal[j]
        lam[hit, 1] = _einsum("ij,ij->i", f, tan[:, 0])
        lam[hit, 2] = _einsum("ij,ij->i", f, tan[:, 1])
        if fraction != 1.0:
            lam[hit] *= fraction
