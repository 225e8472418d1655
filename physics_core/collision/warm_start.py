"""Warm starting: a contact starts each substep with last substep's impulses.

Matched by Manifold key (pair and feature). The normal impulse is reused as
is; the friction impulse is kept as a world vector and projected on the new
tangent basis, so it survives a change of basis. The contact's slip speed
after the solve is kept too: it decides static or kinetic friction next
substep (friction.py). The restitution pass's
extra push is not kept: it belongs to one impact, not to the resting load.
"""
import numpy as np


class WarmCache:
    def __init__(self):
        self.key = np.zeros(0, dtype=np.int64)   # sorted
        self.normal = np.zeros(0)
        self.friction = np.zeros((0, 3))
        self.slip = np.zeros(0)

    def store(self, rows, slip):
        """Keep this substep's impulses and each contact's final slip speed (m/s)."""
        order = np.argsort(rows.key, kind="stable")
        self.slip = slip[order]
        lam = rows.lam[order]
        tan = rows.tangent[order]
        self.key = rows.key[order]
        self.normal = lam[:, 0].copy()
        self.friction = lam[:, 1:2] * tan[:, 0] + lam[:, 2:3] * tan[:, 1]

    def clear(self):
        self.__init__()

    def load(self, rows, fraction):
        """Set rows.lam from the cache (× fraction) for keys seen last substep.
        Returns each row's slip speed at the end of last substep (NaN: new contact)."""
        slip = np.full(len(rows), np.nan)
        if not len(self.key) or not len(rows):
            return slip
        i = np.minimum(np.searchsorted(self.key, rows.key), len(self.key) - 1)
        hit = np.flatnonzero(self.key[i] == rows.key)
        if not len(hit):
            return slip
        j = i[hit]
        slip[hit] = self.slip[j]
        if fraction <= 0.0:
            return slip
        f = self.friction[j]
        rows.lam[hit, 0] = fraction * self.normal[j]
        rows.lam[hit, 1] = fraction * np.einsum("ij,ij->i", f, rows.tangent[hit, 0])
        rows.lam[hit, 2] = fraction * np.einsum("ij,ij->i", f, rows.tangent[hit, 1])
        return slip
