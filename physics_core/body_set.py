"""Bodies added to and removed from a Model between steps.

`with_body(model, spec)` checks a body given with the scene's body keys
(scene_loader.parse_body: the same rules and errors, naming the key, with
the source "add_body") and returns a Model with it appended as the last
body; `without_body(model, i)` returns one without body i, the bodies after
it moving one place down. Springs attached to a removed body go with it.
The Model stays frozen: each change makes a new one, so a stage can never
see a half-changed scene. Friction pairs of a new material come from the
same pair table the scene was built with (scene_loader.friction_matrices).
"""
from dataclasses import replace
from types import MappingProxyType

import numpy as np

from . import materials, shapes
from .errors import SceneError
from .model import SpringSet, frozen_array
from .validate import Reader

# Model arrays with one row per body, and the scene_loader.parse_body field each comes from
_ROW_FIELDS = ("shape_type", "radius", "half_extents", "plane_normal", "plane_offset", "mass",
               "inv_mass", "inertia", "inv_inertia", "is_static", "volume", "restitution",
               "drag_cd", "drag_area", "drag_b", "char_length")


def parse_new_body(model, spec, source="add_body"):
    """The body dict of scene_loader.parse_body for `spec`, or SceneError."""
    from .scene_loader import parse_body, plain_data
    if not isinstance(spec, dict):
        raise SceneError(source, "", "a mapping of body keys (name, shape, mass, ...)",
                         type(spec).__name__)
    known = set(materials.COURSE_MATERIALS) | {materials.DEFAULT_MATERIAL} | set(model.material_names)
    known |= {m for pair in model.extra.get("friction_pairs", {}) for m in pair}
    body = parse_body(Reader(source, plain_data(spec)), known)
    if body["name"] in model.index:
        raise SceneError(source, "name", "a name not used by another body", body["name"])
    return body


def body_rows(body):
    """One body's rows of the Model's per-body arrays (as scene_loader.build_model makes them)."""
    stype = np.array([body["stype"]])
    radius, half = np.array([body["radius"]]), np.asarray(body["half"], float).reshape(1, 3)
    mass = np.array([body["mass"]])
    static = np.array([body["static"]])
    inertia = shapes.principal_inertia(stype, mass, radius, half)
    return dict(
        shape_type=stype, radius=radius, half_extents=half,
        plane_normal=np.asarray(body["normal"], float).reshape(1, 3),
        plane_offset=np.array([body["offset"]]), mass=mass,
        inv_mass=np.where(static, 0.0, 1.0 / np.where(mass > 0, mass, 1.0)),
        inertia=inertia,
        inv_inertia=np.where(static[:, None] | (inertia <= 0), 0.0,
                             1.0 / np.where(inertia > 0, inertia, 1.0)),
        is_static=static, volume=shapes.volume(stype, radius, half),
        restitution=np.array([body["restitution"]]),
        drag_cd=np.array([body["drag"][0]]), drag_area=np.array([body["drag"][1]]),
        drag_b=np.array([body["drag"][2]]),
        char_length=shapes.characteristic_length(stype, radius, half))


def _materials_with(model, name):
    """(material_names, mu_static, mu_kinetic, index of `name`) with `name` included."""
    from .scene_loader import friction_matrices
    names = model.material_names
    if name in names:
        return names, model.mu_static, model.mu_kinetic, names.index(name)
    names = tuple(sorted(set(names) | {name}))
    table = materials.build_table(model.extra.get("friction_pairs", {}))
    mu_s, mu_k, _ = friction_matrices(list(names), table)
    return names, mu_s, mu_k, names.index(name)


def with_body(model, body):
    """A Model with the parsed `body` appended (index model.n)."""
    rows = body_rows(body)
    names, mu_s, mu_k, m = _materials_with(model, body["material"])
    remap = np.array([names.index(model.material_names[i]) for i in model.material], dtype=int)
    changes = {f: frozen_array(np.concatenate([getattr(model, f), rows[f]]),
                               getattr(model, f).dtype) for f in _ROW_FIELDS}
    index = dict(model.index)
    index[body["name"]] = model.n
    return replace(
        model, names=model.names + (body["name"],), index=MappingProxyType(index),
        material=frozen_array(np.append(remap, m), int), material_names=names,
        mu_static=frozen_array(mu_s), mu_kinetic=frozen_array(mu_k), **changes)


def without_body(model, i):
    """A Model without body i; springs attached to it are removed with it."""
    keep = np.arange(model.n) != i
    changes = {f: frozen_array(getattr(model, f)[keep], getattr(model, f).dtype)
               for f in _ROW_FIELDS}
    names = model.names[:i] + model.names[i + 1:]
    return replace(
        model, names=names, index=MappingProxyType({n: k for k, n in enumerate(names)}),
        material=frozen_array(model.material[keep], int), springs=_springs_without(model.springs, i),
        **changes)


def _springs_without(springs, i):
    keep = (springs.a != i) & (springs.b != i)
    shift = lambda end: np.where(end > i, end - 1, end)[keep]
    return SpringSet(
        a=frozen_array(shift(springs.a), int), b=frozen_array(shift(springs.b), int),
        point_a=frozen_array(springs.point_a[keep]), point_b=frozen_array(springs.point_b[keep]),
        stiffness=frozen_array(springs.stiffness[keep]),
        rest_length=frozen_array(springs.rest_length[keep]),
        damping=frozen_array(springs.damping[keep]))
