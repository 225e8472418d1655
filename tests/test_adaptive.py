"""Error-controlled integration (`integrator: adaptive`, physics_core/adaptive.py).

On the closed-form problems of `physics-bench accuracy` (benchmarks/problems.py:
the e = 0.9 Kepler orbit, the damped oscillator, the quadratic-drag fall and a
k = 1e6 N/m spring), each in that problem's own relative error norm (phase-space
distance in units of the amplitude for the oscillators, fallen distance in
v_t²/g and speed in v_t for the fall, |Δr| / a for the orbit):

- the final error is within the requested accuracy, 1e-3 … 1e-9, with no factor
  of our own in the assertion (the engine's stated LOCAL_SHARE = 1e-4 is how it
  gets there: accuracy_params.py);
- the internal steps grow as the tolerance tightens, at the rate of a
  fifth-order method (steps ∝ tol^(−1/5));
- the output grid stays dt; the run is bit-exact however world.step(n) is
  chunked, with commands and a reset between steps (what replay re-does).
"""
import hashlib
import math

import numpy as np
import pytest

from benchmarks import problems as P
from physics_core import SceneError, load_scene
from physics_core.accuracy_params import LOCAL_SHARE
from physics_scenes import scene, sphere

TOLERANCES = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9)
# (problem, output step dt, simulated time): output steps coarse enough that
# the error control, not the dt grid, decides the internal steps
CASES = {
    "kepler_e09": (P.ECCENTRIC, P.KEPLER_PERIOD / 16, P.KEPLER_PERIOD),   # one orbit from periapsis
    "damped": (P.DAMPED, 0.25, 5.0),                                      # five periods, ζ = 0.1
    "drag_fall": (P.DRAG_FALL, 0.5, 4.0),                                 # to ~0.9 v_t
    "stiff_spring": (P.STIFF, 1.0 / 240.0, 0.2),                          # ~32 periods, ω dt ≈ 4.2
}


def adaptive_run(key, tolerance, method="dormand_prince"):
    problem, dt, duration = CASES[key]
    spec = problem.build("adaptive", dt, 1)
    spec["accuracy"] = {"relative": tolerance, "method": method}
    world = load_scene(spec)
    world.step(round(duration / dt))
    return problem, world


@pytest.mark.parametrize("tolerance", TOLERANCES)
@pytest.mark.parametrize("key", CASES)
def test_final_error_is_within_the_requested_accuracy(key, tolerance):
    problem, world = adaptive_run(key, tolerance)
    assert world.time == pytest.approx(CASES[key][2], rel=1e-12)     # still on the dt grid
    error = problem.error(world)
    assert error <= tolerance, f"{key}: error {error:.3g} for accuracy {tolerance:g}"
    stats = world.integration_stats
    assert stats["steps_at_min_step"] == 0
    assert 0.0 < stats["max_local_error"] <= 1.0


@pytest.mark.parametrize("key", ["kepler_e09", "stiff_spring"])
def test_internal_steps_grow_as_the_tolerance_tightens(key):
    """Where the error control sets the step (not dt): strictly more internal
    steps for each tighter decade, and from 1e-5 to 1e-9 the count grows like
    tol^(−1/5) (Dormand–Prince: local error ∝ h⁵), the log–log slope within
    0.15 … 0.3."""
    steps = [adaptive_run(key, tol)[1].integration_stats["internal_steps"] for tol in TOLERANCES]
    assert all(b > a for a, b in zip(steps, steps[1:])), steps
    slope = math.log(steps[-1] / steps[2]) / math.log(1e-5 / 1e-9)
    assert 0.15 <= slope <= 0.3, (slope, steps)


def test_the_third_order_pair_takes_more_steps_at_a_tight_tolerance():
    """Bogacki–Shampine 3(2) meets the same accuracy with steps ∝ tol^(−1/3):
    at 1e-7 on the eccentric orbit it needs several times the steps of
    Dormand–Prince 5(4)."""
    problem, bs = adaptive_run("kepler_e09", 1e-7, method="bogacki_shampine")
    _, dp = adaptive_run("kepler_e09", 1e-7)
    assert problem.error(bs) <= 1e-7
    assert bs.integration_stats["internal_steps"] > 3 * dp.integration_stats["internal_steps"]


