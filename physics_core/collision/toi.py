"""Time of impact of fast bodies, by bisection along the step (COURSE.md 5).

The course finds the first instant two bodies touch in [t, t+Δt] by halving
the interval until [t₀, t₁] is short, apart at t₀ and overlapping at t₁.
Bisection alone needs the pair to overlap at the end of the step; a bullet
that crosses a thin wall within one step overlaps it at neither end. So:

1. `fast_body_mask`: bodies whose sweep over the step is large against
   their own size; only they can skip through something.
2. `swept_pairs`: each fast body against everything its swept bounding box
   (the box at both ends, the span between, grown for the rotation) meets,
   by the same grid broad phase as the discrete contacts.
3. `time_of_impact`: for each pair, the sub-interval where the two moving
   bounding boxes overlap (slab test on the relative motion of the centres),
   sampled finely enough that the pair cannot pass through each other
   between two samples; the first sample that overlaps closes the bracket
   [t₀, t₁], and bisection shrinks it, every pair in lockstep.

Poses along the step: positions move linearly, orientations by slerp
(constant angular rate, so a sample spacing bounds the motion of every
point of the body).

Settings (scene keys under effects.contacts):
- ccd_threshold (CCD_THRESHOLD): a dynamic body is fast when its sweep over
  the step, |Δc| + R θ (centre travel plus the arc of its farthest point,
  R the bounding radius, θ the rotation angle), exceeds this fraction of its
  smallest half size (radius of a sphere, smallest half extent of a box).
- ccd_iterations (CCD_ITERATIONS): at most this many halvings.
- ccd_tolerance (CCD_TOLERANCE): stop when t₁ − t₀ is below this fraction
  of the step.
"""
import numpy as np

from .. import quaternion as qt
from ..shapes import BOX, PLANE, SPHERE
from .broadphase import aabb_half_extents, bounding_radius, overlapping_pairs, support_along
from .narrowphase import signed_depth

CCD_THRESHOLD = 0.5
CCD_ITERATIONS = 30
CCD_TOLERANCE = 1e-4
SAMPLE_SPACING = 0.5   # samples at most this × (s_a + s_b) of relative travel apart
MAX_SAMPLES = 512      # sample intervals per pair at most (bounds the work; a pair needing
                       # more, e.g. a 1 mm sliver crossed at 10 km/s, may skip between samples)


def smallest_half_size(model) -> np.ndarray:
    """(n,) radius of a sphere, smallest half extent of a box, inf for a plane."""
    out = np.where(model.shape_type == SPHERE, model.radius, model.half_extents.min(axis=1))
    return np.where(model.shape_type == PLANE, np.inf, out)


def rotation_angle(q0, q1) -> np.ndarray:
    """(n,) angle (rad) of the rotation taking orientation q0 to q1."""
    c = np.abs(np.einsum("ij,ij->i", q0, q1))
    return 2.0 * np.arccos(np.clip(c, 0.0, 1.0))


def sweep_length(model, prev_pos, prev_quat, pos, quat) -> np.ndarray:
    """(n,) bound on how far any point of each body moves over the step:
    centre travel |Δc| plus R θ for the rotation."""
    travel = np.linalg.norm(pos - prev_pos, axis=1)
    return travel + bounding_radius(model) * rotation_angle(prev_quat, quat)


def fast_body_mask(model, prev_pos, pos, threshold: float = CCD_THRESHOLD,
                   prev_quat=None, quat=None) -> np.ndarray:
    """(n,) dynamic bodies whose sweep over the step exceeds `threshold` ×
    their smallest half size (the rotation counts when orientations are given)."""
    if prev_quat is None or quat is None:
        sweep = np.linalg.norm(pos - prev_pos, axis=1)
    else:
        sweep = sweep_length(model, prev_pos, prev_quat, pos, quat)
    return ~model.is_static & (model.shape_type != PLANE) & (sweep > threshold * smallest_half_size(model))


