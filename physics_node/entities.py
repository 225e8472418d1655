"""Entities of the simulator standard (simulation_interfaces) on a World:
spawn, delete, get and set state, reset scopes.

One `Entities` object runs in the live node and in `--resimulate`, taking
the standard's request messages as received, so a recorded request is
re-applied through exactly the code that first applied it. Nothing here
publishes or records; the node does that when an operation succeeded.

Spawn format `physics_node/body` (SPAWN_FORMAT): YAML (or JSON) holding one
body with the keys of a scene file's `bodies:` entries (INTERFACE.md), or a
scene-shaped mapping whose `bodies:` list holds exactly one body. It comes
in `resource_string`, or in a file named by `uri` (a path or `file://`
URI ending in .yaml, .yml or .json).
"""

import re
from pathlib import Path
from urllib.parse import unquote, urlparse

import numpy as np
import yaml
from simulation_interfaces.msg import Result
from simulation_interfaces.srv import ResetSimulation, SetEntityState, SpawnEntity

from physics_core import CommandError, SceneError, shapes
from physics_core.scene_limits import MAX_BODIES
from physics_core.validate import NAME_RE

from .entity_frames import FrameError, Motion, body_motion, frame_motion, is_world, to_frame, to_world

SPAWN_FORMAT = "physics_node/body"
SPAWN_FILE_SUFFIXES = (".yaml", ".yml", ".json")
_NAMESPACE_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*$")
_POSE_KEYS = ("position", "orientation", "velocity", "angular_velocity")
RESET_SCOPES = ResetSimulation.Request.SCOPE_TIME | ResetSimulation.Request.SCOPE_STATE
RESET_SCOPES |= ResetSimulation.Request.SCOPE_SPAWNED


class EntityError(Exception):
    """A request refused with the standard's result code `code`."""

    def __init__(self, code, message):
        super().__init__(message)
        self.code = int(code)
        self.message = message


def unit_quaternion_wxyz(q_msg, what, code):
    """A geometry_msgs Quaternion as (w, x, y, z); EntityError(code) unless unit."""
    q = np.array([q_msg.w, q_msg.x, q_msg.y, q_msg.z], dtype=float)
    norm = float(np.sqrt(q @ q)) if np.all(np.isfinite(q)) else float("nan")
    if not abs(norm - 1.0) <= 1e-6:
        raise EntityError(code, f"{what}: orientation {q.tolist()} is not a unit quaternion (|q| = {norm:.9g})")
    return q if norm == 1.0 else q / norm


def finite_vector(v_msg, what, code):
    v = np.array([v_msg.x, v_msg.y, v_msg.z], dtype=float)
    if not np.all(np.isfinite(v)):
        raise EntityError(code, f"{what} has a NaN or infinite component: {v.tolist()}")
    return v


def read_resource(uri, resource_string, read_uri=None):
    """The text of a spawn resource (the uri wins when both are given);
    `read_uri(uri)` reads a uri's text (default: the local file)."""
    if uri:
        return (read_uri or read_uri_file)(uri)
    if not resource_string.strip():
        raise EntityError(SpawnEntity.Response.NO_RESOURCE, "both uri and resource_string are empty")
    return resource_string


def read_uri_file(uri):
    parsed = urlparse(uri)
    if parsed.scheme not in ("", "file"):
        raise EntityError(
            SpawnEntity.Response.UNSUPPORTED_FORMAT,
            f"uri {uri!r}: only local files (a path or file://) in the {SPAWN_FORMAT!r} format are supported",
        )
    path = Path(unquote(parsed.path) if parsed.scheme else uri)
    if path.suffix.lower() not in SPAWN_FILE_SUFFIXES:
        raise EntityError(
            SpawnEntity.Response.UNSUPPORTED_FORMAT,
            f"uri {uri!r}: the {SPAWN_FORMAT!r} format is a {'/'.join(SPAWN_FILE_SUFFIXES)} file",
        )
    try:
        return path.read_text()
    except OSError as exc:
        raise EntityError(Result.RESULT_NOT_FOUND, f"uri {uri!r}: cannot read it: {exc.strerror or exc}") from None


def parse_body_resource(text):
    """The body mapping held by a spawn resource's text."""
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise EntityError(SpawnEntity.Response.RESOURCE_PARSE_ERROR, f"resource is not YAML: {exc}") from None
    if isinstance(data, dict) and "bodies" in data:
        bodies = data["bodies"]
        if not isinstance(bodies, list) or len(bodies) != 1:
            code = SpawnEntity.Response.RESOURCE_PARSE_ERROR
            raise EntityError(code, "resource: `bodies` must list exactly one body")
        data = bodies[0]
    if not isinstance(data, dict):
        raise EntityError(
            SpawnEntity.Response.RESOURCE_PARSE_ERROR,
            f"resource: expected a mapping of body keys (shape, mass, ...), got {type(data).__name__}",
        )
    return dict(data)