def test_adaptive_steps_concentrate_at_periapsis():
    """On the e = 0.9 orbit the smallest internal step (near periapsis, r = 0.1)
    is far below the largest (near apoapsis, r = 1.9): the point of error control."""
    _, world = adaptive_run("kepler_e09", 1e-6)
    s = world.integration_stats
    assert s["largest_step_s"] > 20 * s["smallest_step_s"]
    assert s["largest_step_s"] <= P.KEPLER_PERIOD / 16


# ---- statistics ----------------------------------------------------------------

def test_statistics_per_step_and_cumulative():
    problem, dt, _ = CASES["stiff_spring"]
    spec = problem.build("adaptive", dt, 1)
    spec["accuracy"] = 1e-6
    world = load_scene(spec)
    assert world.integration_stats["internal_steps"] == 0
    world.step(10)
    total = world.integration_stats
    last = world.last_step_integration_stats
    assert last["internal_steps"] == pytest.approx(total["internal_steps"] / 10)
    world.step(1)
    one = world.last_step_integration_stats
    assert world.integration_stats["internal_steps"] == total["internal_steps"] + one["internal_steps"]
    # ω = 1000 rad/s: a stable explicit step is ≲ 3/ω, so several per 1/240 s step
    assert one["internal_steps"] >= 2
    assert one["smallest_step_s"] <= one["largest_step_s"] <= dt
    # each accepted step costs 6 evaluations (FSAL), plus one first slope per
    # output step and 6 per rejected try
    s = world.integration_stats
    assert s["force_evaluations"] == 6 * (s["internal_steps"] + s["rejected_steps"]) + 11


def test_fixed_step_worlds_report_no_integration_statistics():
    world = load_scene(scene(sphere(), integrator="rk4"))
    world.step(3)
    assert world.integration_stats == {} and world.last_step_integration_stats == {}


def test_a_min_step_above_what_the_tolerance_needs_is_counted_not_fatal():
    """min_step = max_step = dt on the stiff spring: every internal step is
    forced at min_step above the tolerance; the run goes on and counts them."""
    problem, dt, _ = CASES["stiff_spring"]
    spec = problem.build("adaptive", dt / 8, 1)
    spec["accuracy"] = {"relative": 1e-6, "min_step": dt / 8, "max_step": dt / 8}
    world = load_scene(spec)
    world.step(20)
    s = world.integration_stats
    assert s["internal_steps"] == 20 and s["steps_at_min_step"] == 20
    assert s["max_local_error"] > 1.0
    assert np.all(np.isfinite(world.state.pos))


# ---- contacts ------------------------------------------------------------------

def _bouncing(integrator, substeps):
    ground = {"name": "ground", "shape": {"type": "plane"}, "static": True, "material": "steel"}
    ball = sphere("ball", radius=0.1, mass=1.0, position=(0.0, 0.0, 1.0), restitution=0.8,
                  velocity=[0.3, 0.0, 0.0], material="steel")
    return scene(ground, ball, integrator=integrator, gravity="earth", dt=1 / 120,
                 substeps=substeps, effects={"contacts": {}})


def test_contacts_with_adaptive_steps_match_rk4_through_bounces():
    """Free flight under gravity is a parabola, which both RK4 and Dormand–Prince
    integrate exactly; the contact stages run on the same substeps for both, so
    the adaptive run bounces where RK4 does (positions within 1e-9 m over 2 s and
    several bounces) and reports the same begin events."""
    adaptive = load_scene(_bouncing("adaptive", 4))
    fixed = load_scene(_bouncing("rk4", 4))
    begins = 0
    for _ in range(240):
        adaptive.step()
        fixed.step()
        assert np.allclose(adaptive.state.pos, fixed.state.pos, rtol=0, atol=1e-9)
        a_events = adaptive.contacts.event.tolist()
        assert a_events == fixed.contacts.event.tolist()
        begins += a_events.count(0)
    assert begins >= 3
    # no internal step crosses a contact substep
    assert adaptive.integration_stats["largest_step_s"] <= (1 / 120) / 4 * (1 + 1e-12)


