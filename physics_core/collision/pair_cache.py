"""The broad phase's pair list, kept between steps (a Verlet list; Box2D's fat AABBs).

Finding candidate pairs from scratch (broadphase.candidate_pairs: a grid,
sorts, block expansion) costs a few hundred microseconds of numpy calls
even for 100 bodies, every substep, though bodies at rest or moving slowly
keep the same neighbours for many steps. The cache instead builds the list
with the detection margin grown by a `skin`, and from then on only tests
the kept pairs with the exact tests of the broad phase at the real margin.

Why that is exact: say every body has moved its centre by at most δ and,
for a box, turned by at most θ since the build. A box's AABB half extent
along an axis and its support along a plane normal are support functions
of a set within its bounding radius R of the centre, so they change by at
most R θ (a sphere's do not change). A pair that passes a test now (AABB
overlap, bounding spheres, height above a plane, each with the margin m)
therefore passed it at the build with the margin m + (δ_a + R_a θ_a) +
(δ_b + R_b θ_b); with δ + R θ ≤ skin / 2 for every body, the build at
m + skin kept it. The list is rebuilt as soon as some body may have moved
further (REBUILD_AT × skin, under the exact bound ½ to leave room for
round-off), or when the margin asked for changes.

The kept pairs are tested with the very arrays and float operations that
candidate_pairs uses (broadphase.solid_columns, plane_clearance, the same
comparisons), and filtering keeps the sorted order, so `pairs` returns the
same arrays, to the last bit, as candidate_pairs at the current poses.
"""
import numpy as np

try:        # the C entry point of np.einsum, without the Python dispatch layer
    from numpy._core.multiarray import c_einsum as _einsum
except ImportError:     # pragma: no cover - other numpy layouts
    _einsum = np.einsum

from ..shapes import BOX, PLANE, SPHERE
from .broadphase import ModelRows, plane_clearance, solid_columns, solid_pairs, sorted_pairs

SKIN = 0.25         # the list's extra margin, × the median bounding radius of the dynamic bodies
REBUILD_AT = 0.45   # rebuild once some body may have moved this × skin (exact bound: 0.5)


class PairCache:
    def __init__(self, model):
        self.rows = ModelRows(model)
        r = self.rows.radius[self.rows.plane_bodies]
        self.skin = SKIN * float(np.median(r)) if len(r) else 0.0
        # a body's points move by up to R θ when it turns θ; only a box's
        # broad-phase shape (AABB, support) depends on its orientation
        self.turners = np.flatnonzero(model.shape_type == BOX)
        self.turn_reach = self.rows.radius[self.turners]
        self.margin = None
        self.builds = 0
        self.memo = None     # narrowphase.PairMemo of the list last handed out
        self.plane_sphere = False   # every kept pair is a plane under a sphere

    def pairs(self, model, pos, quat, margin):
        """(a, b): candidate_pairs(model, pos, quat, margin), from the kept list."""
        if margin != self.margin or not self._still_valid(pos, quat):
            self._build(model, pos, quat, margin)
        keep = np.empty(len(self.a), bool)
        if len(self.solid_at):
            keep[self.solid_at] = overlap_mask(*solid_columns(model, pos, quat, margin, self.rows),
                                               self.si, self.sj)
        if len(self.plane_at):
            gap = plane_clearance(model, pos, quat, rows=self.rows)[2]
            keep[self.plane_at] = gap[self.prow, self.pcol] < margin
        if keep.all():
            return self.a, self.b
        return self.a[keep], self.b[keep]

    def _still_valid(self, pos, quat):
        """Has every body moved (and, for boxes, turned) less than the list allows?"""
        d = pos - self.pos0
        limit = REBUILD_AT * self.skin
        if not len(self.turners):
            # no turn term: compare squared lengths (NaN compares False: rebuild)
            return bool(_einsum("ij,ij->i", d, d).max(initial=0.0) <= limit * limit)
        move = np.sqrt(_einsum("ij,ij->i", d, d))
        if len(self.turners):
            t = self.turners
            dq = quat[t] - self.quat0[t]
            # |q − q0| = 2 sin(θ/4) for unit quaternions of the same sign; a flipped
            # sign reads as a large turn, which only rebuilds sooner
            chord = np.sqrt(_einsum("ij,ij->i", dq, dq))
            move[t] += self.turn_reach * 4.0 * np.arcsin(np.minimum(0.5 * chord, 1.0))
        # NaN (a body gone non-finite) compares False: rebuild, as from scratch
        return bool(move.max(initial=0.0) <= limit)

    def _build(self, model, pos, quat, margin):
        fat = margin + self.skin
        rows = self.rows
        a, b, i, j = solid_pairs(model, pos, quat, fat, rows, local=True)
        planes, bodies, gap = plane_clearance(model, pos, quat, rows=rows)
        if gap is None:
            prow = pcol = np.zeros(0, np.int64)
        else:       # plane_pairs' order
            prow, pcol = np.nonzero(gap < fat)
            order = np.lexsort((bodies[prow], planes[pcol]))
            prow, pcol = prow[order], pcol[order]
        self.a, self.b, order = sorted_pairs(model, a, b, planes[pcol], bodies[prow])
        ns = len(a)
        self.solid_at = np.flatnonzero(order < ns)          # where each kind sits in the list
        self.si, self.sj = i[order[self.solid_at]], j[order[self.solid_at]]
        self.plane_at = np.flatnonzero(order >= ns)
        self.prow, self.pcol = prow[order[self.plane_at] - ns], pcol[order[self.plane_at] - ns]
        self.pos0 = np.array(pos, dtype=float)
        self.quat0 = np.array(quat, dtype=float)
        self.margin = margin
        self.builds += 1
        st = model.shape_type
        self.plane_sphere = bool(len(self.a) and (st[self.a] == PLANE).all()
                                 and (st[self.b] == SPHERE).all())
        self.memo = None


def overlap_mask(lo, hi, centre, reach, p, q):
    """(k,) bool: do the pairs (p, q) pass broadphase._filter's two tests
    (bounding spheres, then boxes)? The same operations in the same order,
    so the same answer to the last bit."""
    d2 = np.zeros(len(p))
    for k in range(3):
        c = centre[:, k]
        d = c.take(p)
        d -= c.take(q)
        d *= d
        d2 += d
    r = reach.take(p)
    r += reach.take(q)
    r *= r
    keep = d2 <= r
    for k in range(3):
        lk, hk = lo[:, k], hi[:, k]
        keep &= lk.take(p) <= hk.take(q)
        keep &= lk.take(q) <= hk.take(p)
    return keep