def slerp(q0, q1, t) -> np.ndarray:
    """Orientations a fraction t (k,) of the way from q0 to q1 (k, 4), along
    the shorter arc, at constant angular rate; normalised lerp when the two
    are within 1e-6 rad (where slerp's 0/0 would lose precision)."""
    t = np.asarray(t, dtype=float)[:, None]
    dot = np.einsum("ij,ij->i", q0, q1)[:, None]
    q1 = np.where(dot < 0.0, -q1, q1)
    dot = np.abs(dot)
    half = np.arccos(np.clip(dot, 0.0, 1.0))
    s = np.sin(half)
    near = s < 1e-6
    safe = np.where(near, 1.0, s)
    w0 = np.where(near, 1.0 - t, np.sin((1.0 - t) * half) / safe)
    w1 = np.where(near, t, np.sin(t * half) / safe)
    q = w0 * q0 + w1 * q1
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def interpolate_poses(prev_pos, prev_quat, pos, quat, t):
    """Poses at fractions t (k,) of the step, rows matching the inputs."""
    t = np.asarray(t, dtype=float)
    return prev_pos + t[:, None] * (pos - prev_pos), slerp(prev_quat, quat, t)


def swept_half_extents(model, prev_quat, quat) -> np.ndarray:
    """(n, 3) AABB half sizes that hold the body at every orientation of the
    step: a point at distance <= R from the centre moves at most R θ as the
    body turns by θ, and never leaves the sphere of radius R."""
    h0 = aabb_half_extents(model, prev_quat)
    h1 = aabb_half_extents(model, quat)
    R = bounding_radius(model)[:, None]
    turn = np.minimum(h0 + R * rotation_angle(prev_quat, quat)[:, None], R)
    return np.maximum(np.maximum(h0, h1), turn)


def swept_pairs(model, prev_pos, prev_quat, pos, quat, fast, margin: float = 0.0):
    """Pairs (a, b) with at least one fast body whose swept boxes meet, in
    the Manifold order (static or lower index first), sorted; plus each fast
    body with each plane its lowest point may come within `margin` of
    during the step."""
    fast = np.asarray(fast, dtype=bool)
    if not fast.any():
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    solid = np.flatnonzero(model.shape_type != PLANE)
    half = swept_half_extents(model, prev_quat, quat)[solid] + 0.5 * margin
    lo = np.minimum(prev_pos, pos)[solid] - half
    hi = np.maximum(prev_pos, pos)[solid] + half
    i, j = overlapping_pairs(lo, hi)
    i, j = solid.take(i), solid.take(j)
    static = model.is_static
    keep = (fast[i] | fast[j]) & ~(static[i] & static[j])
    i, j = i[keep], j[keep]
    flip = static[j] & ~static[i]
    a = np.where(flip, j, i)
    b = np.where(flip, i, j)
    pa, pb = _swept_plane_pairs(model, prev_pos, prev_quat, pos, quat, np.flatnonzero(fast), margin)
    a = np.concatenate([a, pa])
    b = np.concatenate([b, pb])
    order = np.argsort(np.minimum(a, b) * model.n + np.maximum(a, b), kind="stable")
    return a[order], b[order]


def _swept_plane_pairs(model, prev_pos, prev_quat, pos, quat, bodies, margin):
    """(plane, body) pairs where the body's lowest point may come within
    `margin` of the plane during the step: the centre's height is lowest at
    an end of the step (linear motion), and the reach below the centre is
    at most the larger end value grown by R θ for the turn (and at most R)."""
    planes = np.flatnonzero(model.shape_type == PLANE)
    if len(planes) == 0 or len(bodies) == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    n = model.plane_normal[planes]
    off = model.plane_offset[planes]
    height = np.minimum(prev_pos[bodies] @ n.T, pos[bodies] @ n.T) - off          # (B, P)
    r0 = support_along(model, prev_quat, bodies, n)
    r1 = support_along(model, quat, bodies, n)
    R = bounding_radius(model)[bodies, None]
    turn = np.minimum(r0 + R * rotation_angle(prev_quat[bodies], quat[bodies])[:, None], R)
    reach = np.maximum(np.maximum(r0, r1), turn)
    b, p = np.nonzero(height - reach < margin)
    order = np.lexsort((bodies[b], planes[p]))
    return planes[p][order], bodies[b][order]


