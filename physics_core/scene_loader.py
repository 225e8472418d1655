"""Scene files (YAML) and dicts → a validated, frozen Model and a World.

Every rule of INTERFACE.md's scene format is checked here, once, so the
step never meets a bad parameter. A failure raises SceneError naming the
file, the key path (``bodies[2].shape.radius``) and what was expected.
"""
import os
import re
import warnings
from types import MappingProxyType

import numpy as np
import yaml

from . import materials, shapes
from .accuracy_params import parse_accuracy
from .contact_params import parse_contacts
from .errors import SceneError
from .model import (BuoyancyParams, DragParams, GravitationParams, Model, SpringSet,
                    frozen_array)
from .planets import PLANETS, surface_gravity
from .scene_yaml import load_yaml
from .scene_limits import (MAX_BODIES, check_body_count, max_file_bytes, read_scene_text,
                           refuse_aliases)
from .validate import NAME_RE, Reader

INTEGRATORS = ("explicit_euler", "semi_implicit_euler", "velocity_verlet", "rk4", "adaptive")
TOP_KEYS = {"name", "description", "dt", "substeps", "integrator", "accuracy", "gravity", "effects",
            "bodies", "springs", "friction"}
EFFECT_KEYS = {"gravitation", "drag", "buoyancy", "contacts"}
BODY_KEYS = {"name", "shape", "static", "mass", "density", "material", "restitution",
             "position", "orientation", "velocity", "angular_velocity", "drag"}
DEFAULT_DT = 1.0 / 240.0
DEFAULT_RESTITUTION = 0.5
QUAT_TOLERANCE = 1e-3   # |q| may differ from 1 by this much (typed-in decimals); then normalised


class SceneYamlLoader(getattr(yaml, "CSafeLoader", yaml.SafeLoader)):
    """Safe YAML whose numbers follow YAML 1.2: `1e6`, `1.0e6` and `2E-3` are floats.

    PyYAML implements YAML 1.1, where a float needs a dot and a signed
    exponent, so `stiffness: 1e6` would arrive as the string "1e6"."""


SceneYamlLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)[eE][-+]?[0-9]+$"),
    list("-+0123456789."))

_SceneYamlDumper = getattr(yaml, "CSafeDumper", yaml.SafeDumper)


