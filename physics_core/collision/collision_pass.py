"""The collision pass, before the contact solve (COURSE.md 5, coefficient of
restitution): bounces (bounce.py) swept in key order until no contact
approaches, one body pair at a time.

A pair touching at one point bounces by the course's pairwise impulse, and
the pairs bounce one after the other: a ball that hits a row of touching
balls passes the blow along the row pair by pair, as elastic collisions
do, so C_R = 1 without friction keeps the kinetic energy and C_R's
definition holds contact by contact.

The points of one manifold (two bodies touching along a face or an edge)
bounce together: each bouncing point i must end separating at its goal
g_i (C_R × its approach, bounce.bounce_goal) or faster, with a normal
impulse λ_i ≥ 0 that is zero where it separates faster,

    u_i(λ) ≥ g_i,   λ_i ≥ 0,   λ_i (u_i(λ) − g_i) = 0,

solved by sweeps over the manifold's points (projected Gauss–Seidel on the
accumulated λ, until a sweep changes no λ by BLOCK_TOLERANCE of their sum),
started from the even share (_even_start).
Bounced point by point instead, the first corner of a box landing flat took
the whole blow and the box left the floor turning: a 20 cm cube dropped
flat on its face from 5 cm with C_R = 0.5 spun at 3.8 rad/s and slid at
0.3 m/s, where it should rise straight at C_R × its approach speed. Friction
then acts on Σλ_i at the manifold's anchor (bounce_friction.py), and on a
single point's λ (bounce.bounce_friction). A single point is
the same problem with one row: one update solves it, and a second would
only add rounding, so it gets exactly the pairwise impulse.

A collision does not create energy: an impulse dλ on a row at normal
velocity u changes the kinetic energy by dλ (u + ½ dλ W_00) (the row's
velocity goes from u to u + dλ W_00); if a manifold's sweeps gained
energy, they are undone and its points bounce one by one.
"""
from numba import njit

from .bounce import AFTER, bounce_friction, bounce_goal, impact_terms
from .bounce_friction import anchor_bounce_friction
from .contact_build import row_velocity, tangent_block
from .contact_layout import BODY_A, BODY_B, MASS_N, W_TT_INV
from .manifold_friction import COUNT, FIRST
from .pair_velocity import load_pair, pair_impulse, pair_velocity, store_pair

# columns of the pass's scratch table after impact_terms' (WHEN, SHIFT, AFTER)
GOAL, ACC, EA, AT, TESTED = AFTER + 1, AFTER + 2, AFTER + 3, AFTER + 4, AFTER + 5
PASS_COLS = TESTED + 1
BLOCK_SWEEPS = 100        # sweeps over one manifold's points at most (about 0.7 a sweep
                          # on four coplanar corners, from zero: 60 reach 1e-9)
BLOCK_TOLERANCE = 1e-9    # × the manifold's total impulse: its sweeps have converged
ENERGY_TOLERANCE = 1e-9   # × Σ λ_i |g_i|: rounding, not a gain


@njit(cache=True, inline="always")
def _manifold_of(MI, c):
    """The manifold holding row c: the last whose first row is c or before
    (MI's first rows ascend; manifold_friction.manifold_ranges, one run of
    rows of one body pair each)."""
    lo, hi = 0, len(MI) - 1
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if MI[mid, FIRST] <= c:
            lo = mid
        else:
            hi = mid - 1
    return lo


@njit(cache=True, inline="always")
def _goals(R, first, end, p, terms, target, J, table):
    """Each point's goal (NaN: it does not bounce), C_R × approach and τ into
    the table, its λ to 0; whether some point bounces."""
    threshold, ramp, h = terms
    some = False
    for c in range(first, end):
        goal, ea, when = bounce_goal(R, c, threshold, ramp, h, pair_velocity(R, c, 0, p), table,
                                     target, J)
        table[c, GOAL], table[c, ACC], table[c, EA], table[c, AT] = goal, 0.0, ea, when
        some |= goal == goal
    return some


@njit(cache=True, inline="always")
def _push(R, c, d, u, p, gained):
    """Impulse d on point c (its velocity u before it) applied to the pair's
    velocities p: (p after, `gained` plus the kinetic energy it adds,
    d (u + ½ d W_cc))."""
    return pair_impulse(R, c, 0, d, p), gained + d * (u + 0.5 * d / R[c, MASS_N])