def _slab_window(d0, dv, E):
    """[t_in, t_out] ∩ [0, 1] where |d0 + t dv| <= E on every axis (rows of (k, 3))."""
    moving = np.abs(dv) > 1e-300
    safe = np.where(moving, dv, 1.0)
    t1 = (-E - d0) / safe
    t2 = (E - d0) / safe
    inside = np.abs(d0) <= E
    lo = np.where(moving, np.minimum(t1, t2), np.where(inside, -np.inf, np.inf))
    hi = np.where(moving, np.maximum(t1, t2), np.where(inside, np.inf, -np.inf))
    return np.maximum(lo.max(axis=1), 0.0), np.minimum(hi.min(axis=1), 1.0)


def _overlap_window(model, prev_pos, prev_quat, pos, quat, a, b):
    """[t_in, t_out] within [0, 1] where the moving bounding boxes of each
    pair overlap (empty: t_in > t_out). Centres move linearly, so on each
    axis |d0 + t dv| <= e_a + e_b is an interval of t (slab test).

    When `a` is a box that does not turn over the step (a static wall), the
    test runs in a's own frame with its exact half extents, so a thin wall
    set at an angle still gives a short window."""
    k = len(a)
    t_in, t_out = np.zeros(k), np.ones(k)
    solid = (model.shape_type[a] != PLANE) & (model.shape_type[b] != PLANE)
    if not solid.any():
        return t_in, t_out
    s = np.flatnonzero(solid)
    sa, sb = a[s], b[s]
    half = swept_half_extents(model, prev_quat, quat)
    d0 = prev_pos[sb] - prev_pos[sa]
    dv = (pos[sb] - prev_pos[sb]) - (pos[sa] - prev_pos[sa])
    t_in[s], t_out[s] = _slab_window(d0, dv, half[sa] + half[sb])

    fixed = (model.shape_type[sa] == BOX) & np.all(prev_quat[sa] == quat[sa], axis=1)
    if fixed.any():
        f = np.flatnonzero(fixed)
        fa, fb = sa[f], sb[f]
        Ra = qt.to_matrix(quat[fa])
        local = lambda v: np.einsum("kji,kj->ki", Ra, v)          # Rᵀ v: world → a's frame
        # b's extent along a's axes: |Ra^T Rb| h_b at either end, grown for its turn
        eb = np.repeat(model.radius[fb, None], 3, axis=1)
        box_b = model.shape_type[fb] == BOX
        if box_b.any():
            g = np.flatnonzero(box_b)
            hb = model.half_extents[fb[g]]
            ends = [np.einsum("kij,kj->ki", np.abs(np.einsum("kji,kjl->kil", Ra[g], qt.to_matrix(q[fb[g]]))), hb)
                    for q in (prev_quat, quat)]
            R = bounding_radius(model)[fb[g], None]
            turn = np.minimum(ends[0] + R * rotation_angle(prev_quat[fb[g]], quat[fb[g]])[:, None], R)
            eb[g] = np.maximum(np.maximum(ends[0], ends[1]), turn)
        lo, hi = _slab_window(local(d0[f]), local(dv[f]), model.half_extents[fa] + eb)
        # both windows hold every overlap: keep their intersection
        t_in[s[f]] = np.maximum(t_in[s[f]], lo)
        t_out[s[f]] = np.minimum(t_out[s[f]], hi)
    return t_in, t_out


def _depth_at(model, prev_pos, prev_quat, pos, quat, a, b, t):
    """Signed overlap of pairs (a, b) at fractions t of the step."""
    pa, qa = interpolate_poses(prev_pos[a], prev_quat[a], pos[a], quat[a], t)
    pb, qb = interpolate_poses(prev_pos[b], prev_quat[b], pos[b], quat[b], t)
    return signed_depth(model, a, b, pa, qa, pb, qb)