class Entities:
    """The standard's entity operations on `world`, through `stepper` (whose
    queued and held commands a reset drops)."""

    def __init__(self, stepper, read_uri=None, max_bodies=MAX_BODIES):
        self.stepper = stepper
        self.max_bodies = int(max_bodies)  # as for a scene file (the node's max_bodies parameter)
        self.read_uri = read_uri  # uri -> text; the node records what it read, --resimulate reads that back
        self.spawned = {}  # name -> the body spec it was spawned with (world frame)
        self.namespaces = {}  # name -> entity namespace ('' for none)

    @property
    def world(self):
        return self.stepper.world

    # -- spawn and delete ----------------------------------------------------
    def spawn(self, request):
        """Spawn from a SpawnEntity request (or SpawnEntity.msg); its name."""
        if self.world.model.n >= self.max_bodies:
            raise EntityError(
                Result.RESULT_OPERATION_FAILED, f"the world holds {self.world.model.n} bodies, max_bodies = {self.max_bodies}"
            )
        resource = getattr(request, "entity_resource", None)
        uri = resource.uri if resource is not None else request.uri
        text = resource.resource_string if resource is not None else request.resource_string
        spec = parse_body_resource(read_resource(uri, text, self.read_uri))
        name = self._spawn_name(request.name or str(spec.get("name") or ""), request.allow_renaming)
        namespace = request.entity_namespace.strip("/") if request.entity_namespace != "/" else ""
        if request.entity_namespace and not _NAMESPACE_RE.match(namespace):
            raise EntityError(
                SpawnEntity.Response.NAMESPACE_INVALID,
                f"entity_namespace {request.entity_namespace!r}: tokens of letters, digits and _ separated by /",
            )
        spec["name"] = name
        spec.update(self._spawn_pose(spec, request.initial_pose))
        try:
            self.world.add_body(spec)
        except SceneError as exc:
            raise EntityError(SpawnEntity.Response.RESOURCE_PARSE_ERROR, str(exc)) from None
        self.spawned[name] = spec
        self.namespaces[name] = namespace
        return name

    def _spawn_name(self, wanted, allow_renaming):
        taken = self.world.model.index
        if wanted and not (NAME_RE.match(wanted) and wanted != "world"):
            raise EntityError(
                SpawnEntity.Response.NAME_INVALID,
                f"name {wanted!r}: letters, digits and _ starting with a letter, not 'world' (it names ROS topics)",
            )
        if wanted and wanted not in taken:
            return wanted
        if not allow_renaming:
            if not wanted:
                raise EntityError(SpawnEntity.Response.NAME_INVALID, "no name given (and allow_renaming is false)")
            raise EntityError(SpawnEntity.Response.NAME_NOT_UNIQUE, f"an entity named {wanted!r} exists")
        base = wanted or "entity"
        k = 1
        while f"{base}_{k}" in taken:
            k += 1
        return f"{base}_{k}"

    def _spawn_pose(self, spec, initial_pose):
        """World pose of a new body: the resource's own pose (if any) taken
        relative to `initial_pose`, which is in the world or a body's frame."""
        pose = initial_pose.pose
        code = SpawnEntity.Response.INVALID_POSE
        where = motion_from_msgs(pose.position, pose.orientation, None, None, "initial_pose", code)
        frame = self._frame(initial_pose.header.frame_id)
        own = {k: spec[k] for k in _POSE_KEYS if k in spec}
        if not own and frame is None:
            return {"position": where.pos.tolist(), "orientation": where.quat.tolist()}
        try:
            local = _spec_motion(spec)
        except (TypeError, ValueError):
            raise EntityError(SpawnEntity.Response.RESOURCE_PARSE_ERROR, "resource: position, orientation, velocity "
                              "and angular_velocity must be lists of 3 (orientation 4) numbers") from None  # fmt: skip
        placed = to_world(compose(where, local), frame)
        return {
            "position": placed.pos.tolist(),
            "orientation": placed.quat.tolist(),
            "velocity": placed.vel.tolist(),
            "angular_velocity": placed.omega.tolist(),
        }

    def delete(self, name):
        self._require(name)
        try:
            self.world.remove_body(name)
        except CommandError as exc:
            raise EntityError(Result.RESULT_OPERATION_FAILED, str(exc)) from None
        self.stepper.applier.forget_body(name)
        self.spawned.pop(name, None)
        self.namespaces.pop(name, None)

    # -- state ---------------------------------------------------------------
    def state(self, name, frame_id=""):
        """Motion of `name` in `frame_id` (world when empty)."""
        self._require(name)
        return to_frame(body_motion(self.world, name), self._frame(frame_id))

    def set_state(self, name, state):
        """Teleport from a simulation_interfaces/EntityState (pose and twist in
        state.header.frame_id; acceleration ignored: the engine holds none)."""
        self._require(name)
        if name == state.header.frame_id:
            raise EntityError(Result.RESULT_OPERATION_FAILED, f"{name!r} cannot be placed in its own frame")
        frame = self._frame(state.header.frame_id)
        pose, twist = state.pose, state.twist
        code = SetEntityState.Response.INVALID_POSE
        given = motion_from_msgs(pose.position, pose.orientation, twist.linear, twist.angular, "state", code)
        target = to_world(given, frame)
        try:
            self.world.set_body_state(name, target.pos, target.quat, target.vel, target.omega)
        except CommandError as exc:
            raise EntityError(Result.RESULT_OPERATION_FAILED, str(exc)) from None

    # -- reset -----------------------------------------------------------------
    def reset(self, scope):
        """ResetSimulation with the standard's scope bits; the queued
        commands it discarded."""
        r = ResetSimulation.Request
        scope = RESET_SCOPES if scope in (r.SCOPE_DEFAULT, r.SCOPE_ALL) else int(scope)
        if scope & ~RESET_SCOPES:
            raise EntityError(
                Result.RESULT_FEATURE_UNSUPPORTED,
                f"scope {scope}: supported are SCOPE_TIME (1), SCOPE_STATE (2), SCOPE_SPAWNED (4), their sums, "
                "SCOPE_DEFAULT (0) and SCOPE_ALL (255)",
            )
        if scope == RESET_SCOPES:
            self.spawned.clear()
            self.namespaces.clear()
            return self.stepper.reset()  # the scene as loaded, at time 0
        dropped = []
        if scope & r.SCOPE_SPAWNED:
            for name in reversed(list(self.spawned)):
                self.delete(name)
        if scope & r.SCOPE_STATE:
            dropped = self._reset_state()
        if scope & r.SCOPE_TIME:
            self.world.state.step_index = 0
            self.world.state.time = 0.0
        return dropped

    def _reset_state(self):
        """Every body back to its initial pose and twist (a scene body as the
        scene gives it, a spawned one as spawned); loads and contacts cleared."""
        w = self.world
        initial = w.scene_model.initial
        scene_index = w.scene_model.index
        for i, name in enumerate(w.model.names):
            if w.model.shape_type[i] == shapes.PLANE:
                continue  # a plane's pose is its normal and offset: it never moved
            if name in self.spawned:
                m = _spec_motion(self.spawned[name])
            else:
                j = scene_index[name]
                m = Motion(*(np.array(initial[k][j], dtype=float) for k in ("pos", "quat", "vel", "omega")))
            moving = not w.model.is_static[i]
            w.set_body_state(name, m.pos, m.quat, m.vel if moving else None, m.omega if moving else None)
        dropped = self.stepper.drop_commands()
        w.clear_loads()
        return dropped

    # -- helpers ---------------------------------------------------------------
    def _require(self, name):
        if name not in self.world.model.index:
            names = ", ".join(self.world.model.names)
            raise EntityError(Result.RESULT_NOT_FOUND, f"no entity named {name!r}; entities are {names}")

    def _frame(self, frame_id):
        try:
            return frame_motion(self.world, frame_id)
        except FrameError as exc:
            raise EntityError(Result.RESULT_NOT_FOUND, str(exc)) from None


def motion_from_msgs(position, orientation, linear, angular, what, code):
    zero = np.zeros(3)
    return Motion(
        finite_vector(position, f"{what} position", code),
        unit_quaternion_wxyz(orientation, what, code) if orientation is not None else np.array([1.0, 0, 0, 0]),
        finite_vector(linear, f"{what} linear velocity", code) if linear is not None else zero,
        finite_vector(angular, f"{what} angular velocity", code) if angular is not None else zero.copy(),
    )


def _spec_motion(spec):
    def vec(key, default):
        return np.array(spec.get(key, default), dtype=float).reshape(len(default))

    return Motion(vec("position", [0.0] * 3), vec("orientation", [1.0, 0, 0, 0]), vec("velocity", [0.0] * 3),
                  vec("angular_velocity", [0.0] * 3))  # fmt: skip


def compose(outer, inner):
    """`inner` given relative to the pose `outer` (at rest), in the frame `outer` is in."""
    return to_world(inner, Motion(outer.pos, outer.quat, np.zeros(3), np.zeros(3)))


def is_world_frame(frame_id):
    return is_world(frame_id)
