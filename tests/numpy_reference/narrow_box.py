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

from physics_core import quaternion as qt

EDGE_EPS = 1e-5        # |A_i × B_j| below this: the edges are parallel, the axis is skipped
BOX_BLOCK = 2048        # box pairs handled together
AXIS_TOL = 1e-3        # prefer A's face, then B's face, then an edge, unless the next beats
                       # it by AXIS_TOL × the smallest half extent (keeps the choice steady)


def _frames(ha, pa, qa, hb, pb, qb):
    A = np.swapaxes(qt.to_matrix(qa), 1, 2)     # A[k, i] = body axis i of box a, world frame
    B = np.swapaxes(qt.to_matrix(qb), 1, 2)
    return A, B, pb - pa


_NEXT = np.array([1, 2, 0])
_PREV = np.array([2, 0, 1])


def separations(ha, A, hb, B, t):
    """Separation of the two boxes along each of the 15 axes.

    Returns face_a (k, 3), face_b (k, 3), edge (k, 3, 3) (-inf where the
    edges are parallel) and C (k, 3, 3), C_ij = A_i·B_j. Along a unit axis L
    the separation is |t·L| - Σ h_a |A_m·L| - Σ h_b |B_m·L|. For the edge
    axis L = A_i × B_j the terms come from C alone (Ericson 4.4.1): in a's
    frame L = (0, -C_{i+2,j}, C_{i+1,j}) (indices cyclic, from position i),
    so |L|² = C_{i+1,j}² + C_{i+2,j}², which stays exact for nearly
    parallel edges where 1 - C_ij² would cancel."""
    C = np.einsum("kim,kjm->kij", A, B)
    absC = np.abs(C)
    tA = np.einsum("kim,km->ki", A, t)
    tB = np.einsum("kjm,km->kj", B, t)
    face_a = np.abs(tA) - ha - np.einsum("kij,kj->ki", absC, hb)
    face_b = np.abs(tB) - hb - np.einsum("kij,ki->kj", absC, ha)
    n1, n2 = _NEXT, _PREV                                  # i+1, i+2 (mod 3)
    C1, C2 = C[:, n1, :], C[:, n2, :]                      # C_{i+1,j}, C_{i+2,j}
    aC1, aC2 = absC[:, n1, :], absC[:, n2, :]
    ra = ha[:, n1, None] * aC2 + ha[:, n2, None] * aC1
    rb = hb[:, None, n1] * absC[:, :, n2] + hb[:, None, n2] * absC[:, :, n1]
    dist = np.abs(tA[:, n2, None] * C1 - tA[:, n1, None] * C2)
    length = np.sqrt(C1 * C1 + C2 * C2)
    valid = length > EDGE_EPS
    edge = np.where(valid, (dist - ra - rb) / np.where(valid, length, 1.0), -np.inf)
    return face_a, face_b, edge, C


def edge_axis(A, C, i, j):
    """Unit world axis A_i × B_j for rows k (arrays i, j), from C (see separations)."""
    k = np.arange(len(i))
    c1, c2 = C[k, _NEXT[i], j], C[k, _PREV[i], j]
    L = -c2[:, None] * A[k, _NEXT[i]] + c1[:, None] * A[k, _PREV[i]]
    return L / np.linalg.norm(L, axis=1, keepdims=True)


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
    on `second`); an edge–edge contact uses slot 0. Pairs go through in
    blocks of BOX_BLOCK, which keeps the many (pairs × 24 candidates) work
    arrays small enough to be reused from the allocator's cache."""
    if len(f) <= BOX_BLOCK:
        return _box_box(model, f, s, pf, qf, ps, qs, margin)
    parts = []
    for c in range(0, len(f), BOX_BLOCK):
        blk = slice(c, c + BOX_BLOCK)
        row, slot, point, normal, depth = _box_box(model, f[blk], s[blk], pf[blk], qf[blk],
                                                   ps[blk], qs[blk], margin)
        parts.append((row + c, slot, point, normal, depth))
    return tuple(np.concatenate(col) for col in zip(*parts))


