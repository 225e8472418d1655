"""Sleeping bodies with compiled kernels: sleep.py's rest timers, islands and
waking as plain loops over bodies and contact edges.

`SleepTimers` holds the per-body state (rest timer, island label of a
sleeping body, last seen awake mask) and the next island label, all in
arrays the kernels update in place. The rules are sleep.py's, and the same
bodies sleep and wake at the same steps:

- a timer counts how long an awake dynamic body's speed has stayed under
  `linear_speed` and its spin under `angular_speed` (reset otherwise);
- islands are the connected components of the contact edges between awake
  dynamic bodies (static and sleeping bodies do not link them), labelled by
  their lowest body index; an island whose every body rested `sleep_time`
  sleeps together: velocities zeroed, awake cleared, and its bodies get the
  island label `next_island + label` (next_island then grows by n);
- a sleeping body touched by an awake dynamic body whose timer is under
  `sleep_time` wakes, with every sleeping body of its island.

The methods change `awake` (and vel, omega) in place and return True when
some body changed state: the caller (World) then refreshes its inverse masses.
"""
import numpy as np
from numba import njit


@njit(cache=True)
def _check(awake, is_static, timer, island, prev_awake):
    """The kernels index without bounds checks: refuse arrays of another world."""
    n = len(timer)
    if len(awake) != n or len(is_static) != n or len(island) != n or len(prev_awake) != n:
        raise ValueError("SleepTimers: arrays of a different number of bodies")


@njit(cache=True)
def _check_bodies(index, n):
    for r in range(len(index)):
        if index[r] < 0 or index[r] >= n:
            raise ValueError("SleepTimers: body index out of range")


@njit(cache=True)
def _sync(awake, timer, island, prev_awake):
    """Bodies woken from outside (World.wake by a command) start a fresh timer."""
    for i in range(len(awake)):
        if awake[i] and not prev_awake[i]:
            timer[i] = 0.0
            island[i] = -1
        prev_awake[i] = awake[i]


# ---- waking ------------------------------------------------------------------

@njit(cache=True, inline="always")
def _waker(awake, is_static, timer, sleep_time, i):
    """Body i is awake, dynamic and not at rest: its touch wakes a sleeper."""
    return awake[i] and not is_static[i] and timer[i] < sleep_time


@njit(cache=True, inline="always")
def _sleeper(awake, is_static, i):
    return not awake[i] and not is_static[i]


@njit(cache=True)
def _touched(awake, is_static, a, b, sleep_time, timer, hit):
    """Mark in hit the sleeping bodies a waker touches over the rows (a, b).
    Returns whether there is one."""
    found = False
    for r in range(len(a)):
        i, j = a[r], b[r]
        if _waker(awake, is_static, timer, sleep_time, i) and _sleeper(awake, is_static, j):
            hit[j] = True
            found = True
        if _waker(awake, is_static, timer, sleep_time, j) and _sleeper(awake, is_static, i):
            hit[i] = True
            found = True
    return found


@njit(cache=True)
def _hit_islands(hit, island):
    """The island labels of the hit bodies, sorted (for binary search)."""
    count = 0
    for i in range(len(hit)):
        count += hit[i]
    labels = np.empty(count, dtype=np.int64)
    r = 0
    for i in range(len(hit)):
        if hit[i]:
            labels[r] = island[i]
            r += 1
    return np.sort(labels)


@njit(cache=True, inline="always")
def _among(sorted_labels, label):
    r = np.searchsorted(sorted_labels, label)
    return r < len(sorted_labels) and sorted_labels[r] == label


@njit(cache=True)
def _wake_touched(awake, is_static, a, b, sleep_time, timer, island, prev_awake):
    """Wake the touched sleepers with their islands (see SleepTimers.wake_touched)."""
    _check(awake, is_static, timer, island, prev_awake)
    n = len(awake)
    _check_bodies(a, n)
    _check_bodies(b, n)
    hit = np.zeros(n, dtype=np.bool_)
    if not _touched(awake, is_static, a, b, sleep_time, timer, hit):
        return False
    # taken before any label is cleared: a whole island wakes with its touched body
    labels = _hit_islands(hit, island)
    for i in range(n):
        if _sleeper(awake, is_static, i) and (hit[i] or _among(labels, island[i])):
            awake[i] = True
            timer[i] = 0.0
            island[i] = -1
    prev_awake[:] = awake
    return True


# ---- falling asleep ----------------------------------------------------------

@njit(cache=True, inline="always")
def _square(v, i):
    """|v[i]|², the squares summed in the order numpy's einsum sums three
    products (two SIMD lanes: x² + z², then + y²), so that the comparisons with
    the thresholds are bit-identical to sleep.py's."""
    x, y, z = v[i, 0], v[i, 1], v[i, 2]
    return (x * x + z * z) + y * y


