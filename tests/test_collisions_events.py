"""Contact events of a step (world.contacts): begin, persist, end, impulses."""
import numpy as np
import pytest

from physics_core import load_scene
from physics_core.contact_events import BEGIN, END, PERSIST

pytestmark = pytest.mark.filterwarnings("ignore:.*fallback")
G = 9.81


def drop_scene(substeps=1, **contacts):
    return {"dt": 1.0 / 240.0, "substeps": substeps, "gravity": [0, 0, -G],
            "effects": {"contacts": dict(sleep=False, **contacts)},
            "bodies": [{"name": "floor", "shape": {"type": "plane"}, "material": "steel"},
                       {"name": "box", "shape": {"type": "box", "half_extents": [0.2, 0.1, 0.05]},
                        "mass": 2.0, "material": "steel", "restitution": 0.0,
                        "position": [0, 0, 0.3]}]}


def test_a_landing_box_begins_persists_and_ends_its_contacts():
    w = load_scene(drop_scene())
    seen = []
    for _ in range(120):
        w.step()
        if len(w.contacts):
            seen.append(w.contacts)
    first = seen[0]
    assert np.all(first.event == BEGIN) and len(first) == 4          # four corners land flat
    assert np.all(first.body_a == 0) and np.all(first.body_b == 1)
    np.testing.assert_allclose(first.normal, [[0, 0, 1]] * 4)
    assert np.all(first.normal_speed > 2.0)                            # fell 0.25 m: ~2.2 m/s
    assert np.all(seen[-1].event == PERSIST)
    # resting: the floor carries the weight, m g dt per step
    assert seen[-1].impulse.sum() == pytest.approx(2.0 * G * w.dt, rel=1e-6)
    w.apply_impulse("box", [0, 0, 3.0])        # 1.5 m/s up: gone beyond the margin in a step
    w.step()
    assert np.all(w.contacts.event == END) and len(w.contacts) == 4
    assert np.all(w.contacts.impulse == 0.0)
    w.step()
    assert len(w.contacts) == 0


def test_impulses_add_up_over_substeps():
    w = load_scene(drop_scene(substeps=4))
    w.step(120)
    assert np.all(w.contacts.event == PERSIST)
    assert w.contacts.impulse.sum() == pytest.approx(2.0 * G * w.dt, rel=1e-6)


def test_sliding_contact_reports_its_friction_impulse():
    scene = drop_scene()
    scene["bodies"][1]["position"] = [0, 0, 0.05]
    scene["bodies"][1]["velocity"] = [3.0, 0, 0]
    w = load_scene(scene)
    w.step(5)
    # kinetic friction μ_k N over the step (steel on steel, μ_k = 0.4)
    assert w.contacts.friction_impulse.sum() == pytest.approx(0.4 * w.contacts.impulse.sum(), rel=1e-9)
    assert w.contacts.impulse.sum() == pytest.approx(2.0 * G * w.dt, rel=1e-4)


def test_events_are_finite_and_typed():
    w = load_scene(drop_scene())
    w.step(80)
    c = w.contacts
    assert c.event.dtype == np.uint8 and c.body_a.dtype.kind == "i"
    for k, v in c.as_dict().items():
        assert np.all(np.isfinite(v)), k
