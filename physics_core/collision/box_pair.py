"""Compiled box–box contact by the separating-axis test (COURSE.md 5: the
contact point and a normal that separates the bodies).

Two convex boxes are apart exactly when some axis separates their
projections; 15 axes suffice: the 3 face normals of each box and the 9
cross products of their edge directions (Gottschalk's OBB test, Ericson,
Real-Time Collision Detection 4.4). The axis of largest separation gives
the normal, with narrow_box.py's preference (A's face, then B's face, then
an edge, unless the next beats it by AXIS_TOL × the smallest half extent).
A face axis clips the incident face of the other box to the reference
face's rectangle (at most 4 points, slots 0–3 with the reference face on
the first box, 4–7 on the second); an edge axis gives one point midway
between the closest points of the two edges (slot 0).

This is narrow_box.py pair by pair: the same candidates, tie rules and
floating-point operations in the same order (geometry.py), so the same
bits. Everything works in a scratch array `ws` (`workspace()`, one per
detect call) whose rows are named below, so no pair allocates; the pair's
data is copied in first and the helpers take `ws` and scalars only (no
array views per pair: each costs reference-count updates).
"""
import math

import numpy as np
from numba import njit

from .geometry import HALF, body_axes, clip, dot_lanes, dot_seq, sign
from .shape_pairs import put_row

EDGE_EPS = 1e-5    # |A_i × B_j| below this: the edges are parallel, the axis is skipped
AXIS_TOL = 1e-3    # prefer A's face, then B's face, then an edge, unless the next beats it by
                   # AXIS_TOL × the smallest half extent (both as in narrow_box.py)

# rows of the workspace (8 columns)
A, B, C, AC = 0, 3, 6, 9          # axes of box a, of box b (rows i: axis i, world), C_ij = A_i·B_j, |C|
T, TA, TB, HA, HB = 12, 13, 14, 15, 16   # t = p_b - p_a, t in a's and b's frames, half extents
PA, PB = 17, 18                   # the two centres
FRAME, INC, FC, IC = 19, 22, 25, 26   # reference frame (U, V, n), incident axes in it, face centre,
                                      # incident face centre
NINC, E1, E2, P, D = 27, 28, 29, 30, 34   # incident face normal, edges; its corners; corner to next
CAND, PICK = 38, 62               # 24 clip candidates (u, v, w, ok, a1, a2); 4 picked (u, v, w, keep)
WS_ROWS = 66
CANDIDATES = 24
_QUAD = ((1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0))   # narrow_box.QUAD_SIGNS


@njit(cache=True)
def workspace():
    """Scratch rows for one box pair at a time (and plane_box's 8 heights in row 0)."""
    return np.zeros((WS_ROWS, 8))


@njit(cache=True, inline="always")
def _load(f, s, dims, pos, quat, ws):
    """Boxes f (a) and s (b) into ws: axes, centres, offset, half extents,
    then C = A Bᵀ and t in both frames (sums over strided axes in
    narrow_box's einsums: dot_seq)."""
    body_axes(quat[f, 0], quat[f, 1], quat[f, 2], quat[f, 3], ws, A)
    body_axes(quat[s, 0], quat[s, 1], quat[s, 2], quat[s, 3], ws, B)
    for m in range(3):
        ws[PA, m], ws[PB, m] = pos[f, m], pos[s, m]
        ws[T, m] = pos[s, m] - pos[f, m]
        ws[HA, m], ws[HB, m] = dims[f, HALF + m], dims[s, HALF + m]
    for i in range(3):
        for j in range(3):
            c = dot_seq(ws[A + i, 0], ws[A + i, 1], ws[A + i, 2], ws[B + j, 0], ws[B + j, 1], ws[B + j, 2])
            ws[C + i, j] = c
            ws[AC + i, j] = abs(c)
        ws[TA, i] = dot_seq(ws[A + i, 0], ws[A + i, 1], ws[A + i, 2], ws[T, 0], ws[T, 1], ws[T, 2])
        ws[TB, i] = dot_seq(ws[B + i, 0], ws[B + i, 1], ws[B + i, 2], ws[T, 0], ws[T, 1], ws[T, 2])