def _box_box(model, f, s, pf, qf, ps, qs, margin):
    ha, hb = model.half_extents[f], model.half_extents[s]
    A, B, t = _frames(ha, pf, qf, hb, ps, qs)
    fa, fb, edge, C = separations(ha, A, hb, B, t)
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
        parts.append(_edge_contacts(E, ie[E] // 3, ie[E] % 3, C, se[E], A, ha, pf, B, hb, ps, t))

    if not parts:
        z = np.zeros(0, np.int64)
        return z, z, np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0)
    row, slot, point, normal, depth = (np.concatenate(c) for c in zip(*parts))
    return row, slot.astype(np.int64), point, normal, depth


def _edge_contacts(E, i, j, C, sep, A, ha, pa, B, hb, pb, t):
    """One point per pair, midway between the closest points of the two edges
    (the edge of a furthest along n, the edge of b furthest along -n).

    Closest points of lines p + s d1, q + u d2 (unit d): with r = p - q,
    b = d1·d2, c = d1·r, f = d2·r: s = (b f - c) / (1 - b²), u = f + s b;
    then clamped to the edges' lengths (Ericson 5.1.9). 1 - b² > EDGE_EPS²
    because parallel edges never give an edge axis."""
    m = np.arange(len(E))
    n = edge_axis(A[E], C[E], i, j)
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
    frame = np.stack([U, V, n_ref], axis=1)                # rows: the reference frame's axes
    inc = np.einsum("kai,kbi->kba", frame, inc_ax)         # incident axes in that frame

    # incident face: the face of the other box most opposed to n_ref
    j = np.argmax(np.abs(inc[:, :, 2]), axis=1)
    n_inc = inc[r, j] * -_sign(inc[r, j, 2])[:, None]
    e1, e2 = inc[r, (j + 1) % 3], inc[r, (j + 2) % 3]
    h1, h2 = inc_h[r, (j + 1) % 3][:, None], inc_h[r, (j + 2) % 3][:, None]
    ic = np.einsum("kai,ki->ka", frame, inc_c - fc) + n_inc * inc_h[r, j][:, None]
    s1, s2 = QUAD_SIGNS[None, :, 0, None], QUAD_SIGNS[None, :, 1, None]
    P = ic[:, None, :] + s1 * (h1 * e1)[:, None, :] + s2 * (h2 * e2)[:, None, :]   # (m, 4, 3)
    vu, vv, vw = P[..., 0], P[..., 1], P[..., 2]

    # 1. incident corners inside the rectangle
    ok1 = (np.abs(vu) <= hu + eps) & (np.abs(vv) <= hv + eps)

    # 2. rectangle corners inside the incident face, lifted onto its plane
    #    n·((u, v, w) - ic) = 0; |n_w| >= 1/√3 by the choice of face
    cu2 = QUAD_SIGNS[None, :, 0] * hu
    cv2 = QUAD_SIGNS[None, :, 1] * hv
    du, dv = cu2 - ic[:, :1], cv2 - ic[:, 1:2]
    dw = -(n_inc[:, :1] * du + n_inc[:, 1:2] * dv) / n_inc[:, 2:]
    cw2 = ic[:, 2:] + dw
    ok2 = ((np.abs(du * e1[:, :1] + dv * e1[:, 1:2] + dw * e1[:, 2:]) <= h1 + eps)
           & (np.abs(du * e2[:, :1] + dv * e2[:, 1:2] + dw * e2[:, 2:]) <= h2 + eps))

    # 3. incident edges (corner v to v+1) crossing the sides u = ±hu and v = ±hv:
    #    at fraction f = (side - P_along) / D_along of the edge
    D = P[:, [1, 2, 3, 0]] - P
    cand = [(vu, vv, vw, ok1), (cu2, cv2, cw2, ok2)]
    for along, other, half, lim in ((0, 1, hu, hv), (1, 0, hv, hu)):
        side = np.stack([half, -half], axis=-1)            # (m, 1, 2): the two sides
        den = D[:, :, along, None]                         # (m, 4, 1)
        good = np.abs(den) > 1e-14
        f = (side - P[:, :, along, None]) / np.where(good, den, 1.0)          # (m, 4, 2)
        co = P[:, :, other, None] + f * D[:, :, other, None]
        cw = (P[:, :, 2, None] + f * D[:, :, 2, None]).reshape(m, 8)
        ok = (good & (f >= 0.0) & (f <= 1.0) & (np.abs(co) <= lim[:, :, None] + eps[:, :, None])).reshape(m, 8)
        sides = np.broadcast_to(side, (m, 4, 2)).reshape(m, 8)
        co = co.reshape(m, 8)
        cand.append((sides, co, cw, ok) if along == 0 else (co, sides, cw, ok))
    cu, cv, cw, ok = (np.concatenate(c, axis=1) for c in zip(*cand))
    ok &= cw < margin
    cu = np.clip(cu, -hu, hu)
    cv = np.clip(cv, -hv, hv)

    # reduce to the extreme candidate along each diagonal of the smaller face:
    # coordinates along that face's two axes, scaled by its half sizes
    inc_smaller = (h1 * h2 < hu * hv)
    g1u = np.where(inc_smaller, e1[:, :1] / h1, 1.0 / hu)
    g1v = np.where(inc_smaller, e1[:, 1:2] / h1, 0.0)
    g2u = np.where(inc_smaller, e2[:, :1] / h2, 0.0)
    g2v = np.where(inc_smaller, e2[:, 1:2] / h2, 1.0 / hv)
    a1 = cu * g1u + cv * g1v                               # (m, 24)
    a2 = cu * g2u + cv * g2v
    pick = np.empty((m, 4), np.int64)
    for q, (q1, q2) in enumerate(QUAD_SIGNS):
        pick[:, q] = np.argmax(np.where(ok, q1 * a1 + q2 * a2, -np.inf), axis=1)
    flat = pick + cu.shape[1] * r[:, None]                 # index into the (m, 24) candidates
    keep = ok.ravel().take(flat)
    pu, pv, pw = cu.ravel().take(flat), cv.ravel().take(flat), cw.ravel().take(flat)
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
