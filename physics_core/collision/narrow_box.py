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


# Incident-face corners, in order round the face: (+,+), (-,+), (-,-), (+,-)
QUAD_SIGNS = np.array([[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]])


def _sign(x):
    """+1 or -1, with +1 at zero (a fixed choice, never 0)."""
    return np.where(x < 0.0, -1.0, 1.0)


def box_box(model, f, s, pf, qf, ps, qs, margin=0.0):
    """Contact rows (pair row, slot, point, normal first→second, depth).

    Slots: face contacts use the quadrant of the contact point in the
    smaller face's frame (0–3 when the reference face is on `first`, 4–7 when
    on `second`); an edge–edge contact uses slot 0."""
    ha, hb = model.half_extents[f], model.half_extents[s]
    A, B, t = _frames(ha, pf, qf, hb, ps, qs)
    fa, fb, edge, L = separations(ha, A, hb, B, t)
    k = len(t)
    rows = np.arange(k)
    ia, ib = np.argmax(fa, axis=1), np.argmax(fb, axis=1)
    sa, sb = fa[rows, ia], fb[rows, ib]
    ie = np.argmax(edge.reshape(k, 9), axis=1)
    se = edge.reshape(k, 9)[rows, ie]
    tol = AXIS_TOL * np.minimum(ha.min(axis=1), hb.min(axis=1))
    use_b = sb > sa + tol
    face_sep = np.where(use_b, sb, sa)
    use_edge = se > face_sep + tol
    touching = np.maximum(np.maximum(sa, sb), se) <= margin
    parts = []

    F = np.flatnonzero(touching & ~use_edge)
    if len(F):
        ub = use_b[F]
        ref_c = np.where(ub[:, None], ps[F], pf[F])
        inc_c = np.where(ub[:, None], pf[F], ps[F])
        ref_ax = np.where(ub[:, None, None], B[F], A[F])
        inc_ax = np.where(ub[:, None, None], A[F], B[F])
        ref_h = np.where(ub[:, None], hb[F], ha[F])
        inc_h = np.where(ub[:, None], ha[F], hb[F])
        axis = np.where(ub, ib[F], ia[F])
        m = np.arange(len(F))
        n_ref = ref_ax[m, axis]
        n_ref = n_ref * _sign(np.einsum("ki,ki->k", n_ref, inc_c - ref_c))[:, None]
        row, quad, point, depth = clip_faces(ref_c, ref_ax, ref_h, axis, n_ref,
                                             inc_c, inc_ax, inc_h, margin)
        normal = np.where(ub[row, None], -n_ref[row], n_ref[row])
        parts.append((F[row], quad + 4 * ub[row], point, normal, depth))

    E = np.flatnonzero(touching & use_edge)
    if len(E):
        parts.append(_edge_contacts(E, ie[E] // 3, ie[E] % 3, L, se[E], A, ha, pf, B, hb, ps, t))

    if not parts:
        z = np.zeros(0, np.int64)
        return z, z, np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0)
    row, slot, point, normal, depth = (np.concatenate(c) for c in zip(*parts))
    return row, slot.astype(np.int64), point, normal, depth


def _edge_contacts(E, i, j, L, sep, A, ha, pa, B, hb, pb, t):
    """One point per pair, midway between the closest points of the two edges
    (the edge of a furthest along n, the edge of b furthest along -n).

    Closest points of lines p + s d1, q + u d2 (unit d): with r = p - q,
    b = d1·d2, c = d1·r, f = d2·r: s = (b f - c) / (1 - b²), u = f + s b;
    then clamped to the edges' lengths (Ericson 5.1.9). 1 - b² > EDGE_EPS²
    because parallel edges never give an edge axis."""
    m = np.arange(len(E))
    n = L[E, i, j]
    n = n * _sign(np.einsum("ki,ki->k", n, t[E]))[:, None]
    Ae, Be, hae, hbe = A[E], B[E], ha[E], hb[E]
    sa = _sign(np.einsum("kmi,ki->km", Ae, n))
    sa[m, i] = 0.0
    sb = _sign(np.einsum("kmi,ki->km", Be, n))
    sb[m, j] = 0.0
    p = pa[E] + np.einsum("km,kmi->ki", sa * hae, Ae)
    q = pb[E] - np.einsum("km,kmi->ki", sb * hbe, Be)
    d1, d2 = Ae[m, i], Be[m, j]
    lim1, lim2 = hae[m, i], hbe[m, j]
    r = p - q
    bb = np.einsum("ki,ki->k", d1, d2)
    c = np.einsum("ki,ki->k", d1, r)
    ff = np.einsum("ki,ki->k", d2, r)
    denom = np.maximum(1.0 - bb * bb, EDGE_EPS * EDGE_EPS)
    s = np.clip((bb * ff - c) / denom, -lim1, lim1)
    u = np.clip(ff + s * bb, -lim2, lim2)
    s = np.clip(u * bb - c, -lim1, lim1)
    point = 0.5 * ((p + s[:, None] * d1) + (q + u[:, None] * d2))
    return E, np.zeros(len(E), np.int64), point, n, -sep


def clip_faces(ref_c, ref_ax, ref_h, axis, n_ref, inc_c, inc_ax, inc_h, margin):
    """Face contact: the incident face of the other box clipped to the
    reference face's rectangle (Sutherland–Hodgman's result, built directly).

    The clipped polygon's corners are among: incident corners inside the
    rectangle, rectangle corners inside the incident face, and crossings of
    incident edges with the rectangle's sides (24 candidates per pair, all
    computed at once). Candidates less than `margin` above the reference face
    are reduced to at most 4: for each diagonal direction of the smaller face,
    the candidate furthest along it. Work is in the reference frame
    (u, v along the face, w along n_ref above it).
    Returns (pair row, quadrant 0–3, world point, depth)."""
    m = len(ref_c)
    r = np.arange(m)
    U = ref_ax[r, (axis + 1) % 3]
    V = ref_ax[r, (axis + 2) % 3]
    hu = ref_h[r, (axis + 1) % 3][:, None]
    hv = ref_h[r, (axis + 2) % 3][:, None]
    fc = ref_c + n_ref * ref_h[r, axis][:, None]
    eps = 1e-9 * (hu + hv) + 1e-12

    # incident face: the face of the other box most opposed to n_ref
    j = np.argmax(np.abs(np.einsum("kmi,ki->km", inc_ax, n_ref)), axis=1)
    n_inc = inc_ax[r, j] * -_sign(np.einsum("ki,ki->k", inc_ax[r, j], n_ref))[:, None]
    e1_dir, e2_dir = inc_ax[r, (j + 1) % 3], inc_ax[r, (j + 2) % 3]
    h1, h2 = inc_h[r, (j + 1) % 3][:, None], inc_h[r, (j + 2) % 3][:, None]
    ic = inc_c + n_inc * inc_h[r, j][:, None]
    verts = (ic[:, None, :] + QUAD_SIGNS[None, :, 0, None] * (h1[:, :, None] * e1_dir[:, None, :])
             + QUAD_SIGNS[None, :, 1, None] * (h2[:, :, None] * e2_dir[:, None, :]))
    rel = verts - fc[:, None, :]
    vu = np.einsum("kvi,ki->kv", rel, U)
    vv = np.einsum("kvi,ki->kv", rel, V)
    vw = np.einsum("kvi,ki->kv", rel, n_ref)

    # 1. incident corners inside the rectangle
    ok1 = (np.abs(vu) <= hu + eps) & (np.abs(vv) <= hv + eps)

    # 2. rectangle corners inside the incident face, lifted onto its plane:
    #    w = n_inc·(ic - x0) / (n_inc·n_ref), |n_inc·n_ref| >= 1/√3 by the choice of face
    cu2 = QUAD_SIGNS[None, :, 0] * hu
    cv2 = QUAD_SIGNS[None, :, 1] * hv
    x0 = fc[:, None, :] + cu2[..., None] * U[:, None, :] + cv2[..., None] * V[:, None, :]
    cos = np.einsum("ki,ki->k", n_inc, n_ref)[:, None]
    cw2 = np.einsum("ki,kvi->kv", n_inc, ic[:, None, :] - x0) / cos
    on_inc = x0 + cw2[..., None] * n_ref[:, None, :] - ic[:, None, :]
    ok2 = ((np.abs(np.einsum("kvi,ki->kv", on_inc, e1_dir)) <= h1 + eps)
           & (np.abs(np.einsum("kvi,ki->kv", on_inc, e2_dir)) <= h2 + eps))

    # 3. incident edges (corner v to v+1) crossing the sides u = ±hu and v = ±hv
    nxt = [1, 2, 3, 0]
    P = np.stack([vu, vv, vw], axis=-1)                    # (m, 4, 3)
    D = P[:, nxt] - P
    side_u = np.stack([hu, -hu], axis=-1)                  # (m, 1, 2)
    side_v = np.stack([hv, -hv], axis=-1)
    cross = []
    for along, other, sides, lim in ((0, 1, side_u, hv), (1, 0, side_v, hu)):
        den = D[:, :, along][..., None]                    # (m, 4, 1)
        good = np.abs(den) > 1e-14
        s = (sides - P[:, :, along][..., None]) / np.where(good, den, 1.0)
        pt = P[:, :, None, :] + s[..., None] * D[:, :, None, :]      # (m, 4, 2, 3)
        ok = good & (s >= 0.0) & (s <= 1.0) & (np.abs(pt[..., other]) <= (lim + eps)[..., None])
        cross.append((pt.reshape(m, 8, 3), ok.reshape(m, 8)))

    cu = np.concatenate([vu, cu2, cross[0][0][..., 0], cross[1][0][..., 0]], axis=1)
    cv = np.concatenate([vv, cv2, cross[0][0][..., 1], cross[1][0][..., 1]], axis=1)
    cw = np.concatenate([vw, cw2, cross[0][0][..., 2], cross[1][0][..., 2]], axis=1)
    ok = np.concatenate([ok1, ok2, cross[0][1], cross[1][1]], axis=1) & (cw < margin)
    cu = np.clip(cu, -hu, hu)
    cv = np.clip(cv, -hv, hv)

    # reduce to the extreme candidate along each diagonal of the smaller face
    inc_smaller = (h1 * h2 < hu * hv)[:, 0]
    g1 = np.where(inc_smaller[:, None],
                  np.stack([np.einsum("ki,ki->k", e1_dir, U), np.einsum("ki,ki->k", e1_dir, V)], 1) / h1,
                  np.concatenate([1.0 / hu, np.zeros_like(hu)], 1))
    g2 = np.where(inc_smaller[:, None],
                  np.stack([np.einsum("ki,ki->k", e2_dir, U), np.einsum("ki,ki->k", e2_dir, V)], 1) / h2,
                  np.concatenate([np.zeros_like(hv), 1.0 / hv], 1))
    a1 = cu * g1[:, :1] + cv * g1[:, 1:]                   # (m, 24) coordinate along each face axis
    a2 = cu * g2[:, :1] + cv * g2[:, 1:]
    score = QUAD_SIGNS[None, :, 0, None] * a1[:, None, :] + QUAD_SIGNS[None, :, 1, None] * a2[:, None, :]
    score = np.where(ok[:, None, :], score, -np.inf)       # (m, 4 quadrants, 24)
    pick = np.argmax(score, axis=2)
    keep = np.take_along_axis(score, pick[..., None], axis=2)[..., 0] > -np.inf
    pu = np.take_along_axis(cu, pick, axis=1)
    pv = np.take_along_axis(cv, pick, axis=1)
    pw = np.take_along_axis(cw, pick, axis=1)
    for q in range(1, 4):
        for p in range(q):
            same = (np.abs(pu[:, q] - pu[:, p]) + np.abs(pv[:, q] - pv[:, p])
                    + np.abs(pw[:, q] - pw[:, p])) <= 4.0 * eps[:, 0]
            keep[:, q] &= ~(keep[:, p] & same)
    row, quad = np.nonzero(keep)
    w = pw[row, quad]
    point = (fc[row] + pu[row, quad, None] * U[row] + pv[row, quad, None] * V[row]
             + (0.5 * w)[:, None] * n_ref[row])
    return row, quad.astype(np.int64), point, -w