@njit(cache=True, inline="always")
def _face_gap(ws, own, ta, i):
    """Separation along face normal i of box a (own = HA, ta = TA) or b
    (HB, TB):
    |t·L| - h_i - Σ_j |C_ij| h'_j; numpy sums A's row contiguously
    (dot_lanes), B's column strided (dot_seq)."""
    if own == HA:
        spread = dot_lanes(ws[AC + i, 0], ws[AC + i, 1], ws[AC + i, 2], ws[HB, 0], ws[HB, 1], ws[HB, 2])
    else:
        spread = dot_seq(ws[AC, i], ws[AC + 1, i], ws[AC + 2, i], ws[HA, 0], ws[HA, 1], ws[HA, 2])
    return (abs(ws[ta, i]) - ws[own, i]) - spread


@njit(cache=True, inline="always")
def _gap(dist, ra, rb, length):
    return (dist - ra - rb) / length if length > EDGE_EPS else -np.inf


@njit(cache=True, inline="always")
def _edge_gap(ws, i, j):
    """Separation along L = A_i × B_j, from C alone (Ericson 4.4.1): in a's
    frame L = (0, -C_{i+2,j}, C_{i+1,j}) (cyclic from i), |L|² = C_{i+1,j}² +
    C_{i+2,j}², exact for nearly parallel edges; -inf where |L| <= EDGE_EPS
    (parallel edges: no axis)."""
    i1, i2, j1, j2 = (i + 1) % 3, (i + 2) % 3, (j + 1) % 3, (j + 2) % 3
    c1, c2 = ws[C + i1, j], ws[C + i2, j]
    ra = ws[HA, i1] * ws[AC + i2, j] + ws[HA, i2] * ws[AC + i1, j]
    rb = ws[HB, j1] * ws[AC + i, j2] + ws[HB, j2] * ws[AC + i, j1]
    return _gap(abs(ws[TA, i2] * c1 - ws[TA, i1] * c2), ra, rb, math.sqrt(c1 * c1 + c2 * c2))


@njit(cache=True, inline="always")
def _better(x, best):
    """np.argmax's step: a later value wins when not <= the best so far
    (so the first maximum stays, and a NaN wins and then stays); `|` and `&`
    rather than `or` and `and`, so it compiles to selects, not branches."""
    return ((x > best) | (x != x)) & (best == best)


@njit(cache=True, inline="always")
def _best_face(ws, own, ta):
    """(axis, separation) of one box's face of largest separation (np.argmax's rule)."""
    best, at = _face_gap(ws, own, ta, 0), 0
    for i in range(1, 3):
        x = _face_gap(ws, own, ta, i)
        if _better(x, best):
            best, at = x, i
    return at, best