def time_of_impact(model, prev_pos, prev_quat, pos, quat, pairs_a, pairs_b,
                   iterations: int = CCD_ITERATIONS, tolerance: float = CCD_TOLERANCE,
                   max_samples: int = MAX_SAMPLES):
    """First touching time of each pair over the step, by sampling and bisection.

    Returns (t, hit): t (k,) in [0, 1] is the last time found with the pair
    apart (t₀ of the final bracket, so moving the bodies to t leaves them
    apart, closer than the relative travel over `tolerance` of the step);
    hit (k,) says the pair goes from apart to overlapping within the step.
    Pairs already overlapping at the start are not hits (t = 1): they are
    resting or discrete contacts, not tunnelling candidates."""
    a = np.asarray(pairs_a, dtype=np.int64)
    b = np.asarray(pairs_b, dtype=np.int64)
    k = len(a)
    t = np.ones(k)
    hit = np.zeros(k, bool)
    if k == 0:
        return t, hit
    prev_pos, prev_quat = np.asarray(prev_pos, float), np.asarray(prev_quat, float)
    pos, quat = np.asarray(pos, float), np.asarray(quat, float)

    start_apart = _depth_at(model, prev_pos, prev_quat, pos, quat, a, b, np.zeros(k)) <= 0.0
    t_in, t_out = _overlap_window(model, prev_pos, prev_quat, pos, quat, a, b)
    live = np.flatnonzero(start_apart & (t_in <= t_out))
    if len(live) == 0:
        return t, hit

    # sample count: relative travel inside the window over the allowed spacing
    la, lb = a[live], b[live]
    sweep = sweep_length(model, prev_pos, prev_quat, pos, quat)
    travel_a = np.linalg.norm(pos[la] - prev_pos[la], axis=1)
    travel_b = np.linalg.norm(pos[lb] - prev_pos[lb], axis=1)
    rel = np.linalg.norm((pos[lb] - prev_pos[lb]) - (pos[la] - prev_pos[la]), axis=1)
    rot = (sweep[la] - travel_a) + (sweep[lb] - travel_b)
    thick = smallest_half_size(model)
    # a plane is a half-space: moving through it leaves the body inside, so
    # only turning (a corner dipping in and out) needs samples, spaced by the body
    plane = model.shape_type[la] == PLANE
    rel = np.where(plane, 0.0, rel)
    spacing = SAMPLE_SPACING * np.where(plane, thick[lb], thick[la] + thick[lb])
    span = t_out[live] - t_in[live]
    need = np.ceil(span * (rel + rot) / spacing)
    intervals = np.clip(need, 1, max_samples).astype(np.int64)

    # every pair's samples t_in + span j / intervals, j = 0..intervals, flattened
    count = intervals + 1
    owner = np.repeat(np.arange(len(live)), count)
    j = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
    ts = t_in[live][owner] + span[owner] * j / intervals[owner]
    over = _depth_at(model, prev_pos, prev_quat, pos, quat, la[owner], lb[owner], ts) > 0.0
    # first overlapping sample of each pair (reduceat over each pair's block)
    first = np.cumsum(count) - count
    idx_or_big = np.where(over, j, np.iinfo(np.int64).max)
    first_hit = np.minimum.reduceat(idx_or_big, first)
    found = first_hit < np.iinfo(np.int64).max
    if not found.any():
        return t, hit
    sel = np.flatnonzero(found)
    fh = first_hit[sel]
    sp = span[sel] / intervals[sel]
    hi = t_in[live][sel] + sp * fh
    lo = np.where(fh > 0, hi - sp, 0.0)   # before t_in the bounding boxes are apart
    ba, bb = la[sel], lb[sel]
    for _ in range(int(iterations)):
        busy = np.flatnonzero(hi - lo >= tolerance)
        if len(busy) == 0:
            break
        mid = 0.5 * (lo[busy] + hi[busy])
        o = _depth_at(model, prev_pos, prev_quat, pos, quat, ba[busy], bb[busy], mid) > 0.0
        hi[busy] = np.where(o, mid, hi[busy])
        lo[busy] = np.where(o, lo[busy], mid)
    rows = live[sel]
    t[rows] = lo
    hit[rows] = True
    return t, hit
