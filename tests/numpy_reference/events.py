"""Contact events of a step (contact_events.ContactEvents), gathered over its substeps.

A contact is identified by its Manifold key (pair and feature). It is
"touching" in a substep when the pair overlaps at the detected pose or the
solver pushed on it (λ_n > 0, which includes a speculative contact about to
close). Over one step: `begin` if it touches now and did not in the previous
step, `persist` if it did, `end` (zero impulse, last known point) if it
touched in the previous step and not in this one. A contact whose bodies
have all gone to sleep (or are static) is frozen, not ended: it is not
reported while they sleep and continues as `persist` when they wake. Impulses are summed over
the substeps; the friction impulse is the length of the summed tangential
impulse vector; point, normal and depth are the last substep's; the normal
speed is the largest approach speed seen (before the solve, > 0 closing).
"""
import numpy as np

from physics_core.contact_events import BEGIN, END, PERSIST, ContactEvents
from physics_core.collision.manifold import same
from numpy import einsum as _einsum


class EventAccumulator:
    def __init__(self):
        self.parts = []
        self.prev = None        # last step's touching contacts, sorted by key

    def reset(self):
        self.parts = []

    def add(self, rows, friction=None):
        """Record the touching contacts of one substep (after its solve).
        `friction`: the rows' tangential impulses as world vectors
        (λ_t1 t1 + λ_t2 t2), when already computed (warm_start.WarmCache.store)."""
        if not len(rows):
            return
        lam = rows.lam
        key = rows.key
        # every row pushing (the usual resting case) already makes all of them touch
        touching = None if (lam[:, 0] > 0.0).all() else (rows.depth >= 0.0) | (lam[:, 0] > 0.0)
        if ((touching is None or touching.all())
                and (rows.key_sorted or np.all(key[1:] > key[:-1]))):
            # every contact touches and they are in key order already (a resting
            # scene, one colour): the rows' own arrays, no gathers (nothing writes
            # to a row's arrays once they are built)
            if friction is None:
                tan = rows.tangent
                friction = lam[:, 1:2] * tan[:, 0] + lam[:, 2:3] * tan[:, 1]
            ft = friction
            self.parts.append(dict(key=key, a=rows.a, b=rows.b, point=rows.point, normal=rows.normal,
                                   depth=rows.depth, impulse=lam[:, 0], friction=ft,
                                   speed=-rows.u0[:, 0]))
            return
        if touching is None:
            touching = np.ones(len(key), bool)
        if not touching.any():
            return
        t = np.flatnonzero(touching)
        t = t[np.argsort(key[t], kind="stable")]
        if friction is not None:
            ft = friction[t]
        else:
            ft = lam[t, 1:2] * rows.tangent[t, 0] + lam[t, 2:3] * rows.tangent[t, 1]
        self.parts.append(dict(
            key=key[t], a=rows.a[t], b=rows.b[t], point=rows.point[t], normal=rows.normal[t],
            depth=rows.depth[t], impulse=lam[t, 0], friction=ft,
            speed=-rows.u0[t, 0]))

    def finish(self, moving, awake=None) -> ContactEvents:
        """The step's events; also remembers them for the next step's begin/end.
        `moving` (n,) marks awake dynamic bodies; or, with `awake`, a function
        of it giving them (called only when some contact began or ended)."""
        cur = self._merge()
        prev = self.prev
        if cur is None and prev is None:
            self.parts = []
            return ContactEvents.empty()
        if cur is not None and prev is not None and same(cur["key"], prev["key"]):
            # the same contacts as last step: all persist, none ended or froze
            self.prev = cur
            self.parts = []
            return ContactEvents(**_columns(cur, np.full(len(cur["key"]), PERSIST, dtype=np.uint8)))
        if awake is not None:
            moving = moving(awake)
        cols = {}
        if cur is not None:
            known = _member(cur["key"], prev["key"]) if prev is not None else np.zeros(len(cur["key"]), bool)
            cols = _columns(cur, np.where(known, PERSIST, BEGIN).astype(np.uint8))
        frozen = None
        if prev is not None:
            gone = ~_member(prev["key"], cur["key"]) if cur is not None else np.ones(len(prev["key"]), bool)
            asleep = gone & ~moving[prev["a"]] & ~moving[prev["b"]]
            if cur is None and asleep.all():
                # a scene asleep: the frozen contacts stay as they are, nothing to report
                self.parts = []
                return ContactEvents.empty()
            if asleep.any():
                frozen = {k: v[asleep] for k, v in prev.items()}
                gone &= ~asleep
            if gone.any():
                g = np.flatnonzero(gone)
                z = np.zeros(len(g))
                end = dict(point=prev["point"][g], normal=prev["normal"][g], impulse=z,
                           friction_impulse=z, normal_speed=z, depth=prev["depth"][g],
                           body_a=prev["a"][g], body_b=prev["b"][g],
                           event=np.full(len(g), END, dtype=np.uint8))
                cols = end if not cols else {k: np.concatenate([cols[k], end[k]]) for k in cols}
        self.prev = _union(cur, frozen)
        self.parts = []
        if not cols:
            return ContactEvents.empty()
        return ContactEvents(**cols)

    def _merge(self):
        if not self.parts:
            return None
        if len(self.parts) == 1:
            return self.parts[0]
        cat = {k: np.concatenate([p[k] for p in self.parts]) for k in self.parts[0]}
        keys, inv = np.unique(cat["key"], return_inverse=True)
        m = len(keys)
        last = np.zeros(m, dtype=np.int64)
        np.maximum.at(last, inv, np.arange(len(inv)))   # later substeps come later
        impulse = np.bincount(inv, cat["impulse"], m)
        fr = np.stack([np.bincount(inv, cat["friction"][:, c], m) for c in range(3)], axis=1)
        speed = np.full(m, -np.inf)
        np.maximum.at(speed, inv, cat["speed"])
        return dict(key=keys, a=cat["a"][last], b=cat["b"][last], point=cat["point"][last],
                    normal=cat["normal"][last], depth=cat["depth"][last], impulse=impulse,
                    friction=fr, speed=speed)


def _columns(cur, event):
    """ContactEvents columns of this step's touching contacts."""
    return dict(point=cur["point"], normal=cur["normal"], impulse=cur["impulse"],
                friction_impulse=np.sqrt(_einsum("ij,ij->i", cur["friction"], cur["friction"])),
                normal_speed=cur["speed"], depth=cur["depth"], body_a=cur["a"],
                body_b=cur["b"], event=event)


def _union(cur, frozen):
    """Touching contacts to remember: this step's plus the sleeping ones, by key."""
    if frozen is None:
        return cur
    if cur is None:
        return frozen
    cat = {k: np.concatenate([cur[k], frozen[k]]) for k in cur}
    order = np.argsort(cat["key"], kind="stable")
    return {k: v[order] for k, v in cat.items()}


def _member(keys, sorted_ref):
    """(len(keys),) bool: which keys appear in the sorted array `sorted_ref`."""
    if sorted_ref is None or not len(sorted_ref):
        return np.zeros(len(keys), bool)
    i = np.searchsorted(sorted_ref, keys)
    i = np.minimum(i, len(sorted_ref) - 1)
    return sorted_ref[i] == keys