def plain_data(value):
    """A deep copy of a scene dict with numpy scalars and arrays (and tuples) turned
    into Python floats, ints and lists, so that numpy-built scenes validate and
    serialise like typed-in ones."""
    if isinstance(value, dict):
        return {k: plain_data(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain_data(v) for v in value]
    if isinstance(value, np.ndarray):
        return plain_data(value.tolist())
    if isinstance(value, np.generic):
        return value.item()
    return value


def read_scene_source(scene, max_bodies=MAX_BODIES):
    """(data dict, source label, text, path) from a path or a dict; the file's
    bounds are scene_limits.py's."""
    if isinstance(scene, dict):
        data = plain_data(scene)
        return data, "<dict>", yaml.dump(data, Dumper=_SceneYamlDumper, sort_keys=False), None
    path = os.fspath(scene)
    text = read_scene_text(path, max_file_bytes(max_bodies))
    refuse_aliases(text, path, SceneYamlLoader)
    try:
        data = load_yaml(text, SceneYamlLoader)
    except yaml.YAMLError as e:
        raise SceneError(path, "", "valid YAML", " ".join(str(e).split())[:300]) from None
    except RecursionError:
        raise SceneError(path, "", "YAML nested less deeply", "too deep to read") from None
    return data, path, text, path


def parse_gravity(r: Reader):
    if not r.has("gravity") or r.data["gravity"] is None:
        return None
    g = r.data["gravity"]
    if isinstance(g, str):
        if g not in PLANETS:
            r.fail("gravity", "one of: " + ", ".join(PLANETS) + ", or [gx, gy, gz]", g)
        return np.array([0.0, 0.0, -surface_gravity(g)])
    if isinstance(g, dict):
        gr = r.sub("gravity")
        gr.only({"planet", "altitude"})
        planet = gr.string("planet", choices=tuple(PLANETS))
        return np.array([0.0, 0.0, -surface_gravity(planet, gr.number("altitude", 0.0, min=0.0))])
    return r.vector("gravity", 3)


def parse_effects(r: Reader, gravity):
    er = r.sub("effects")
    er.only(EFFECT_KEYS)
    effects = {}
    if er.has("gravitation"):
        gr = er.sub("gravitation")
        gr.only({"G", "softening"})
        d = GravitationParams()
        effects["gravitation"] = GravitationParams(
            G=gr.number("G", d.G, positive=True), softening=gr.number("softening", d.softening, positive=True))
    if er.has("drag"):
        dr = er.sub("drag")
        dr.only({"model", "fluid_density", "viscosity", "b", "reynolds_threshold"})
        d = DragParams()
        effects["drag"] = DragParams(
            model=dr.string("model", d.model, choices=("linear", "quadratic", "reynolds")),
            fluid_density=dr.number("fluid_density", d.fluid_density, min=0.0),
            viscosity=dr.number("viscosity", d.viscosity, positive=True),
            b=dr.number("b", d.b, min=0.0),
            reynolds_threshold=dr.number("reynolds_threshold", d.reynolds_threshold, positive=True))
    if er.has("buoyancy"):
        br = er.sub("buoyancy")
        br.only({"fluid_density", "surface_z", "linear_damping", "angular_damping", "cells"})
        if gravity is None or not np.any(gravity):
            er.fail("buoyancy", "buoyancy only with a `gravity:` that is not zero (F = ρ g V)",
                    "no gravity")
        d = BuoyancyParams()
        effects["buoyancy"] = BuoyancyParams(
            fluid_density=br.number("fluid_density", d.fluid_density, positive=True),
            surface_z=br.number("surface_z", d.surface_z),
            linear_damping=br.number("linear_damping", d.linear_damping, min=0.0),
            angular_damping=br.number("angular_damping", d.angular_damping, min=0.0),
            cells=br.number("cells", d.cells, min=1, max=16, integer=True))
    if er.has("contacts"):
        effects["contacts"] = parse_contacts(er.sub("contacts"))
    return effects


def parse_shape(br: Reader):
    sr = br.sub("shape") if br.has("shape") else br.fail("shape", "a shape mapping (required)", "missing")
    kind = sr.string("type", choices=tuple(shapes.SHAPE_NAMES))
    radius, half, normal, offset = 0.0, np.zeros(3), np.array([0.0, 0.0, 1.0]), 0.0
    if kind == "sphere":
        sr.only({"type", "radius"})
        radius = sr.number("radius", positive=True)
    elif kind == "box":
        sr.only({"type", "half_extents"})
        half = sr.vector("half_extents", 3)
        if np.any(half <= 0):
            sr.fail("half_extents", "three numbers > 0", sr.data["half_extents"])
    else:
        sr.only({"type", "normal", "offset"})
        normal = sr.vector("normal", 3, [0.0, 0.0, 1.0])
        length = np.linalg.norm(normal)
        if length < 1e-12:
            sr.fail("normal", "a non-zero vector", sr.data["normal"])
        normal = normal / length
        offset = sr.number("offset", 0.0)
    return shapes.SHAPE_NAMES[kind], radius, half, normal, offset


def parse_body(br: Reader, known_materials):
    br.only(BODY_KEYS)
    name = _body_name(br)
    stype, radius, half, normal, offset = parse_shape(br)
    static = br.boolean("static", stype == shapes.PLANE)
    if stype == shapes.PLANE and not static:
        br.fail("static", "true: a plane is a static half-space", False)
    mass = _body_mass(br, stype, radius, half, static)
    material = br.string("material", materials.DEFAULT_MATERIAL)
    if material not in known_materials:
        br.fail("material", "a material of the friction table: " + ", ".join(sorted(known_materials)),
                material)
    restitution = br.number("restitution", DEFAULT_RESTITUTION, min=0.0, max=1.0)
    pos, quat, vel, omega = _body_motion(br, static)
    return dict(name=name, stype=stype, radius=radius, half=half, normal=normal, offset=offset,
                static=static, mass=mass, material=material, restitution=restitution,
                pos=pos, quat=quat, vel=vel, omega=omega, drag=_body_drag(br, stype))


def _body_name(br: Reader):
    name = br.string("name")
    if not NAME_RE.match(name) or name == "world":
        br.fail("name", "a name of letters, digits and _ starting with a letter, not 'world' "
                "(it becomes a ROS topic name)", name)
    return name


def _body_mass(br: Reader, stype, radius, half, static):
    """`mass`, or `density` times the shape's volume; 0 for a static body without either."""
    if br.has("mass") and br.has("density"):
        br.fail("density", "either mass or density, not both", br.data["density"])
    if br.has("mass"):
        return br.number("mass", positive=True)
    if br.has("density"):
        if stype == shapes.PLANE:
            br.fail("density", "no density on a plane (it has no volume)", br.data["density"])
        vol = float(shapes.volume(np.array([stype]), np.array([radius]), half[None])[0])
        return br.number("density", positive=True) * vol
    if not static:
        br.fail("mass", "mass (kg) or density (kg/m³) for a dynamic body", "missing")
    return 0.0


def _body_motion(br: Reader, static):
    """(position, unit orientation, velocity, angular velocity) of a body."""
    pos = br.vector("position", 3, [0.0, 0.0, 0.0])
    quat = br.vector("orientation", 4, [1.0, 0.0, 0.0, 0.0])
    qn = np.linalg.norm(quat)
    if abs(qn - 1.0) > QUAT_TOLERANCE:
        br.fail("orientation", f"a unit quaternion [w, x, y, z] (|q| = 1 ± {QUAT_TOLERANCE})",
                br.data["orientation"])
    vel = br.vector("velocity", 3, [0.0, 0.0, 0.0])
    omega = br.vector("angular_velocity", 3, [0.0, 0.0, 0.0])
    if static and (np.any(vel) or np.any(omega)):
        br.fail("velocity" if np.any(vel) else "angular_velocity",
                "zero velocities on a static body", "non-zero")
    return pos, quat / qn, vel, omega


def _body_drag(br: Reader, stype):
    """(cd, area, b) of the body's `drag:` (NaN: not given, the shape's own is used)."""
    dr = br.sub("drag")
    dr.only({"cd", "area", "b"})
    nan = float("nan")
    return (dr.number("cd", shapes.DEFAULT_CD[stype], min=0.0),
            dr.number("area", positive=True) if dr.has("area") else nan,
            dr.number("b", min=0.0) if dr.has("b") else nan)


def parse_friction(r: Reader):
    """`friction: [{a: rubber, b: ice, static: 0.1, kinetic: 0.05}, ...]`."""
    pairs = {}
    for fr in r.items("friction"):
        fr.only({"a", "b", "static", "kinetic"})
        a, b = fr.string("a"), fr.string("b")
        for k, m in (("a", a), ("b", b)):
            if not NAME_RE.match(m):
                fr.fail(k, "a material name of letters, digits and _", m)
        mu_s = fr.number("static", min=0.0)
        mu_k = fr.number("kinetic", min=0.0)
        if mu_k > mu_s:
            fr.fail("kinetic", f"kinetic <= static ({mu_s}) (COURSE.md 2: μ_k < μ_s)", mu_k)
        pairs[(a, b)] = (mu_s, mu_k)
    return pairs


def friction_matrices(names, table):
    m = len(names)
    mu_s = np.empty((m, m))
    mu_k = np.empty((m, m))
    fallbacks = []
    for i, a in enumerate(names):
        for j, b in enumerate(names):
            v = table.get(materials.pair_key(a, b))
            if v is None:
                v = materials.FALLBACK_FRICTION
                if i <= j:
                    fallbacks.append((a, b))
            mu_s[i, j], mu_k[i, j] = v
    return mu_s, mu_k, tuple(fallbacks)


def parse_springs(r: Reader, index):
    cols = {k: [] for k in ("a", "b", "point_a", "point_b", "stiffness", "rest_length", "damping")}
    for sr in r.items("springs"):
        sr.only(set(cols))
        ends = []
        for key in ("a", "b"):
            name = sr.string(key)
            if name != "world" and name not in index:
                sr.fail(key, "a body name or 'world'", name)
            ends.append(-1 if name == "world" else index[name])
        if ends[0] == ends[1]:
            sr.fail("b", "two different ends", sr.data["b"])
        cols["a"].append(ends[0])
        cols["b"].append(ends[1])
        cols["point_a"].append(sr.vector("point_a", 3, [0.0, 0.0, 0.0]))
        cols["point_b"].append(sr.vector("point_b", 3, [0.0, 0.0, 0.0]))
        cols["stiffness"].append(sr.number("stiffness", min=0.0))
        cols["rest_length"].append(sr.number("rest_length", 0.0, min=0.0))
        cols["damping"].append(sr.number("damping", 0.0, min=0.0))
    return SpringSet(
        a=frozen_array(cols["a"], int), b=frozen_array(cols["b"], int),
        point_a=frozen_array(np.reshape(cols["point_a"], (-1, 3))),
        point_b=frozen_array(np.reshape(cols["point_b"], (-1, 3))),
        stiffness=frozen_array(cols["stiffness"]), rest_length=frozen_array(cols["rest_length"]),
        damping=frozen_array(cols["damping"]))


def parse_bodies(r, data, known):
    """(body dicts, name → index) of the scene's `bodies`, names unique."""
    body_readers = r.items("bodies")
    if not body_readers:
        r.fail("bodies", "a list of at least one body", data.get("bodies"))
    bodies, index = [], {}
    for br in body_readers:
        b = parse_body(br, known)
        if b["name"] in index:
            br.fail("name", "a name not used by another body", b["name"])
        index[b["name"]] = len(bodies)
        bodies.append(b)
    return bodies, index


def material_fields(bodies, table, effects, source):
    """The Model's material fields: the materials used, per-body index, and
    the pair friction matrices (warning once about table fallbacks)."""
    used = sorted({b["material"] for b in bodies})
    mu_s, mu_k, fallbacks = friction_matrices(used, table)
    if fallbacks and "contacts" in effects:
        warnings.warn(f"{source}: friction pairs not in the table use the fallback "
                      f"μ_s={materials.FALLBACK_FRICTION[0]}, μ_k={materials.FALLBACK_FRICTION[1]}: "
                      + ", ".join(f"{a}-{b}" for a, b in fallbacks), stacklevel=4)
    return dict(material=frozen_array([used.index(b["material"]) for b in bodies], int),
                material_names=tuple(used), mu_static=frozen_array(mu_s),
                mu_kinetic=frozen_array(mu_k), friction_fallbacks=fallbacks)


def body_fields(bodies):
    """The Model's per-body arrays: shape, mass and inertia (static: infinite),
    restitution, drag, and the initial state."""
    col = lambda k, dtype=float: np.array([b[k] for b in bodies], dtype=dtype)
    stype, radius, static, mass = col("stype", int), col("radius"), col("static", bool), col("mass")
    half = np.array([b["half"] for b in bodies]).reshape(-1, 3)
    inv_mass = np.where(static, 0.0, 1.0 / np.where(mass > 0, mass, 1.0))
    inertia = shapes.principal_inertia(stype, mass, radius, half)
    inv_inertia = np.where(static[:, None] | (inertia <= 0), 0.0,
                           1.0 / np.where(inertia > 0, inertia, 1.0))
    drag = np.array([b["drag"] for b in bodies]).reshape(-1, 3)
    initial = MappingProxyType({k: frozen_array([b[k] for b in bodies])
                                for k in ("pos", "quat", "vel", "omega")})
    return dict(
        shape_type=frozen_array(stype, int), radius=frozen_array(radius),
        half_extents=frozen_array(half),
        plane_normal=frozen_array([b["normal"] for b in bodies]),
        plane_offset=frozen_array(col("offset")),
        mass=frozen_array(mass), inv_mass=frozen_array(inv_mass),
        inertia=frozen_array(inertia), inv_inertia=frozen_array(inv_inertia),
        is_static=frozen_array(static, bool),
        volume=frozen_array(shapes.volume(stype, radius, half)),
        restitution=frozen_array(col("restitution")),
        drag_cd=frozen_array(drag[:, 0]), drag_area=frozen_array(drag[:, 1]),
        drag_b=frozen_array(drag[:, 2]),
        char_length=frozen_array(shapes.characteristic_length(stype, radius, half)),
        initial=initial)


def build_model(scene, max_bodies=MAX_BODIES) -> Model:
    data, source, text, path = read_scene_source(scene, max_bodies)
    if data is None:
        data = {}
    r = Reader(source, data)
    check_body_count(source, data.get("bodies"), max_bodies)
    r.only(TOP_KEYS)
    dt = r.number("dt", DEFAULT_DT, positive=True)
    substeps = r.number("substeps", 1, min=1, integer=True)
    integrator = r.string("integrator", "adaptive" if r.has("accuracy") else "semi_implicit_euler",
                          choices=INTEGRATORS)
    accuracy = parse_accuracy(r, integrator, dt / substeps)
    gravity = parse_gravity(r)
    effects = parse_effects(r, gravity)

    extra_pairs = parse_friction(r)
    table = materials.build_table(extra_pairs)
    known = set(materials.COURSE_MATERIALS) | {materials.DEFAULT_MATERIAL}
    known |= {m for pair in extra_pairs for m in pair}
    bodies, index = parse_bodies(r, data, known)
    springs = parse_springs(r, index)
    return Model(
        names=tuple(index), index=MappingProxyType(dict(index)),
        **body_fields(bodies), **material_fields(bodies, table, effects, source),
        springs=springs,
        gravity=None if gravity is None else frozen_array(gravity),
        effects=MappingProxyType(effects), dt=dt, substeps=substeps, integrator=integrator,
        accuracy=accuracy, source_text=text, source_path=path,
        extra=MappingProxyType({"friction_pairs": MappingProxyType(extra_pairs)}),
    )


def load_scene(scene, max_bodies=MAX_BODIES):
    """A World from a YAML scene file path or a dict with the same keys; at most
    `max_bodies` bodies (scene_limits.py)."""
    from .world import World
    return World(build_model(scene, max_bodies))