# ---- determinism -----------------------------------------------------------------

def _digest(world):
    s = world.state
    h = hashlib.sha256()
    for a in (s.pos, s.quat, s.vel, s.omega):
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


def _session(world, chunks):
    """The same commands at the same steps, stepped in the given chunk sizes."""
    plan = {5: lambda w: w.apply_force("planet", [0.0, 1e-4, 0.0]),
            9: lambda w: w.apply_impulse("planet", [1e-4, 0.0, 0.0]),
            14: lambda w: w.reset(),
            17: lambda w: w.apply_torque("planet", [0.0, 0.0, 1e-6])}
    done, i = 0, 0
    while done < 30:
        if done in plan:
            plan[done](world)
        k = min(chunks[i % len(chunks)], 30 - done, min((s for s in plan if s > done), default=30) - done)
        world.step(k)
        done += k
        i += 1
    return _digest(world), world.integration_stats


def test_an_adaptive_session_is_bit_exact_however_it_is_stepped():
    """Replay and --resimulate re-run the recorded commands at their steps in
    their own chunking: the internal steps, statistics and bits must not depend
    on it (nor on a reset in the middle)."""
    spec = P.ECCENTRIC.build("adaptive", P.KEPLER_PERIOD / 32, 1)
    spec["accuracy"] = 1e-7
    one_by_one = _session(load_scene(spec), [1])
    chunked = _session(load_scene(spec), [7, 3, 2])
    assert one_by_one == chunked


# ---- scene keys --------------------------------------------------------------------

def _spec(**top):
    """A one-ball scene at dt = 0.01 s with these top-level keys (no integrator unless given)."""
    return {"dt": 0.01, "bodies": [sphere()], **top}


@pytest.mark.parametrize("top, path", [
    ({"integrator": "rk4", "accuracy": 1e-6}, "accuracy"),
    ({"accuracy": 0.5}, "accuracy"),
    ({"accuracy": 1e-12}, "accuracy"),
    ({"accuracy": "tight"}, "accuracy"),
    ({"accuracy": {"relative": -1.0}}, "accuracy.relative"),
    ({"accuracy": {"tolerance": 1e-6}}, "accuracy.tolerance"),
    ({"accuracy": {"absolute": {"speed": 1e-6}}}, "accuracy.absolute.speed"),
    ({"accuracy": {"absolute": {"position": 0.0}}}, "accuracy.absolute.position"),
    ({"accuracy": {"max_step": 0.02}}, "accuracy.max_step"),
    ({"accuracy": {"max_step": 0.001, "min_step": 0.002}}, "accuracy.min_step"),
    ({"accuracy": {"min_step": 0.0}}, "accuracy.min_step"),
    ({"accuracy": {"method": "rk45"}}, "accuracy.method"),
])
def test_bad_accuracy_keys_are_refused_naming_the_key(top, path):
    with pytest.raises(SceneError) as e:
        load_scene(_spec(**top))
    assert e.value.path == path, str(e.value)


def test_accuracy_alone_means_adaptive_and_a_number_sets_every_tolerance():
    world = load_scene(_spec(accuracy=1e-5))
    a = world.model.accuracy
    assert world.model.integrator == "adaptive"
    assert (a.relative, a.position, a.velocity, a.orientation, a.angular_velocity) == (1e-5,) * 5
    assert a.max_step == 0.01 and a.min_step == pytest.approx(1e-8)
    assert a.method == "dormand_prince"
    assert LOCAL_SHARE == 1e-4
    default = load_scene(_spec(integrator="adaptive")).model.accuracy
    assert default.relative == 1e-6
    assert load_scene(_spec(integrator="rk4")).model.accuracy is None
