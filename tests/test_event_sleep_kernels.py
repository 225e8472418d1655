"""The compiled contact events (event_log: the EventLog wrapper and the
state kernels called from compiled code) and sleep islands
(sleep_islands.SleepTimers) against the numpy originals (events.py, sleep.py)
on random sequences: the same events, timers, islands and awake masks."""
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numba import njit

from numpy_reference import sleep
from physics_core.collision import manifold
from physics_core.collision.event_log import (EventLog, events_add, events_bodies_changed,
                                              events_finish, events_output, events_reset,
                                              new_event_state)
from numpy_reference.events import EventAccumulator
from physics_core.collision.sleep_islands import SleepTimers
from physics_core.collision.warm_cache import remap_keys
from physics_core.contact_events import BEGIN, END, PERSIST, ContactEvents

SLOTS = 4


def bits(x):
    """An array's shape, dtype and bytes: equal means bit for bit equal (-0.0 ≠ 0.0)."""
    x = np.ascontiguousarray(x)
    return x.shape, x.dtype.str, x.tobytes()


def assert_same_events(got: ContactEvents, want: ContactEvents):
    for name, w in want.as_dict().items():
        g = getattr(got, name)
        assert bits(g) == bits(w), (name, g, w)


# ---- events ------------------------------------------------------------------

class Rows:
    """What EventAccumulator.add reads of a ContactRows."""

    def __init__(self, key, a, b, point, normal, depth, impulse_n, speed, key_sorted):
        k = len(key)
        self.key, self.a, self.b = key, a, b
        self.point, self.normal, self.depth = point, normal, depth
        self.lam = np.zeros((k, 3))
        self.lam[:, 0] = impulse_n
        self.u0 = np.zeros((k, 3))
        self.u0[:, 0] = -speed
        self.tangent = np.zeros((k, 2, 3))
        self.key_sorted = key_sorted

    def __len__(self):
        return len(self.key)