@njit(cache=True, inline="always")
def _even_start(R, first, end, p, table):
    """The sweeps' start for two or more points: λ_i = (g_i − u_i) / Σ_j W_ij
    over the bouncing points j (their velocity change for a unit impulse on
    each), the answer where every point needs the same share, as on a face
    landing flat (the sweeps from zero took about 60 sweeps there), and a
    start otherwise. Applied in turn (_push): (p after, the energy they
    gained)."""
    q = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    for c in range(first, end):
        if table[c, GOAL] == table[c, GOAL]:
            q = pair_impulse(R, c, 0, 1.0, q)
    for c in range(first, end):
        share = pair_velocity(R, c, 0, q)
        if table[c, GOAL] == table[c, GOAL] and share > 0.0:
            table[c, ACC] = max((table[c, GOAL] - pair_velocity(R, c, 0, p)) / share, 0.0)
    gained = 0.0
    for c in range(first, end):
        d = table[c, ACC]
        if d > 0.0:
            p, gained = _push(R, c, d, pair_velocity(R, c, 0, p), p, gained)
    return p, gained


@njit(cache=True, inline="always")
def _sweeps(R, first, end, p, table, gained):
    """Projected Gauss–Seidel on the points' λ (module docstring), from the
    pair's velocities p and λ in the table: (p after, the kinetic energy
    the impulses gained, `gained` before them, Σ λ_i |g_i| for scale)."""
    for _ in range(BLOCK_SWEEPS if end - first > 1 else 1):
        change = total = 0.0
        for c in range(first, end):
            goal = table[c, GOAL]
            if goal != goal:
                continue
            u = pair_velocity(R, c, 0, p)
            old = table[c, ACC]
            new = old + (goal - u) * R[c, MASS_N]
            if not new > 0.0:                # pushes only (a NaN bounces nothing)
                new = 0.0
            d = new - old
            if d != 0.0:
                p, gained = _push(R, c, d, u, p, gained)
                table[c, ACC] = new
            change = max(change, abs(d))
            total += new
        if not change > BLOCK_TOLERANCE * total:
            break
    scale = 0.0
    for c in range(first, end):
        if table[c, GOAL] == table[c, GOAL]:
            scale += table[c, ACC] * abs(table[c, GOAL])
    return p, gained, scale


@njit(cache=True, inline="always")
def _record(R, I, first, end, vel, omega, target, tau, J, table, anchor):
    """Friction on the bounce (a single point's on its λ, bounce.py; two or
    more points' at their manifold's anchor on their Σλ,
    bounce_friction.py), the impulses into J and the first bounce's target
    and τ; the number of points that bounced."""
    a, b = I[first, BODY_A], I[first, BODY_B]
    if end - first > 1:
        M, k = anchor
        anchor_bounce_friction(M, k, R, first, end, a, b, vel, omega, table[:, ACC], J)
    count = 0
    for c in range(first, end):
        jn = table[c, ACC]
        if not jn > 0.0:
            continue
        if end - first == 1:
            if R[c, W_TT_INV] != R[c, W_TT_INV]:
                tangent_block(R, c)      # a manifold's point bounced alone (_one_by_one)
            s1, s2 = bounce_friction(R, c, a, b, jn, vel, omega)
            J[c, 1] += s1
            J[c, 2] += s2
        J[c, 0] += jn
        if target[c] == 0.0:             # the first bounce of this contact sets its timing
            target[c] = table[c, EA]
            tau[c] = table[c, AT]
        count += 1
    return count


@njit(cache=True, inline="always")
def bounce_points(R, I, first, end, vel, omega, terms, target, tau, J, table, anchor):
    """The bounce of rows first..end − 1, one body pair's points, together
    (module docstring); the number of points that bounced, or −1 when the
    sweeps would have gained energy (nothing is then changed)."""
    a, b = I[first, BODY_A], I[first, BODY_B]
    p = load_pair(vel, omega, a, b)
    if not _goals(R, first, end, p, terms, target, J, table):
        return 0
    gained = 0.0
    if end - first > 1:
        p, gained = _even_start(R, first, end, p, table)
    p, gained, scale = _sweeps(R, first, end, p, table, gained)
    if end - first > 1 and gained > ENERGY_TOLERANCE * scale:
        return -1
    store_pair(vel, omega, a, b, p)
    return _record(R, I, first, end, vel, omega, target, tau, J, table, anchor)


@njit(cache=True, inline="always")
def _one_by_one(R, I, first, end, vel, omega, terms, target, tau, J, table, anchor):
    """The bounces of rows first..end − 1 each alone (bounce_points on one row)."""
    got = 0
    for c in range(first, end):
        got += bounce_points(R, I, c, c + 1, vel, omega, terms, target, tau, J, table,
                             anchor)
    return got


