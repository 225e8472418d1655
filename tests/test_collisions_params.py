"""The `effects.contacts` keys: defaults, validation, and the stages they switch."""
import pytest

from physics_core import SceneError, load_scene
from physics_core.contact_params import ContactParams

pytestmark = pytest.mark.filterwarnings("ignore:.*fallback")


def scene(contacts):
    return {"effects": {"contacts": contacts},
            "bodies": [{"name": "floor", "shape": {"type": "plane"}},
                       {"name": "ball", "shape": {"type": "sphere", "radius": 0.1}, "mass": 1.0,
                        "position": [0, 0, 0.5]}]}


def test_empty_contacts_gives_the_documented_defaults():
    w = load_scene(scene({}))
    assert w.model.effects["contacts"] == ContactParams()


def test_every_key_is_read():
    values = dict(iterations=12, velocity_tolerance=0.0, static_friction_speed=0.02,
                  warm_start=0.5, margin=0.01, restitution_threshold=1.0, restitution_ramp=0.5,
                  restitution_combine="max", restitution_iterations=5, shock_propagation=False,
                  resting_block=False,
                  position_iterations=2,
                  slop=0.001, correction_rate=0.5,
                  max_correction_speed=2.0, ccd=False, ccd_threshold=1.0, ccd_iterations=10,
                  ccd_tolerance=1e-3, sleep=False, sleep_linear_speed=0.1, sleep_angular_speed=0.2,
                  sleep_time=1.0)
    assert set(values) == set(ContactParams.__dataclass_fields__)
    p = load_scene(scene(values)).model.effects["contacts"]
    for k, v in values.items():
        assert getattr(p, k) == v, k


@pytest.mark.parametrize("key, value", [
    ("iterations", 0), ("iterations", 2.5), ("solver", "jacobi"), ("warm_start", 1.5),
    ("margin", -0.1), ("restitution_combine", "product"), ("ccd", "yes"), ("slop", -1.0),
    ("correction_rate", 2.0), ("sleep_time", -1.0), ("ccd_tolerance", 0.0), ("unknown_key", 1)])
def test_bad_values_are_rejected_with_their_key_path(key, value):
    with pytest.raises(SceneError) as err:
        load_scene(scene({key: value}))
    assert f"effects.contacts.{key}" in str(err.value)


def test_stages_follow_the_switches():
    names = load_scene(scene({})).stage_names
    assert [n for n in names if n in ("ccd", "collide", "solve", "restitution", "correct", "events", "sleep")] == \
        ["ccd", "collide", "restitution", "solve", "correct", "events", "sleep"]
    names = load_scene(scene({"ccd": False, "sleep": False})).stage_names
    assert "ccd" not in names and "sleep" not in names


def test_stage_timings_are_in_the_profile():
    w = load_scene(scene({}))
    w.step(60)
    for stage in ("ccd", "collide", "solve", "restitution", "correct", "events", "sleep"):
        assert w.profile[stage] > 0.0