def substep_rows(rng, n, chosen, slots=SLOTS):
    """Random rows for the chosen (pair, slot) ids, in key order: some gaps,
    some pushed, some both or neither, signed zeros included."""
    chosen = sorted(chosen)
    k = len(chosen)
    pairs = [(i, j) for i in range(n) for j in range(i + 1, n)]     # in key order
    pair = [pairs[c // slots] for c in chosen]
    key = np.array([(i * n + j) * slots + c % slots for (i, j), c in zip(pair, chosen)],
                   dtype=np.int64)
    ab = np.array(pair, dtype=np.int64).reshape(k, 2)
    swap = rng.random(k) < 0.2          # a row's a, b may come in either order
    ab[swap] = ab[swap, ::-1]
    depth = rng.choice([-0.01, -0.0, 0.0, 0.002, 0.03], k) * rng.random(k)
    impulse = rng.choice([0.0, -0.0, 1.0, 1e-300], k) * rng.random(k) * 10.0
    friction = rng.standard_normal((k, 3)) * rng.choice([0.0, -0.0, 1e-8, 1.0, 1e8], (k, 1))
    speed = rng.standard_normal(k) * rng.choice([0.0, 1.0, 100.0], k)
    return dict(key=key, a=ab[:, 0].copy(), b=ab[:, 1].copy(),
                point=rng.standard_normal((k, 3)), normal=rng.standard_normal((k, 3)),
                depth=depth, impulse_n=impulse, friction=friction, speed=speed)


@njit
def compiled_step(state, starts, key, a, b, point, normal, depth, impulse_n, friction, speed,
                  moving):
    """One step in compiled code: substep s is rows starts[s]:starts[s + 1]."""
    events_reset(state)
    for s in range(len(starts) - 1):
        r = slice(starts[s], starts[s + 1])
        events_add(state, key[r], a[r], b[r], point[r], normal[r], depth[r], impulse_n[r],
                   friction[r], speed[r])
    events_finish(state, moving)


def no_rows():
    return substep_rows(np.random.default_rng(0), 2, [])


def stacked(substeps):
    """The substeps' rows one after the other, and where each starts."""
    starts = np.cumsum([0] + [len(r["key"]) for r in substeps]).astype(np.int64)
    empty = no_rows()
    cols = {name: np.concatenate([r[name] for r in substeps] + [empty[name]])
            for name in empty}
    return starts, cols


def run_compiled_step(state, substeps, moving):
    starts, c = stacked(substeps)
    compiled_step(state, starts, c["key"], c["a"], c["b"], c["point"], c["normal"], c["depth"],
                  c["impulse_n"], c["friction"], c["speed"], moving)
    return events_output(state)


def feed_step(acc, log, rng, n, substeps, moving, keep_sorted, state=None, slots=SLOTS):
    """(accumulator's, EventLog's, compiled kernels' events) of one step."""
    acc.reset()
    log.reset()
    rows = [substep_rows(rng, n, ids, slots) for ids in substeps]
    for r in rows:
        acc.add(Rows(r["key"], r["a"], r["b"], r["point"], r["normal"], r["depth"],
                     r["impulse_n"], r["speed"], keep_sorted), r["friction"])
        log.add(**r)
    compiled = None if state is None else run_compiled_step(state, rows, moving)
    return acc.finish(moving), log.finish(moving), compiled


@st.composite
def event_runs(draw):
    n = draw(st.integers(2, 5))
    ids = st.sets(st.integers(0, n * (n - 1) // 2 * SLOTS - 1), max_size=12)
    steps = draw(st.lists(st.tuples(st.lists(ids, min_size=0, max_size=4),
                                    st.lists(st.booleans(), min_size=n, max_size=n)),
                          min_size=1, max_size=12))
    return n, steps, draw(st.integers(0, 2 ** 32 - 1)), draw(st.booleans())


@settings(max_examples=300, deadline=None)
@given(event_runs())
def test_event_log_gives_the_accumulators_events(run):
    n, steps, seed, key_sorted = run
    rng = np.random.default_rng(seed)
    acc, log = EventAccumulator(), EventLog(capacity=1)    # capacity 1: grows on the way
    state = new_event_state(1)
    for substeps, moving in steps:
        moving = np.array(moving)
        moving[0] = False                  # body 0 is static
        want, got, compiled = feed_step(acc, log, rng, n, substeps, moving, key_sorted, state)
        assert_same_events(got, want)
        assert_same_events(compiled, want)
        assert_remembered(log, acc.prev)
        assert_remembered(EventLog(state=state), acc.prev)


def assert_remembered(log, prev):
    kept = log.remembered()
    if prev is None:
        assert len(kept["key"]) == 0
    else:
        for name in kept:
            assert bits(kept[name]) == bits(prev[name]), name


def touching_rows(key, a, b):
    k = len(key)
    z = np.zeros((k, 3))
    return dict(key=np.array(key, dtype=np.int64), a=np.array(a, dtype=np.int64),
                b=np.array(b, dtype=np.int64), point=z, normal=z, depth=np.full(k, 0.001),
                impulse_n=np.full(k, 0.5), friction=z, speed=np.zeros(k))


def test_contacts_freeze_while_asleep_and_persist_when_woken():
    log = EventLog()
    floor_box, box_box = touching_rows([1], [0], [1]), touching_rows([1, 9], [0, 1], [1, 2])
    awake, asleep = np.array([False, True, True]), np.array([False, False, False])
    seen = []
    for rows, moving in [(box_box, awake), (None, asleep), (None, asleep),
                         (floor_box, awake), (None, awake)]:
        log.reset()
        if rows is not None:
            log.add(**rows)
        ev = log.finish(moving)
        seen.append((list(ev.event), list(ev.body_b)))
    assert seen == [([BEGIN, BEGIN], [1, 2]),
                    ([], []), ([], []),                    # frozen: nothing reported
                    ([PERSIST, END], [1, 2]),              # woken: one persists, one ends
                    ([END], [1])]


def test_resting_contacts_persist_with_summed_impulses():
    log = EventLog()
    key = np.array([8, 9], dtype=np.int64)
    ab = np.array([0, 0], dtype=np.int64), np.array([1, 1], dtype=np.int64)
    pts = np.zeros((2, 3))
    moving = np.array([False, True])
    for step in range(3):
        log.reset()
        for _ in range(4):
            log.add(key, *ab, pts, pts, np.full(2, 0.001), np.full(2, 0.25),
                    np.tile([3.0, 0.0, 4.0], (2, 1)), np.array([1.0, 2.0]))
        ev = log.finish(moving)
        np.testing.assert_array_equal(ev.event, [BEGIN if step == 0 else PERSIST] * 2)
        np.testing.assert_array_equal(ev.impulse, [1.0, 1.0])
        np.testing.assert_array_equal(ev.friction_impulse, [20.0, 20.0])
        np.testing.assert_array_equal(ev.normal_speed, [1.0, 2.0])
    log.reset()
    ev = log.finish(moving)
    np.testing.assert_array_equal(ev.event, [END, END])
    log.reset()
    assert len(log.finish(moving)) == 0


def test_unsorted_keys_are_refused():
    log = EventLog()
    z = np.zeros((2, 3))
    with pytest.raises(ValueError):
        log.add(np.array([5, 3]), np.zeros(2, np.int64), np.ones(2, np.int64), z, z,
                np.zeros(2), np.ones(2), z, np.zeros(2))


# ---- the compiled entry points: body changes, growth, persistence -------------

def remap_accumulator(acc, n_old, n_new, new_index):
    """What EventLog.bodies_changed does, on the accumulator's remembered
    contacts (numpy, the reference): renumbered, and the ContactEvents of the
    removed bodies' contacts (None if there are none)."""
    prev = acc.prev
    if prev is None:
        return None
    key, kept = remap_keys(prev["key"].copy(), n_old, n_new, new_index, manifold.SLOTS)
    prev = dict(prev, key=key, a=new_index[prev["a"]], b=new_index[prev["b"]])
    acc.prev = {name: v[kept] for name, v in prev.items()} if kept.any() else None
    gone = ~kept
    if not gone.any():
        return None
    z = np.zeros(int(gone.sum()))
    return ContactEvents(point=prev["point"][gone], normal=prev["normal"][gone], impulse=z,
                         friction_impulse=z, normal_speed=z, depth=prev["depth"][gone],
                         body_a=prev["a"][gone], body_b=prev["b"][gone],
                         event=np.full(len(z), END, np.uint8))


def joined(parts):
    parts = [e for e in parts if len(e)]
    if not parts:
        return ContactEvents.empty()
    return ContactEvents(**{name: np.concatenate([getattr(e, name) for e in parts])
                            for name in parts[0].as_dict()})


def body_change(rng, n):
    """(n_new, new_index): one body removed (at least two stay) or one added."""
    if n > 2 and rng.random() < 0.7:
        i = int(rng.integers(n))
        new_index = np.arange(n) - (np.arange(n) > i)
        new_index[i] = -1
        return n - 1, new_index
    return n + 1, np.arange(n)


@settings(max_examples=150, deadline=None)
@given(st.integers(2, 6), st.integers(0, 2 ** 32 - 1), st.integers(1, 14), st.booleans())
def test_removed_bodies_contacts_end_at_the_next_step(n, seed, steps, key_sorted):
    """Random steps with bodies removed and added between them (sometimes two
    changes in a row): EventLog and the compiled kernels (both from capacity
    1) report the accumulator's events, then the removed bodies' ends."""
    rng = np.random.default_rng(seed)
    acc, log, state = EventAccumulator(), EventLog(capacity=1), new_event_state(1)
    pending = []
    for _ in range(steps):
        while rng.random() < 0.4:
            n_old = n
            n, new_index = body_change(rng, n)
            pending.append(remap_accumulator(acc, n_old, n, new_index))
            log.bodies_changed(n_old, n, new_index)
            events_bodies_changed(state, n_old, n, new_index)
        moving = rng.random(n) < 0.7
        pairs = n * (n - 1) // 2 * manifold.SLOTS
        substeps = [rng.choice(pairs, int(rng.integers(0, min(pairs, 10) + 1)), replace=False)
                    for _ in range(int(rng.integers(0, 4)))]
        want, got, compiled = feed_step(acc, log, rng, n, substeps, moving, key_sorted, state,
                                        slots=manifold.SLOTS)
        want = joined([want] + [e for e in pending if e is not None])
        pending = []
        assert_same_events(got, want)
        assert_same_events(compiled, want)
        assert_remembered(log, acc.prev)
        assert_remembered(EventLog(state=state), acc.prev)


def test_a_removed_body_gets_minus_one_in_its_contacts_ends():
    log = EventLog(capacity=1)
    n = 4
    key = manifold.SLOTS * np.array([0 * n + 1, 1 * n + 2, 2 * n + 3], dtype=np.int64)
    rows = touching_rows(key, [0, 1, 2], [1, 2, 3])
    moving = np.array([False, True, True, True])
    log.reset()
    log.add(**rows)
    assert list(log.finish(moving).event) == [BEGIN] * 3
    new_index = np.array([0, 1, -1, 2])                 # body 2 removed
    log.bodies_changed(4, 3, new_index)
    log.reset()
    log.add(**touching_rows([manifold.SLOTS], [0], [1]))   # 0-1 goes on touching
    ev = log.finish(moving[:3])
    assert list(ev.event) == [PERSIST, END, END]
    assert list(ev.body_a) == [0, 1, -1] and list(ev.body_b) == [1, -1, 2]
    np.testing.assert_array_equal(log.remembered()["key"], [manifold.SLOTS])
    log.reset()
    assert list(log.finish(moving[:3]).event) == [END]      # reported once


@njit
def resting_steps(state, steps, substeps, key, a, b, point, normal, depth, impulse_n, friction,
                  speed, moving):
    """Steps of a resting scene, all in one compiled call."""
    for _ in range(steps):
        events_reset(state)
        for _ in range(substeps):
            events_add(state, key, a, b, point, normal, depth, impulse_n, friction, speed)
        events_finish(state, moving)


def resting_rows(n, k):
    rng = np.random.default_rng(3)
    r = substep_rows(rng, n, rng.choice(n * (n - 1) // 2 * SLOTS, k, replace=False))
    r["depth"] = np.abs(r["depth"])                     # all touch
    return r


def test_a_compiled_loop_keeps_the_state_between_steps_and_calls():
    """The buffers grow from capacity 1 inside compiled code and the Python
    side sees the grown ones; a second call goes on from the first."""
    n, k = 6, 40
    moving = np.array([False] + [True] * (n - 1))
    r = resting_rows(n, k)
    log, state = EventLog(capacity=1), new_event_state(1)
    for call in range(2):
        for _ in range(3):
            log.reset()
            for _ in range(4):
                log.add(**r)
            want = log.finish(moving)
        resting_steps(state, 3, 4, *r.values(), moving)
        assert_same_events(events_output(state), want)
    assert len(want) == k and np.all(want.event == PERSIST)
    assert len(state[0][0]) >= 4 * k and state[2][1] == k   # grown in compiled code, seen here


def test_output_copies_stay_valid_after_the_next_step():
    moving = np.ones(4, bool)
    state = new_event_state(1)
    resting_steps(state, 1, 2, *resting_rows(4, 10).values(), moving)
    got = events_output(state)
    before = {name: v.copy() for name, v in got.as_dict().items()}
    resting_steps(state, 1, 1, *no_rows().values(), moving)    # all end: buffers rewritten
    assert np.all(events_output(state).event == END)
    assert_same_events(got, ContactEvents(**before))


@njit
def add_in_compiled_code(state, key, a, b, point, normal, depth, impulse_n, friction, speed):
    events_add(state, key, a, b, point, normal, depth, impulse_n, friction, speed)


def test_compiled_add_refuses_bad_rows():
    state, z = new_event_state(), np.zeros((2, 3))
    zi, one = np.zeros(2, np.int64), np.ones(2, np.int64)
    with pytest.raises(ValueError, match="ascending"):
        add_in_compiled_code(state, np.array([5, 3]), zi, one, z, z, np.zeros(2), np.ones(2), z,
                             np.zeros(2))
    with pytest.raises(ValueError, match="lengths"):
        add_in_compiled_code(state, np.array([1, 2]), zi, one[:1], z, z, np.zeros(2),
                             np.ones(2), z, np.zeros(2))
    assert state[2][0] == 0                             # nothing was gathered


def test_no_events_give_the_shared_empty_events():
    state = new_event_state()
    resting_steps(state, 1, 1, *no_rows().values(), np.ones(2, bool))
    assert events_output(state) is EventLog().finish(np.ones(2, bool))
    assert len(events_output(state)) == 0


# ---- sleep -------------------------------------------------------------------

class World:
    """What sleep.py reads of a World."""

    def __init__(self, is_static, awake, vel, omega):
        self.model = SimpleNamespace(is_static=is_static, n=len(is_static))
        self.state = SimpleNamespace(awake=awake, vel=vel, omega=omega)
        self.refreshed = 0

    def refresh_awake(self):
        self.refreshed += 1


PARAMS = dict(sleep_linear_speed=0.05, sleep_angular_speed=0.1)


def random_edges(rng, n, count):
    a = rng.integers(0, n, count)
    b = rng.integers(0, n, count)
    keep = a != b
    return a[keep].astype(np.int64), b[keep].astype(np.int64)


def random_speeds(rng, n, rest):
    """Velocities: most bodies under the thresholds (some right at them)."""
    scale = np.where(rng.random(n) < rest, rng.choice([0.0, 0.01, 0.028, 0.0288675], n), 1.0)
    vel = rng.standard_normal((n, 3)) * scale[:, None]
    vel[rng.random(n) < 0.1] = [0.05, 0.0, 0.0]            # exactly at the limit: moving
    omega = rng.standard_normal((n, 3)) * 0.05 * (rng.random(n) < rest)[:, None]
    return vel, omega


def assert_same_sleep(state, timers, world, awake, vel, omega):
    np.testing.assert_array_equal(awake, world.state.awake)
    assert bits(vel) == bits(world.state.vel) and bits(omega) == bits(world.state.omega)
    assert bits(timers.timer) == bits(state.timer)
    np.testing.assert_array_equal(timers.island, state.island)
    np.testing.assert_array_equal(timers.prev_awake, state.prev_awake)
    assert timers.next_island[0] == state.next_island


@settings(max_examples=200, deadline=None)
@given(st.integers(1, 14), st.integers(0, 2 ** 32 - 1), st.integers(1, 6),
       st.floats(0.5, 0.98), st.integers(1, 40))
def test_sleep_timers_match_sleep_py(n, seed, rest_steps, rest, steps):
    rng = np.random.default_rng(seed)
    dt = 1.0 / 240.0
    params = SimpleNamespace(sleep_time=rest_steps * dt, **PARAMS)
    is_static = rng.random(n) < 0.25
    world = World(is_static, np.ones(n, bool), np.zeros((n, 3)), np.zeros((n, 3)))
    state, timers = sleep.SleepState(n), SleepTimers(n)
    awake = np.ones(n, bool)
    for _ in range(steps):
        if rng.random() < 0.15:              # a command wakes a body (World.wake)
            i = rng.integers(n)
            awake[i] = world.state.awake[i] = True
        # collide: sync, then bodies in the margin wake the sleepers they touch
        state.sync(world.state.awake)
        timers.sync(awake)
        a, b = random_edges(rng, n, rng.integers(0, 2 * n + 1))
        before = world.refreshed
        woke = sleep.wake_touched(world, state, a, b, np.zeros(len(a)), params)
        assert timers.wake_touched(awake, is_static, a, b, params.sleep_time) == bool(woke)
        assert world.refreshed - before == int(bool(woke))
        assert_same_sleep(state, timers, world, awake, world.state.vel, world.state.omega)
        # the solve's velocities, then the last substep's sleep stage
        vel, omega = random_speeds(rng, n, rest)
        world.state.vel, world.state.omega = vel.copy(), omega.copy()
        ea, eb = random_edges(rng, n, rng.integers(0, 2 * n + 1))
        before = world.refreshed
        sleep.update(world, state, ea, eb, dt, params)
        slept = timers.update(awake, is_static, vel, omega, ea, eb, dt,
                              params.sleep_linear_speed, params.sleep_angular_speed,
                              params.sleep_time)
        assert slept == (world.refreshed > before)
        assert_same_sleep(state, timers, world, awake, vel, omega)


@settings(max_examples=200, deadline=None)
@given(st.integers(1, 30), st.integers(0, 2 ** 32 - 1))
def test_islands_are_sleep_pys_components(n, seed):
    from physics_core.collision.sleep_islands import _islands
    rng = np.random.default_rng(seed)
    a, b = random_edges(rng, n, rng.integers(0, 2 * n))
    active = rng.random(n) < 0.8
    link = active[a] & active[b]
    np.testing.assert_array_equal(_islands(active, a, b), sleep.islands(n, a[link], b[link]))


def test_a_resting_pile_sleeps_together_and_wakes_together():
    n = 4                                    # floor, and three boxes in a stack
    is_static = np.array([True, False, False, False])
    awake = np.ones(n, bool)
    vel, omega = np.zeros((n, 3)), np.zeros((n, 3))
    ea, eb = np.array([0, 1, 2]), np.array([1, 2, 3])
    timers = SleepTimers(n)
    vel[3] = [0.2, 0.0, 0.0]                 # the top box still slides: nobody sleeps
    for _ in range(10):
        assert not timers.update(awake, is_static, vel, omega, ea, eb, 0.1, 0.05, 0.1, 0.5)
    vel[3] = 0.0
    slept = [timers.update(awake, is_static, vel, omega, ea, eb, 0.1, 0.05, 0.1, 0.5)
             for _ in range(5)]
    assert slept == [False] * 4 + [True] and not awake[1:].any()
    np.testing.assert_array_equal(timers.island, [-1, 1, 1, 1])
    awake = np.append(awake, True)           # a fifth, falling body lands on the top box
    t5 = SleepTimers(5)
    t5.timer[:4], t5.island[:4], t5.prev_awake[:] = timers.timer, timers.island, awake
    assert t5.wake_touched(awake, np.append(is_static, False), np.array([3]), np.array([4]), 0.5)
    assert awake.all()


def test_rest_speed_is_summed_as_sleep_py_sums_it():
    """A speed whose squared length depends on the summation order, right at the
    threshold: the body rests or moves exactly as sleep.py decides."""
    rng = np.random.default_rng(7)
    for _ in range(100000):
        v = rng.standard_normal(3) * 0.03
        x, y, z = v * v
        e, s = (x + z) + y, (x + y) + z
        lin = np.sqrt(max(e, s))
        if e != s and lin * lin == max(e, s):
            break
    else:
        raise AssertionError("no speed at the threshold in 100,000 draws of seed 7")
    params = SimpleNamespace(sleep_time=2.5 / 240.0, sleep_linear_speed=lin,
                             sleep_angular_speed=1.0)
    is_static = np.array([True, False])
    vel = np.array([[0.0, 0.0, 0.0], v])
    world = World(is_static, np.ones(2, bool), vel.copy(), np.zeros((2, 3)))
    state, timers, awake = sleep.SleepState(2), SleepTimers(2), np.ones(2, bool)
    for _ in range(4):
        sleep.update(world, state, np.zeros(0, np.int64), np.zeros(0, np.int64), 1 / 240.0, params)
        timers.update(awake, is_static, vel, np.zeros((2, 3)), np.zeros(0, np.int64),
                      np.zeros(0, np.int64), 1 / 240.0, lin, 1.0, params.sleep_time)
        assert_same_sleep(state, timers, world, awake, vel, world.state.omega)


def test_arrays_of_another_world_are_refused():
    timers, z = SleepTimers(3), np.zeros(0, np.int64)
    with pytest.raises(ValueError):
        timers.update(np.ones(4, bool), np.zeros(4, bool), np.zeros((4, 3)), np.zeros((4, 3)),
                      z, z, 0.01, 0.1, 0.1, 0.5)
    with pytest.raises(ValueError):
        timers.wake_touched(np.ones(3, bool), np.zeros(3, bool), np.array([0]), np.array([3]), 0.5)
    log, p = EventLog(), np.zeros((2, 3))
    with pytest.raises(ValueError):
        log.add(np.array([1, 2]), np.zeros(2, np.int64), np.ones(1, np.int64), p, p,
                np.zeros(2), np.ones(2), p, np.zeros(2))


def test_a_body_deeper_than_the_slop_does_not_fall_asleep():
    """Regression (a body deeper than the slop fell asleep): position correction
    still pushes apart a contact deeper than twice the slop, so its bodies are
    not at rest whatever their velocity reads, and neither is their island.
    A floor (0), box 1 sunk 3 cm into it, box 2 resting on box 1 at the slop,
    box 3 alone on the floor 6 mm deep (under twice the slop of 5 mm); all
    with zero velocity. Box 3 sleeps after sleep_time; boxes 1 and 2 sleep
    only sleep_time after box 1 has been pushed out to under twice the slop."""
    from physics_core.collision.contact_layout import BODY_A, BODY_B, DEPTH, ICOL, NCOL
    from physics_core.collision.contact_stages import touching_edges, unsettled_bodies
    from physics_core.collision.sleep_islands import _update
    n, slop, dt, sleep_time = 4, 0.005, 0.1, 0.5
    R, I = np.zeros((3, NCOL)), np.zeros((3, ICOL), np.int64)
    I[:, BODY_A], I[:, BODY_B] = [0, 1, 0], [1, 2, 3]
    R[:, DEPTH] = [0.03, slop, 0.006]
    is_static = np.array([True, False, False, False])
    awake, vel, omega = np.ones(n, bool), np.zeros((n, 3)), np.zeros((n, 3))
    timers = SleepTimers(n)

    def step():
        ea, eb = touching_edges(R, I)
        return _update(awake, is_static, vel, omega, unsettled_bodies(R, I, n, slop), ea, eb, dt,
                       0.05, 0.1, sleep_time, timers.timer, timers.island, timers.prev_awake,
                       timers.next_island)

    np.testing.assert_array_equal(unsettled_bodies(R, I, n, slop), [True, True, False, False])
    for _ in range(10):                       # twice sleep_time, box 1 still 3 cm deep
        step()
    np.testing.assert_array_equal(awake, [True, True, True, False])
    assert timers.timer[1] == 0.0
    R[0, DEPTH] = 0.009                       # pushed out to under twice the slop
    slept = [step() for _ in range(5)]        # 5 dt = sleep_time
    assert slept == [False] * 4 + [True]
    np.testing.assert_array_equal(awake, [True, False, False, False])