@njit(cache=True)
def _advance(awake, is_static, vel, omega, unsettled, dt, linear_speed, angular_speed,
             sleep_time, timer, active):
    """active[i]: awake and dynamic. Advance the timers of the resting active
    bodies by dt, reset the others' (moving, or `unsettled`: overlapping
    deeper than the slop, so position correction still moves them though
    their velocity reads rest). Returns whether some body rested sleep_time."""
    v_max = linear_speed * linear_speed
    w_max = angular_speed * angular_speed
    ready = False
    for i in range(len(awake)):
        active[i] = awake[i] and not is_static[i]
        if not active[i]:
            continue
        if _square(vel, i) < v_max and _square(omega, i) < w_max and not unsettled[i]:
            timer[i] += dt
        else:
            timer[i] = 0.0
        ready |= timer[i] >= sleep_time
    return ready


@njit(cache=True, inline="always")
def _root(parent, i):
    while parent[i] != i:
        parent[i] = parent[parent[i]]      # path halving
        i = parent[i]
    return i


@njit(cache=True)
def _islands(active, edges_a, edges_b):
    """(n,) label per body: the lowest body index of its connected component
    over the edges between active bodies. Union by smaller index keeps every
    parent below its child, so a root is its component's lowest index."""
    n = len(active)
    parent = np.arange(n)
    for e in range(len(edges_a)):
        u, v = edges_a[e], edges_b[e]
        if not (active[u] and active[v]):
            continue
        ru, rv = _root(parent, u), _root(parent, v)
        if ru < rv:
            parent[rv] = ru
        elif rv < ru:
            parent[ru] = rv
    for i in range(n):
        parent[i] = _root(parent, i)
    return parent


@njit(cache=True)
def _slowest(active, label, timer):
    """(n,) per island label: the least timer of its active bodies (inf: none)."""
    slowest = np.full(len(active), np.inf)
    for i in range(len(active)):
        if active[i] and timer[i] < slowest[label[i]]:
            slowest[label[i]] = timer[i]
    return slowest


@njit(cache=True)
def _fall_asleep(awake, vel, omega, active, label, slowest, sleep_time, island,
                 prev_awake, next_island):
    """Put the active bodies of islands that all rested sleep_time to sleep.
    Returns whether there was one."""
    n = len(awake)
    base = next_island[0]
    slept = False
    for i in range(n):
        if not (active[i] and slowest[label[i]] >= sleep_time):
            continue
        awake[i] = False
        prev_awake[i] = False
        for c in range(3):
            vel[i, c] = 0.0
            omega[i, c] = 0.0
        island[i] = base + label[i]
        slept = True
    if slept:
        next_island[0] = base + n
    return slept


@njit(cache=True)
def _update(awake, is_static, vel, omega, unsettled, edges_a, edges_b, dt, linear_speed,
            angular_speed, sleep_time, timer, island, prev_awake, next_island):
    """Advance the timers and put the rested islands to sleep (see SleepTimers.update)."""
    _check(awake, is_static, timer, island, prev_awake)
    n = len(awake)
    if vel.shape != (n, 3) or omega.shape != (n, 3):
        raise ValueError("SleepTimers: vel and omega must be (n, 3)")
    _check_bodies(edges_a, n)
    _check_bodies(edges_b, n)
    _sync(awake, timer, island, prev_awake)
    active = np.empty(len(awake), dtype=np.bool_)
    if not _advance(awake, is_static, vel, omega, unsettled, dt, linear_speed, angular_speed,
                    sleep_time, timer, active):
        return False
    label = _islands(active, edges_a, edges_b)
    slowest = _slowest(active, label, timer)
    return _fall_asleep(awake, vel, omega, active, label, slowest, sleep_time, island,
                        prev_awake, next_island)


class SleepTimers:
    """Per-body sleep state of a world of n bodies (sleep.SleepState's, in arrays)."""

    def __init__(self, n):
        self.timer = np.zeros(n)                          # s at rest so far
        self.island = np.full(n, -1, dtype=np.int64)      # label of a sleeping body's island
        self.prev_awake = np.ones(n, dtype=bool)          # awake mask the state last saw
        self.next_island = np.zeros(1, dtype=np.int64)    # first label of the next sleep

    def sync(self, awake):
        """Bodies woken from outside (World.wake by a command) start a fresh timer."""
        if len(awake) != len(self.timer):
            raise ValueError("SleepTimers: arrays of a different number of bodies")
        _sync(awake, self.timer, self.island, self.prev_awake)

    def wake_touched(self, awake, is_static, a, b, sleep_time) -> bool:
        """Wake the islands of sleeping bodies an awake, moving body touches over
        the contact rows (a, b) (all within the contact margin); `awake` is
        updated in place. Returns True when some body woke."""
        return _wake_touched(awake, is_static, a, b, float(sleep_time), self.timer,
                             self.island, self.prev_awake)

    def update(self, awake, is_static, vel, omega, edges_a, edges_b, dt, linear_speed,
               angular_speed, sleep_time) -> bool:
        """Advance the rest timers by dt (after syncing with `awake`) and put the
        islands over the touching edges (edges_a, edges_b) that rested
        sleep_time to sleep: their vel and omega zeroed and awake cleared in
        place. Returns True when some body went to sleep."""
        return _update(awake, is_static, vel, omega, np.zeros(len(awake), np.bool_), edges_a,
                       edges_b, float(dt),
                       float(linear_speed), float(angular_speed), float(sleep_time),
                       self.timer, self.island, self.prev_awake, self.next_island)
