"""The contact hard cases of scenes/, each held to a stated bound.

| case | bound |
|---|---|
| box_resting: a box on the floor, 10 s | moves < 1 mm (also with sleep off, 2 s) |
| box_stack_10: ten boxes stacked, 10 s | every box within 3 mm of where it started (sleep off: 2 s) |
| pyramid_10: 55 boxes, base 10, 5 s | every box within 2 mm |
| mass_ratio_100: 100 kg box on 1 kg boxes, 5 s | sinks < slop + 1 mm, light boxes pushed out < 2 mm |
| bullet_wall: 500 m/s, r 5 mm, 1 cm wall | 0 tunnels in 100 randomised trials (and tunnels with ccd off) |
| overlapping_spawn: boxes and balls spawned overlapping | apart within 1 s, never faster than 0.05 m/s |
| coincident_spheres: same centre | apart along the fixed normal, speed exactly 0 |
| head_on: relative velocity along n | closed-form velocities, nothing sideways, momentum to round-off |
"""
import hashlib
import os

import numpy as np
import pytest
import yaml

from physics_core import load_scene

pytestmark = pytest.mark.filterwarnings("ignore:.*fallback")
SCENES = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scenes")


def scene(name, **contacts):
    with open(os.path.join(SCENES, name + ".yaml"), encoding="utf-8") as f:
        data = yaml.safe_load(f)
    data["effects"]["contacts"].update(contacts)
    return data


def run(data, seconds):
    w = load_scene(data)
    p0 = w.state.pos.copy()
    w.step(round(seconds / w.dt))
    dyn = ~w.model.is_static
    return w, np.abs(w.state.pos - p0)[dyn].max()


def test_box_resting_on_the_floor_does_not_drift():
    w, drift = run(scene("box_resting"), 10.0)
    assert drift < 1e-3
    assert not w.state.awake[1]                 # and it fell asleep


def test_box_resting_without_sleep_does_not_jitter():
    w, drift = run(scene("box_resting", sleep=False), 2.0)
    assert drift < 1e-3
    assert np.abs(w.state.vel).max() < 1e-3


def test_stack_of_ten_boxes_stands_for_ten_seconds():
    w, drift = run(scene("box_stack_10"), 10.0)
    assert drift < 3e-3


def test_stack_of_ten_boxes_stands_without_sleep():
    w, drift = run(scene("box_stack_10", sleep=False), 2.0)
    assert drift < 3e-3
    assert np.abs(w.state.vel).max() < 0.02


def test_pyramid_with_a_base_of_ten_stands():
    w, drift = run(scene("pyramid_10"), 5.0)
    assert drift < 2e-3


def test_heavy_box_on_light_boxes_is_held_up():
    data = scene("mass_ratio_100")
    w = load_scene(data)
    p0 = w.state.pos.copy()
    w.step(round(5.0 / w.dt))
    heavy = w.model.index["heavy"]
    light = [w.model.index[f"light{j}"] for j in range(3)]
    slop = w.model.effects["contacts"].slop
    assert p0[heavy, 2] - w.state.pos[heavy, 2] < slop + 1e-3
    assert np.abs(w.state.pos[light, :2] - p0[light, :2]).max() < 2e-3


def _bullet_trial(rng, ccd=True):
    data = scene("bullet_wall", ccd=ccd)
    bullet = data["bodies"][1]
    speed = 500.0
    angle = rng.uniform(0.0, np.radians(30.0))          # up to 30° off the wall's normal
    turn = rng.uniform(0.0, 2 * np.pi)
    d = np.array([np.cos(angle), np.sin(angle) * np.cos(turn), np.sin(angle) * np.sin(turn)])
    # start anywhere along one step's travel before the wall, aimed inside it
    start = -rng.uniform(0.05, 0.05 + speed * data["dt"]) * d + np.array([0.0, *rng.uniform(-0.5, 0.5, 2)])
    bullet["position"] = start.tolist()
    bullet["velocity"] = (speed * d).tolist()
    bullet["angular_velocity"] = rng.uniform(-50, 50, 3).tolist()
    w = load_scene(data)
    w.step(4)
    return w.body("bullet").position[0] > 0.0, w


def test_fast_bullet_never_tunnels_through_a_thin_wall():
    rng = np.random.default_rng(2024)
    results = [_bullet_trial(rng) for _ in range(100)]
    tunnels = sum(t for t, _ in results)
    assert tunnels == 0
    for _, w in results:
        v = w.body("bullet").velocity
        assert v[0] < 0.0                              # bounced back off the wall
        assert np.all(np.isfinite(v))


def test_the_bullet_case_needs_time_of_impact():
    rng = np.random.default_rng(7)
    assert sum(_bullet_trial(rng, ccd=False)[0] for _ in range(10)) >= 8


def test_overlapping_spawns_separate_without_gaining_speed():
    data = scene("overlapping_spawn")
    w = load_scene(data)
    names = ["box_a", "box_b", "ball_a", "ball_b"]
    idx = [w.model.index[n] for n in names]
    vmax = 0.0
    for _ in range(240):
        w.step()
        vmax = max(vmax, float(np.abs(w.state.vel[idx]).max()))
    slop = w.model.effects["contacts"].slop
    pos = {n: w.body(n).position for n in names}
    assert pos["box_b"][0] - pos["box_a"][0] > 0.5 - slop - 1e-3
    assert np.linalg.norm(pos["ball_b"] - pos["ball_a"]) > 0.4 - slop - 1e-3
    assert vmax < 0.05


def test_coincident_sphere_centres_separate_along_the_fixed_normal():
    w = load_scene(scene("coincident_spheres"))
    w.step(240)
    a, b = w.body("ball_a"), w.body("ball_b")
    assert np.all(np.isfinite(w.state.pos))
    d = b.position - a.position
    assert d[2] > 0.2 - w.model.effects["contacts"].slop - 1e-3
    np.testing.assert_array_equal(d[:2], 0.0)
    assert np.abs(w.state.vel).max() == 0.0       # pushed apart in position only
    np.testing.assert_allclose(w.momentum(), 0.0, atol=1e-15)


def test_head_on_hit_is_exact_and_has_no_sideways_motion():
    w = load_scene(scene("head_on"))
    p0 = w.momentum()
    w.step(240)
    m1, m2, v1, v2, e = 1.0, 3.0, 2.0, -1.0, 0.9
    p = m1 * v1 + m2 * v2
    assert w.body("ball_a").velocity[0] == pytest.approx((p + m2 * e * (v2 - v1)) / (m1 + m2), abs=1e-12)
    assert w.body("ball_b").velocity[0] == pytest.approx((p + m1 * e * (v1 - v2)) / (m1 + m2), abs=1e-12)
    assert np.all(w.state.vel[:, 1:] == 0.0) and np.all(w.state.omega == 0.0)
    np.testing.assert_allclose(w.momentum(), p0, atol=1e-14)


def _state_hash(w):
    h = hashlib.sha256()
    for a in (w.state.pos, w.state.quat, w.state.vel, w.state.omega):
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


def test_same_scene_same_result_bit_for_bit():
    hashes = []
    for _ in range(2):
        w = load_scene(scene("pyramid_10", sleep=False))
        w.step(30)
        hashes.append(_state_hash(w))
    assert hashes[0] == hashes[1]
