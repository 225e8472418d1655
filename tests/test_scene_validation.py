"""Bad scenes are refused at load with a SceneError naming the file and the key path.

Every bad scene below is a one-line change to a valid scene; each is tried as
a dict (source `<dict>`) and as a YAML file (source = the file's path).
"""
import copy
import math

import numpy as np
import pytest
import yaml

from physics_core import SceneError, load_scene

VALID = {
    "dt": 0.005,
    "integrator": "semi_implicit_euler",
    "gravity": "earth",
    "effects": {"drag": {"model": "quadratic"}},
    "bodies": [
        {"name": "ground", "shape": {"type": "plane", "normal": [0, 0, 1], "offset": 0.0}, "static": True,
         "material": "concrete"},
        {"name": "ball", "shape": {"type": "sphere", "radius": 0.1}, "mass": 1.0, "material": "rubber",
         "position": [0.0, 0.0, 1.0], "orientation": [1.0, 0.0, 0.0, 0.0]},
        {"name": "crate", "shape": {"type": "box", "half_extents": [0.2, 0.1, 0.1]}, "density": 500.0,
         "position": [1.0, 0.0, 1.0]},
    ],
    "springs": [{"a": "ball", "b": "crate", "stiffness": 20.0, "rest_length": 1.0}],
}


def _set(path, value):
    """A change to VALID: set the value at a key path like ('bodies', 1, 'mass')."""
    def change(sc):
        node = sc
        for key in path[:-1]:
            node = node[key]
        node[path[-1]] = value
    return change


def _delete(path):
    def change(sc):
        node = sc
        for key in path[:-1]:
            node = node[key]
        del node[path[-1]]
    return change


def _add_body(body):
    return lambda sc: sc["bodies"].append(body)


BAD_SCENES = [
    # (id, change, key path the error must name)
    ("negative_mass", _set(("bodies", 1, "mass"), -1.0), "bodies[1].mass"),
    ("zero_mass", _set(("bodies", 1, "mass"), 0.0), "bodies[1].mass"),
    ("zero_radius", _set(("bodies", 1, "shape", "radius"), 0.0), "bodies[1].shape.radius"),
    ("zero_half_extent", _set(("bodies", 2, "shape", "half_extents"), [0.2, 0.0, 0.1]),
     "bodies[2].shape.half_extents"),
    ("unknown_top_key", _set(("gravty",), "earth"), "gravty"),
    ("unknown_body_key", _set(("bodies", 1, "colour"), "red"), "bodies[1].colour"),
    ("unknown_shape_key", _set(("bodies", 1, "shape", "size"), 1.0), "bodies[1].shape.size"),
    ("unknown_effect", _set(("effects", "wind"), {}), "effects.wind"),
    ("unknown_drag_model", _set(("effects", "drag", "model"), "cubic"), "effects.drag.model"),
    ("unknown_shape_type", _set(("bodies", 1, "shape", "type"), "cone"), "bodies[1].shape.type"),
    ("wrong_type_mass", _set(("bodies", 1, "mass"), "heavy"), "bodies[1].mass"),
    ("wrong_type_bool_as_number", _set(("dt",), True), "dt"),
    ("wrong_type_static", _set(("bodies", 0, "static"), "yes"), "bodies[0].static"),
    ("wrong_type_bodies", _set(("bodies",), {"ball": {}}), "bodies"),
    ("wrong_length_vector", _set(("bodies", 1, "position"), [0.0, 1.0]), "bodies[1].position"),
    ("duplicate_name", _set(("bodies", 2, "name"), "ball"), "bodies[2].name"),
    ("invalid_name", _set(("bodies", 1, "name"), "my ball"), "bodies[1].name"),
    ("name_world_reserved", _set(("bodies", 1, "name"), "world"), "bodies[1].name"),
    ("unknown_material", _set(("bodies", 1, "material"), "unobtainium"), "bodies[1].material"),
    ("non_unit_quaternion", _set(("bodies", 1, "orientation"), [1.0, 1.0, 0.0, 0.0]), "bodies[1].orientation"),
    ("zero_quaternion", _set(("bodies", 1, "orientation"), [0.0, 0.0, 0.0, 0.0]), "bodies[1].orientation"),
    ("bad_integrator", _set(("integrator",), "leapfrog"), "integrator"),
    ("negative_dt", _set(("dt",), -0.01), "dt"),
    ("zero_dt", _set(("dt",), 0.0), "dt"),
    ("substeps_zero", _set(("substeps",), 0), "substeps"),
    ("substeps_fraction", _set(("substeps",), 2.5), "substeps"),
    ("spring_to_unknown_body", _set(("springs", 0, "b"), "anchor"), "springs[0].b"),
    ("spring_to_itself", _set(("springs", 0, "b"), "ball"), "springs[0].b"),
    ("spring_negative_stiffness", _set(("springs", 0, "stiffness"), -5.0), "springs[0].stiffness"),
    ("spring_missing_stiffness", _delete(("springs", 0, "stiffness")), "springs[0].stiffness"),
    ("plane_not_static", _set(("bodies", 0, "static"), False), "bodies[0].static"),
    ("mass_and_density", _set(("bodies", 2, "mass"), 5.0), "bodies[2].density"),
    ("no_mass_nor_density", _delete(("bodies", 1, "mass")), "bodies[1].mass"),
    ("static_body_moving", _add_body({"name": "wall", "shape": {"type": "box", "half_extents": [1, 1, 1]},
                                      "static": True, "velocity": [1.0, 0.0, 0.0]}), "bodies[3].velocity"),
    ("nan_position", _set(("bodies", 1, "position"), [0.0, math.nan, 1.0]), "bodies[1].position"),
    ("inf_velocity", _set(("bodies", 1, "velocity"), [math.inf, 0.0, 0.0]), "bodies[1].velocity"),
    ("inf_dt", _set(("dt",), math.inf), "dt"),
    ("nan_density", _set(("bodies", 2, "density"), math.nan), "bodies[2].density"),
    ("bad_gravity_preset", _set(("gravity",), "jupiter"), "gravity"),
    ("negative_altitude", _set(("gravity",), {"planet": "mars", "altitude": -10.0}), "gravity.altitude"),
    ("buoyancy_without_gravity", lambda sc: (sc.pop("gravity"), sc["effects"].update(buoyancy={})),
     "effects.buoyancy"),
    ("restitution_above_one", _set(("bodies", 1, "restitution"), 1.5), "bodies[1].restitution"),
    ("missing_shape", _delete(("bodies", 1, "shape")), "bodies[1].shape"),
    ("body_not_a_mapping", _set(("bodies", 1), "ball"), "bodies[1]"),
    ("no_bodies", _set(("bodies",), []), "bodies"),
    ("friction_kinetic_above_static", _set(("friction",), [{"a": "rubber", "b": "ice", "static": 0.1,
                                                             "kinetic": 0.2}]), "friction[0].kinetic"),
]