@njit(cache=True, inline="always")
def _best_edge(ws):
    """(flat index 3 i + j, separation) of the edge axis of largest separation."""
    best, at = _edge_gap(ws, 0, 0), 0
    for e in range(1, 9):
        x = _edge_gap(ws, e // 3, e % 3)
        if _better(x, best):
            best, at = x, e
    return at, best


@njit(cache=True, inline="always")
def argmax_row(ws, row, start, count):
    """np.argmax of ws[row, start:start + count]: the first maximum (a NaN first)."""
    best, at = ws[row, start], 0
    for c in range(1, count):
        x = ws[row, start + c]
        if _better(x, best):
            best, at = x, c
    return at, best


@njit(cache=True, inline="always")
def nan_max(a, b):
    """np.maximum of two floats: NaN if either is NaN."""
    if a != a or b != b:
        return np.nan
    return a if a >= b else b


@njit(cache=True)
def separation(f, s, dims, pos, quat, ws):
    """Largest separation of boxes f, s over the 15 axes: > 0 exactly when
    they are apart (then a lower bound of their distance), else minus the
    penetration depth (narrow_box.box_box_separation)."""
    _load(f, s, dims, pos, quat, ws)
    sa = _best_face(ws, HA, TA)[1]
    sb = _best_face(ws, HB, TB)[1]
    return nan_max(nan_max(sa, sb), _best_edge(ws)[1])


@njit(cache=True)
def box_box(f, s, dims, pos, quat, margin, ws, out, k):
    """Contact rows of boxes f, s from row k (normal f → s); returns the count."""
    _load(f, s, dims, pos, quat, ws)
    ia, sa = _best_face(ws, HA, TA)
    ib, sb = _best_face(ws, HB, TB)
    ie, se = _best_edge(ws)
    tol = AXIS_TOL * min(min(ws[HA, 0], ws[HA, 1], ws[HA, 2]), min(ws[HB, 0], ws[HB, 1], ws[HB, 2]))
    use_b = sb > sa + tol
    use_edge = se > (sb if use_b else sa) + tol
    count = 0
    if nan_max(nan_max(sa, sb), se) <= margin:       # touching, or within the margin
        if use_edge:
            count = edge_contact(ie // 3, ie % 3, se, ws, out, k)
        else:
            count = face_contact(use_b, ib if use_b else ia, margin, ws, out, k)
    return count


# ---- edge–edge -------------------------------------------------------------------

@njit(cache=True, inline="always")
def _edge_direction(ws, i, j):
    """Unit world axis A_i × B_j = -C_{i+2,j} A_{i+1} + C_{i+1,j} A_{i+2} (narrow_box.edge_axis)."""
    i1, i2 = (i + 1) % 3, (i + 2) % 3
    c1, c2 = ws[C + i1, j], ws[C + i2, j]
    l0 = -c2 * ws[A + i1, 0] + c1 * ws[A + i2, 0]
    l1 = -c2 * ws[A + i1, 1] + c1 * ws[A + i2, 1]
    l2 = -c2 * ws[A + i1, 2] + c1 * ws[A + i2, 2]
    norm = math.sqrt((l0 * l0 + l1 * l1) + l2 * l2)     # np.linalg.norm's order
    return l0 / norm, l1 / norm, l2 / norm


@njit(cache=True, inline="always")
def _weight(ws, axes, half, m, skip, n0, n1, n2):
    """s_m h_m with s_m = sign(axis_m·n), 0 on the edge's own axis."""
    if m == skip:
        return 0.0
    return sign(dot_seq(ws[axes + m, 0], ws[axes + m, 1], ws[axes + m, 2], n0, n1, n2)) * ws[half, m]


@njit(cache=True, inline="always")
def _edge_offset(ws, axes, half, skip, n0, n1, n2):
    """Σ_m s_m h_m axis_m: from a box's centre to its edge (along axis `skip`)
    furthest along n."""
    w0 = _weight(ws, axes, half, 0, skip, n0, n1, n2)
    w1 = _weight(ws, axes, half, 1, skip, n0, n1, n2)
    w2 = _weight(ws, axes, half, 2, skip, n0, n1, n2)
    return (dot_seq(w0, w1, w2, ws[axes, 0], ws[axes + 1, 0], ws[axes + 2, 0]),
            dot_seq(w0, w1, w2, ws[axes, 1], ws[axes + 1, 1], ws[axes + 2, 1]),
            dot_seq(w0, w1, w2, ws[axes, 2], ws[axes + 1, 2], ws[axes + 2, 2]))


@njit(cache=True, inline="always")
def _edge_params(ws, i, j, r0, r1, r2):
    """Closest points of lines p + s d1, q + u d2 (unit d, r = p - q):
    s = (b f - c) / (1 - b²), u = f + s b with b = d1·d2, c = d1·r, f = d2·r,
    clamped to the edges' half lengths (Ericson 5.1.9); 1 - b² > EDGE_EPS²
    because parallel edges never give an edge axis."""
    bb = dot_lanes(ws[A + i, 0], ws[A + i, 1], ws[A + i, 2], ws[B + j, 0], ws[B + j, 1], ws[B + j, 2])
    c = dot_lanes(ws[A + i, 0], ws[A + i, 1], ws[A + i, 2], r0, r1, r2)
    ff = dot_lanes(ws[B + j, 0], ws[B + j, 1], ws[B + j, 2], r0, r1, r2)
    lim1, lim2 = ws[HA, i], ws[HB, j]
    denom = nan_max(1.0 - bb * bb, EDGE_EPS * EDGE_EPS)
    s = clip((bb * ff - c) / denom, -lim1, lim1)
    u = clip(ff + s * bb, -lim2, lim2)
    return clip(u * bb - c, -lim1, lim1), u


@njit(cache=True, inline="always")
def edge_contact(i, j, sep, ws, out, k):
    """One point midway between the closest points of edge i of box a (the
    one furthest along n) and edge j of box b (furthest along -n); depth -sep."""
    n0, n1, n2 = _edge_direction(ws, i, j)
    turn = sign(dot_lanes(n0, n1, n2, ws[T, 0], ws[T, 1], ws[T, 2]))    # n from a towards b
    n0, n1, n2 = n0 * turn, n1 * turn, n2 * turn
    oa = _edge_offset(ws, A, HA, i, n0, n1, n2)
    ob = _edge_offset(ws, B, HB, j, n0, n1, n2)
    p0, p1, p2 = ws[PA, 0] + oa[0], ws[PA, 1] + oa[1], ws[PA, 2] + oa[2]
    q0, q1, q2 = ws[PB, 0] - ob[0], ws[PB, 1] - ob[1], ws[PB, 2] - ob[2]
    sa, u = _edge_params(ws, i, j, p0 - q0, p1 - q1, p2 - q2)
    x0 = 0.5 * ((p0 + sa * ws[A + i, 0]) + (q0 + u * ws[B + j, 0]))
    x1 = 0.5 * ((p1 + sa * ws[A + i, 1]) + (q1 + u * ws[B + j, 1]))
    x2 = 0.5 * ((p2 + sa * ws[A + i, 2]) + (q2 + u * ws[B + j, 2]))
    put_row(out, k, 0, x0, x1, x2, n0, n1, n2, -sep)
    return 1


# ---- face contact: the incident face clipped to the reference face ----------------

@njit(cache=True, inline="always")
def face_contact(use_b, axis, margin, ws, out, k):
    """Reference face: box b's face `axis` when use_b, else box a's; the
    incident face of the other box is clipped to its rectangle
    (Sutherland–Hodgman's result, built directly from 24 candidates: incident
    corners inside the rectangle, rectangle corners inside the incident face,
    incident edges crossing the rectangle's sides), reduced to <= 4 points.
    Works in the reference frame (u, v along the face, w along n above it)."""
    ref_ax, inc_ax, ref_h, inc_h = (B, A, HB, HA) if use_b else (A, B, HA, HB)
    ref, inc = (PB, PA) if use_b else (PA, PB)
    n0, n1, n2 = ws[ref_ax + axis, 0], ws[ref_ax + axis, 1], ws[ref_ax + axis, 2]
    turn = sign(dot_lanes(n0, n1, n2, ws[inc, 0] - ws[ref, 0], ws[inc, 1] - ws[ref, 1], ws[inc, 2] - ws[ref, 2]))
    _reference_frame(ws, ref_ax, ref_h, axis, n0 * turn, n1 * turn, n2 * turn, ref)
    hu, hv = ws[ref_h, (axis + 1) % 3], ws[ref_h, (axis + 2) % 3]
    eps = 1e-9 * (hu + hv) + 1e-12
    h1, h2 = _incident_face(ws, inc_ax, inc_h, inc)
    _corner_candidates(ws, hu, hv, eps, h1, h2)
    _crossing_candidates(ws, hu, hv, eps)
    _reduce(ws, hu, hv, h1, h2, margin)
    _merge_coincident(ws, eps)
    return _face_rows(ws, use_b, out, k)


@njit(cache=True, inline="always")
def _reference_frame(ws, ref_ax, ref_h, axis, n0, n1, n2, ref_c):
    """FRAME rows U, V (the face's edges), n; FC = the face centre c + n h_axis
    (c: row ref_c)."""
    for m in range(3):
        ws[FRAME, m] = ws[ref_ax + (axis + 1) % 3, m]
        ws[FRAME + 1, m] = ws[ref_ax + (axis + 2) % 3, m]
    ws[FRAME + 2, 0], ws[FRAME + 2, 1], ws[FRAME + 2, 2] = n0, n1, n2
    h = ws[ref_h, axis]
    ws[FC, 0], ws[FC, 1], ws[FC, 2] = ws[ref_c, 0] + n0 * h, ws[ref_c, 1] + n1 * h, ws[ref_c, 2] + n2 * h


@njit(cache=True, inline="always")
def _incident_face(ws, inc_ax, inc_h, inc_c):
    """The face of the other box most opposed to n: its outward normal NINC,
    edge directions E1, E2 and centre IC in the reference frame (the other
    box's centre: row inc_c); returns the half lengths (h1, h2) along E1, E2."""
    for b in range(3):
        for a in range(3):
            ws[INC + b, a] = dot_seq(ws[FRAME + a, 0], ws[FRAME + a, 1], ws[FRAME + a, 2],
                                     ws[inc_ax + b, 0], ws[inc_ax + b, 1], ws[inc_ax + b, 2])
        ws[PICK, b] = abs(ws[INC + b, 2])
    j = argmax_row(ws, PICK, 0, 3)[0]
    turn = -sign(ws[INC + j, 2])
    j1, j2 = (j + 1) % 3, (j + 2) % 3
    d0, d1, d2 = ws[inc_c, 0] - ws[FC, 0], ws[inc_c, 1] - ws[FC, 1], ws[inc_c, 2] - ws[FC, 2]
    for a in range(3):
        ws[NINC, a] = ws[INC + j, a] * turn
        ws[E1, a] = ws[INC + j1, a]
        ws[E2, a] = ws[INC + j2, a]
        ws[IC, a] = (dot_lanes(ws[FRAME + a, 0], ws[FRAME + a, 1], ws[FRAME + a, 2], d0, d1, d2)
                     + ws[NINC, a] * ws[inc_h, j])
    return ws[inc_h, j1], ws[inc_h, j2]


@njit(cache=True, inline="always")
def _set_candidate(ws, c, u, v, w, ok):
    ws[CAND + c, 0], ws[CAND + c, 1], ws[CAND + c, 2] = u, v, w
    ws[CAND + c, 3] = 1.0 if ok else 0.0


@njit(cache=True, inline="always")
def _corner_candidates(ws, hu, hv, eps, h1, h2):
    """Candidates 0–3: incident corners P_q (inside the rectangle?); 4–7:
    rectangle corners lifted onto the incident face's plane n·(x - ic) = 0
    (inside the incident face?); |n_w| >= 1/√3 by the choice of face."""
    for q in range(4):
        s1, s2 = _QUAD[q]
        for a in range(3):
            ws[P + q, a] = (ws[IC, a] + s1 * (h1 * ws[E1, a])) + s2 * (h2 * ws[E2, a])
        vu, vv = ws[P + q, 0], ws[P + q, 1]
        _set_candidate(ws, q, vu, vv, ws[P + q, 2], (abs(vu) <= hu + eps) & (abs(vv) <= hv + eps))
        cu, cv = s1 * hu, s2 * hv
        du, dv = cu - ws[IC, 0], cv - ws[IC, 1]
        dw = -(ws[NINC, 0] * du + ws[NINC, 1] * dv) / ws[NINC, 2]
        in1 = abs((du * ws[E1, 0] + dv * ws[E1, 1]) + dw * ws[E1, 2]) <= h1 + eps
        in2 = abs((du * ws[E2, 0] + dv * ws[E2, 1]) + dw * ws[E2, 2]) <= h2 + eps
        _set_candidate(ws, 4 + q, cu, cv, ws[IC, 2] + dw, in1 & in2)


@njit(cache=True, inline="always")
def _crossing_candidates(ws, hu, hv, eps):
    """Candidates 8–23: incident edge q (corner q to q+1) crossing the side
    u = ±hu (8 + 2 q + side) or v = ±hv (16 + 2 q + side), at fraction
    f = (side - P_along) / D_along of the edge."""
    for q in range(4):
        for a in range(3):
            ws[D + q, a] = ws[P + (q + 1) % 4, a] - ws[P + q, a]
    for along in range(2):
        other = 1 - along
        half, lim = (hu, hv) if along == 0 else (hv, hu)
        for q in range(4):
            den = ws[D + q, along]
            good = abs(den) > 1e-14
            for sd in range(2):
                side = half if sd == 0 else -half
                fr = (side - ws[P + q, along]) / (den if good else 1.0)
                co = ws[P + q, other] + fr * ws[D + q, other]
                ok = good & (fr >= 0.0) & (fr <= 1.0) & (abs(co) <= lim + eps)
                u, v = (side, co) if along == 0 else (co, side)
                _set_candidate(ws, 8 + 8 * along + 2 * q + sd, u, v, ws[P + q, 2] + fr * ws[D + q, 2], ok)


@njit(cache=True, inline="always")
def _diagonal_gains(ws, hu, hv, h1, h2):
    """(g1u, g1v, g2u, g2v): a candidate's coordinates along the smaller
    face's two axes, scaled by its half sizes, are u g_u + v g_v."""
    if h1 * h2 < hu * hv:           # the incident face is the smaller one
        return ws[E1, 0] / h1, ws[E1, 1] / h1, ws[E2, 0] / h2, ws[E2, 1] / h2
    return 1.0 / hu, 0.0, 0.0, 1.0 / hv


@njit(cache=True, inline="always")
def _track(x, c, best, at, exact):
    """One step of np.argmax over candidates: (best, at) after candidate c of
    value x. `exact` applies its NaN rule; without it a plain `>` (the same
    answer when no value is NaN, and a shorter chain of dependent steps)."""
    take = _better(x, best) if exact else x > best
    return (x if take else best), (c if take else at)


@njit(cache=True, inline="always")
def _keep_candidate(ws, c, hu, hv, margin):
    """Candidate c cut at the margin and clamped to the rectangle; returns (u, v, kept)."""
    row = CAND + c
    ok = (ws[row, 3] != 0.0) & (ws[row, 2] < margin)
    u, v = clip(ws[row, 0], -hu, hu), clip(ws[row, 1], -hv, hv)
    ws[row, 0], ws[row, 1], ws[row, 3] = u, v, (1.0 if ok else 0.0)
    return u, v, ok


@njit(cache=True, inline="always")
def _keep_candidates(ws, hu, hv, h1, h2, margin):
    """Cut the candidates at the margin and clamp them to the rectangle; store
    each one's coordinates (a1, a2) along the smaller face's two axes, scaled
    by its half sizes; returns whether any is NaN."""
    g1u, g1v, g2u, g2v = _diagonal_gains(ws, hu, hv, h1, h2)
    nan = False
    for c in range(CANDIDATES):
        if ws[CAND + c, 3] == 0.0:      # not a clip point: stays out (_reduce)
            continue
        u, v, ok = _keep_candidate(ws, c, hu, hv, margin)
        a1, a2 = u * g1u + v * g1v, u * g2u + v * g2v
        ws[CAND + c, 4], ws[CAND + c, 5] = a1, a2
        nan |= ok & ((a1 != a1) | (a2 != a2))
    return nan


@njit(cache=True, inline="always")
def _along(ws, c, q):
    """How far candidate c lies along diagonal q; -inf when not kept."""
    row = CAND + c
    x = _QUAD[q][0] * ws[row, 4] + _QUAD[q][1] * ws[row, 5]
    return x if ws[row, 3] != 0.0 else -np.inf


@njit(cache=True, inline="always")
def _reduce(ws, hu, hv, h1, h2, margin):
    """Keep candidates less than `margin` above the face, clamped to the
    rectangle; for each diagonal direction q of the smaller face pick the
    candidate furthest along it (np.argmax over the 24, -inf where not kept)
    into PICK rows (u, v, w, keep)."""
    exact = _keep_candidates(ws, hu, hv, h1, h2, margin)
    b0 = b1 = b2 = b3 = -np.inf     # np.argmax from candidate 0: the same as starting at -inf
    t0 = t1 = t2 = t3 = 0
    for c in range(CANDIDATES):
        # a candidate left out is -inf along every diagonal, which never
        # beats the start: skipping it picks the same ones (a face pair keeps
        # a few of the 24; tracking all of them took half a box pair's time)
        if ws[CAND + c, 3] == 0.0:
            continue
        b0, t0 = _track(_along(ws, c, 0), c, b0, t0, exact)
        b1, t1 = _track(_along(ws, c, 1), c, b1, t1, exact)
        b2, t2 = _track(_along(ws, c, 2), c, b2, t2, exact)
        b3, t3 = _track(_along(ws, c, 3), c, b3, t3, exact)
    for q, at in enumerate((t0, t1, t2, t3)):
        for m in range(4):
            ws[PICK + q, m] = ws[CAND + at, m]


@njit(cache=True, inline="always")
def _merge_coincident(ws, eps):
    """Drop a picked point that repeats an earlier kept one (within 4 eps, L1)."""
    for q in range(1, 4):
        for p in range(q):
            same = (abs(ws[PICK + q, 0] - ws[PICK + p, 0]) + abs(ws[PICK + q, 1] - ws[PICK + p, 1])
                    + abs(ws[PICK + q, 2] - ws[PICK + p, 2])) <= 4.0 * eps
            if (ws[PICK + p, 3] != 0.0) & same:
                ws[PICK + q, 3] = 0.0


@njit(cache=True, inline="always")
def _face_point(ws, m, u, v, w):
    return ((ws[FC, m] + u * ws[FRAME, m]) + v * ws[FRAME + 1, m]) + (0.5 * w) * ws[FRAME + 2, m]


@njit(cache=True, inline="always")
def _face_rows(ws, use_b, out, k):
    """Rows of the kept picks: point fc + u U + v V + (w / 2) n (midway
    between the faces), depth -w, normal ±n (from the first box), slot
    quadrant + 4 when the reference face is on the second box."""
    flip = -1.0 if use_b else 1.0
    rows = 0
    for q in range(4):
        if ws[PICK + q, 3] != 0.0:
            u, v, w = ws[PICK + q, 0], ws[PICK + q, 1], ws[PICK + q, 2]
            put_row(out, k + rows, q + (4 if use_b else 0), _face_point(ws, 0, u, v, w),
                    _face_point(ws, 1, u, v, w), _face_point(ws, 2, u, v, w),
                    flip * ws[FRAME + 2, 0], flip * ws[FRAME + 2, 1], flip * ws[FRAME + 2, 2], -w)
            rows += 1
    return rows
