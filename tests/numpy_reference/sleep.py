"""Sleeping bodies: a body at rest leaves the solver until something touches it.

Per body, a timer counts how long its speed has stayed under
`sleep_linear_speed` and its spin under `sleep_angular_speed`. Bodies in
touch form islands (connected components of the contact graph between awake
moving bodies; static and sleeping bodies do not link them, as in Box2D). An
island whose every body rested `sleep_time` goes to sleep together: velocities
zeroed, awake = False, so World.inv_mass and inv_inertia are zero for it and
the integrator and solver leave it in place.

Waking: a sleeping body touched by an awake body that is not itself at rest
wakes with its whole island; World.wake (any command) wakes one body, which
then wakes its neighbours the same way if it moves.
"""
import numpy as np


class SleepState:
    def __init__(self, n):
        self.timer = np.zeros(n)
        self.island = np.full(n, -1, dtype=np.int64)
        self.prev_awake = np.ones(n, dtype=bool)
        self.next_island = 0

    def sync(self, awake):
        """Bodies woken from outside (World.wake by a command) start a fresh timer."""
        woken = awake & ~self.prev_awake
        if woken.any():
            self.timer[woken] = 0.0
            self.island[woken] = -1
        self.prev_awake = awake.copy()


def islands(n, a, b):
    """(n,) label per body: the lowest body index of its connected component
    over edges (a, b). Hook the larger root under the smaller, then jump
    pointers until every body points at its root."""
    parent = np.arange(n)
    while len(a):
        ra, rb = parent[a], parent[b]
        differ = ra != rb
        if not differ.any():
            break
        ra, rb = ra[differ], rb[differ]
        np.minimum.at(parent, np.maximum(ra, rb), np.minimum(ra, rb))
        while True:
            pp = parent[parent]
            if np.array_equal(pp, parent):
                break
            parent = pp
    return parent


def wake_touched(world, sleep_state, a, b, depth, params):
    """Wake the islands of sleeping bodies that an awake, moving body touches.
    Returns True when some body woke (the caller refreshes the solver's masses)."""
    model, s = world.model, world.state
    awake = s.awake
    dyn = ~model.is_static
    asleep = dyn & ~awake
    if not asleep.any() or not len(a):
        return False
    mover = dyn & awake & (sleep_state.timer < params.sleep_time)
    touch = np.ones(len(a), bool)     # every row is within the contact margin
    hit_b = touch & mover[a] & asleep[b]
    hit_a = touch & mover[b] & asleep[a]
    if not (hit_a.any() or hit_b.any()):
        return False
    bodies = np.concatenate([b[hit_b], a[hit_a]])
    wake = asleep & np.isin(sleep_state.island, sleep_state.island[bodies])
    wake[bodies] = True
    s.awake[wake] = True
    sleep_state.timer[wake] = 0.0
    sleep_state.island[wake] = -1
    sleep_state.prev_awake = s.awake.copy()
    world.refresh_awake()
    return True


def update(world, sleep_state, edges_a, edges_b, dt, params):
    """Advance the rest timers by dt and put islands that rested long enough to sleep."""
    model, s = world.model, world.state
    sleep_state.sync(s.awake)
    active = ~model.is_static & s.awake
    if not active.any():
        return          # everything asleep (or static): no timer runs
    v2 = np.einsum("ij,ij->i", s.vel, s.vel)
    w2 = np.einsum("ij,ij->i", s.omega, s.omega)
    resting = (v2 < params.sleep_linear_speed ** 2) & (w2 < params.sleep_angular_speed ** 2)
    t = sleep_state.timer
    t[:] = np.where(active & resting, t + dt, np.where(active, 0.0, t))
    ready = active & (t >= params.sleep_time)
    if not ready.any():
        return
    n = model.n
    link = active[edges_a] & active[edges_b]
    label = islands(n, edges_a[link], edges_b[link])
    slowest = np.full(n, np.inf)
    np.minimum.at(slowest, label[active], t[active])
    sleepers = active & (slowest[label] >= params.sleep_time)
    if not sleepers.any():
        return
    s.awake[sleepers] = False
    s.vel[sleepers] = 0.0
    s.omega[sleepers] = 0.0
    sleep_state.island[sleepers] = sleep_state.next_island + label[sleepers]
    sleep_state.next_island += n
    sleep_state.prev_awake = s.awake.copy()
    world.refresh_awake()