@njit(cache=True, inline="always")
def _bounce_pair(R, I, first, end, vel, omega, terms, target, tau, J, table, anchor):
    """One pair's bounce, its points together, or one by one if that gained energy."""
    got = bounce_points(R, I, first, end, vel, omega, terms, target, tau, J, table, anchor)
    if got >= 0:
        return got
    return _one_by_one(R, I, first, end, vel, omega, terms, target, tau, J, table, anchor)


# Inlined in the pass's loop: most contacts do not bounce, and for them the
# pass is one velocity and one test, as before the manifolds bounced together;
# a call per contact would pass eight arrays field by field.
@njit(cache=True, inline="always")
def _bounces(R, I, c, vel, omega, terms, target, J, table):
    """Whether contact c would bounce now (bounce.bounce_goal)."""
    threshold, ramp, h = terms
    u = row_velocity(R, c, 0, I[c, BODY_A], I[c, BODY_B], vel, omega)
    goal = bounce_goal(R, c, threshold, ramp, h, u, table, target, J)[0]
    return goal == goal


@njit(cache=True, inline="always")
def _unchanged(I, c, since, table):
    """Whether neither body of contact c changed velocity since its last
    test (since: each body's last change; table's TESTED: when c was
    tested, on the same clock). Its test reads nothing else that a bounce
    of another pair changes, so it would give the same answer."""
    tested = table[c, TESTED]
    return since[I[c, BODY_A]] <= tested and since[I[c, BODY_B]] <= tested


# Inlined in collision_pass: a call passes its nine arrays field by field
# (a one-sphere step's restitution stage 0.31 -> 0.45 µs when it was called).
@njit(cache=True, inline="always")
def _pass_sweep(R, I, vel, omega, terms, target, tau, J, table, since, retest, anchors):
    """One sweep of the pass, pair by pair in key order; skips a contact
    whose bodies did not change velocity since its last test (_unchanged)
    unless `retest`. since[-1] is the clock: the number of pairs bounced
    so far; anchors = (M, MI) (manifold_friction.py): a bouncing contact's
    manifold gives its pair's rows and its anchor. Returns the number of
    points that bounced."""
    M, MI = anchors
    bounced = 0
    c = 0
    while c < len(R):
        if not retest and _unchanged(I, c, since, table):
            c += 1
            continue
        table[c, TESTED] = since[-1]
        if not _bounces(R, I, c, vel, omega, terms, target, J, table):
            c += 1
            continue
        k = _manifold_of(MI, c)      # its pair's points bounce together
        first, end = MI[k, FIRST], MI[k, FIRST] + MI[k, COUNT]
        bounced += _bounce_pair(R, I, first, end, vel, omega, terms, target, tau, J, table,
                                (M, k))
        since[-1] += 1
        since[I[c, BODY_A]] = since[I[c, BODY_B]] = since[-1]
        c = end
    return bounced


@njit(cache=True, inline="always")
def collision_pass(R, I, vel, omega, vel_start, omega_start, threshold, ramp, h, w, sweeps,
                   target, tau, J, table, since, anchors, retest_all=False):
    """Sweeps of bounces, pair by pair, until none bounces (at most `sweeps`).
    target[c] = C_R × approach of contact c's first bounce (0: it did not
    bounce elastically), tau[c] its impact fraction (1 when none), J (k, 3)
    the impulses applied; vel_start, omega_start: the velocities at the
    start of the substep; table (k, PASS_COLS) and since (n + 1,) int64:
    scratch; anchors = (M, MI), the manifolds' anchors (manifold_friction.py).
    Returns the number of bounces.
    A sweep after the first tests again only the contacts a bounce since
    their last test reached (a body of theirs changed velocity): the others
    would not bounce now either. With retest_all every contact is tested
    every sweep (the same bounces, tests/test_collision_pass_retest.py);
    on a dense pile of 1,000 spheres, four sweeps took 373 µs that way and
    196 µs with the skip."""
    for c in range(len(R)):
        target[c] = 0.0
        tau[c] = 1.0
        J[c, 0] = J[c, 1] = J[c, 2] = 0.0
        # never tested: a bounce's pair skips its other points in that sweep
        table[c, TESTED] = -1.0
    impact_terms(R, I, vel_start, omega_start, h, w, table)
    since[:] = 0
    terms = (threshold, ramp, h)
    count = 0
    for sweep in range(sweeps):
        bounced = _pass_sweep(R, I, vel, omega, terms, target, tau, J, table, since,
                              retest_all or sweep == 0, anchors)
        count += bounced
        if bounced == 0:
            break
    return count