def bad_scene(change):
    sc = copy.deepcopy(VALID)
    change(sc)
    return sc


def test_the_valid_scene_loads():
    world = load_scene(copy.deepcopy(VALID))
    assert world.model.names == ("ground", "ball", "crate")
    assert world.body("crate").mass == pytest.approx(500.0 * 0.4 * 0.2 * 0.2)


@pytest.mark.parametrize("change, path", [(c, p) for _, c, p in BAD_SCENES], ids=[i for i, _, _ in BAD_SCENES])
def test_bad_dict_scene_is_refused_naming_the_key_path(change, path):
    with pytest.raises(SceneError) as err:
        load_scene(bad_scene(change))
    assert err.value.path == path
    assert str(err.value).startswith(f"<dict>: {path}: expected ")


@pytest.mark.parametrize("change, path", [(c, p) for _, c, p in BAD_SCENES], ids=[i for i, _, _ in BAD_SCENES])
def test_bad_yaml_file_is_refused_naming_the_file_and_key_path(tmp_path, change, path):
    f = tmp_path / "bad_scene.yaml"
    f.write_text(yaml.safe_dump(bad_scene(change), sort_keys=False))
    with pytest.raises(SceneError) as err:
        load_scene(str(f))
    assert err.value.source == str(f)
    assert str(err.value).startswith(f"{f}: {path}: expected ")


def test_error_says_what_was_expected_and_what_was_found(tmp_path):
    f = tmp_path / "pile.yaml"
    f.write_text("bodies:\n  - name: ball\n    shape: {type: sphere, radius: -0.5}\n    mass: 1.0\n")
    with pytest.raises(SceneError) as err:
        load_scene(f)
    assert str(err.value) == f"{f}: bodies[0].shape.radius: expected a number > 0, got -0.5"


def test_typed_in_yaml_non_finite_values_are_refused(tmp_path):
    f = tmp_path / "nan.yaml"
    f.write_text("dt: .nan\nbodies:\n  - {name: a, shape: {type: sphere, radius: 0.1}, mass: 1.0}\n")
    with pytest.raises(SceneError, match=r"nan\.yaml: dt: expected a finite number"):
        load_scene(f)


def test_invalid_yaml_and_missing_file_name_the_file(tmp_path):
    f = tmp_path / "broken.yaml"
    f.write_text("bodies: [\n  - name: a\n")
    with pytest.raises(SceneError, match="broken.yaml: expected valid YAML"):
        load_scene(f)
    with pytest.raises(SceneError, match="nowhere.yaml: expected a readable scene file"):
        load_scene(tmp_path / "nowhere.yaml")
    top = tmp_path / "list.yaml"
    top.write_text("- 1\n- 2\n")
    with pytest.raises(SceneError, match=r"list.yaml: <top level>: expected a mapping"):
        load_scene(top)


def test_scientific_notation_without_a_dot_is_a_number(tmp_path):
    """YAML 1.1 (PyYAML) would read `1e6` as a string; scene files use the YAML 1.2
    number rule, so the usual ways to write a stiffness all load."""
    f = tmp_path / "stiff.yaml"
    f.write_text("dt: 4.0e-3\nbodies:\n"
                 "  - {name: a, shape: {type: sphere, radius: 1e-1}, mass: 1E0}\n"
                 "springs:\n  - {a: a, b: world, stiffness: 1e6, damping: 2.5e+1}\n")
    world = load_scene(f)
    assert world.model.springs.stiffness[0] == 1e6
    assert world.model.springs.damping[0] == 25.0
    assert world.model.radius[0] == 0.1 and world.dt == 0.004


def test_numpy_values_in_a_dict_scene_are_accepted():
    sc = copy.deepcopy(VALID)
    sc["bodies"][1]["position"] = np.array([0.0, 0.5, 2.0])
    sc["bodies"][1]["mass"] = np.float32(2.0)
    sc["substeps"] = np.int64(2)
    world = load_scene(sc)
    assert world.body("ball").position.tolist() == [0.0, 0.5, 2.0]
    assert world.body("ball").mass == 2.0 and world.model.substeps == 2
    assert "position:" in world.model.source_text


def test_loading_does_not_modify_the_callers_dict():
    sc = copy.deepcopy(VALID)
    load_scene(sc)
    assert sc == VALID
