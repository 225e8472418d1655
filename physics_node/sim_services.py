"""The ROS simulator standard (simulation_interfaces, Jazzy 1.5.x) on the node.

Services under the node (`~/spawn_entity`, `~/step_simulation`, ... — the
standard's names in snake case, as Gazebo offers them under its server
node), answering with the standard's Result codes; the SimulateSteps action
is in sim_actions.py. Every request that changes the world is recorded as
received on `~/requests/<service>` (its request type) at the sim time and
step it took effect, so `physics-replay --resimulate` re-applies it through
the same `Entities` code (resimulate.py). A bad request gets an error code
and a message; the node keeps running.
"""

import time

from rclpy.parameter import Parameter
from simulation_interfaces import srv
from simulation_interfaces.msg import EntityState, Result, SimulationState, SimulatorFeatures, SpawnResult

from msg_adapters import sim_time_ns

from .entities import SPAWN_FORMAT, Entities, EntityError, read_uri_file
from .sim_requests import SPAWN_ATTACHMENT_PREFIX, SPAWN_MEDIA_TYPE
from .entity_queries import bounds, info, matching
from .sim_requests import REQUESTS_SUFFIX, apply_request, state_msg

F = SimulatorFeatures
FEATURES = [
    F.SPAWNING, F.SPAWNING_ENTITIES, F.SPAWNING_RESOURCE_STRING, F.DELETING,
    F.ENTITY_TAGS, F.ENTITY_CATEGORIES, F.ENTITY_BOUNDS, F.ENTITY_BOUNDS_BOX,
    F.ENTITY_STATE_GETTING, F.ENTITY_STATE_SETTING, F.ENTITY_INFO_GETTING,
    F.SIMULATION_RESET, F.SIMULATION_RESET_TIME, F.SIMULATION_RESET_STATE, F.SIMULATION_RESET_SPAWNED,
    F.SIMULATION_STATE_GETTING, F.SIMULATION_STATE_SETTING, F.SIMULATION_STATE_PAUSE,
    F.STEP_SIMULATION_SINGLE, F.STEP_SIMULATION_MULTIPLE, F.STEP_SIMULATION_ACTION,
]  # fmt: skip
CUSTOM_INFO = (
    f"physics_node: spawn format {SPAWN_FORMAT!r} = YAML/JSON with one body in the scene file's body keys; "
    "entity names are body names (also the TF child frames); acceleration in EntityState is not computed (zero)"
)
OK = Result.RESULT_OK


def ok(message=""):
    return Result(result=OK, error_message=message)


def failed(code, message):
    return Result(result=int(code), error_message=message)


class SimServices:
    """The standard's services on `node` (a physics_node.node.PhysicsNode)."""

    def __init__(self, node):
        self.node = node
        self.entities = Entities(node.stepper, read_uri=self._read_and_record_uri, max_bodies=node.settings.max_bodies)
        self.stopped = False  # STATE_STOPPED: paused at the initial state until played
        self.requests_topic = node.get_fully_qualified_name() + REQUESTS_SUFFIX
        for name, kind, handler in (
            ("get_simulator_features", srv.GetSimulatorFeatures, self._features),
            ("spawn_entity", srv.SpawnEntity, self._changing("spawn_entity")),
            ("spawn_entities", srv.SpawnEntities, self._changing("spawn_entities")),
            ("delete_entity", srv.DeleteEntity, self._changing("delete_entity")),
            ("set_entity_state", srv.SetEntityState, self._changing("set_entity_state")),
            ("reset_simulation", srv.ResetSimulation, self._changing("reset_simulation")),
            ("set_simulation_state", srv.SetSimulationState, self._changing("set_simulation_state")),
            ("get_entities", srv.GetEntities, self._get_entities),
            ("get_entities_states", srv.GetEntitiesStates, self._get_entities_states),
            ("get_entity_info", srv.GetEntityInfo, self._get_entity_info),
            ("get_entity_state", srv.GetEntityState, self._get_entity_state),
            ("get_entity_bounds", srv.GetEntityBounds, self._get_entity_bounds),
            ("get_simulation_state", srv.GetSimulationState, self._get_simulation_state),
            ("step_simulation", srv.StepSimulation, self._step_simulation),
        ):
            node.create_service(kind, f"~/{name}", self._guarded(name, handler))

    def _guarded(self, name, handler):
        """A handler that cannot take the node down: an unexpected error is
        logged and answered with RESULT_OPERATION_FAILED."""

        def handle(request, response):
            try:
                return handler(request, response)
            except Exception as exc:  # noqa: BLE001 - the node keeps running whatever a request does
                self.node.get_logger().error(f"{name}: {type(exc).__name__}: {exc}")
                if hasattr(response, "result"):
                    response.result = failed(Result.RESULT_OPERATION_FAILED, f"internal error: {type(exc).__name__}: {exc}")
                return response

        return handle

    # -- what changes the world ----------------------------------------------
    def _changing(self, name):
        def handle(request, response):
            node = self.node
            w = node.world
            self.node.outputs.record_request(f"{self.requests_topic}/{name}", request, sim_time_ns(w.time), w.step_index)
            try:
                apply_request(self, name, request, response)
            except EntityError as exc:
                response.result = failed(exc.code, exc.message)
            self.follow_bodies()
            return response

        return handle

    def _read_and_record_uri(self, uri):
        """A spawn file's text, kept in the recording (as an attachment named
        by the uri) so --resimulate spawns the same body without the file."""
        text = read_uri_file(uri)
        t = sim_time_ns(self.node.world.time)
        self.node.recording.add_attachment(SPAWN_ATTACHMENT_PREFIX + uri, text.encode(), SPAWN_MEDIA_TYPE, t)
        return text

    def follow_bodies(self):
        """Topics and outputs for the world's body list, if it changed."""
        if tuple(self.node.outputs.model.names) != tuple(self.node.world.model.names):
            self.node.bodies_changed(self.entities.namespaces)

    def after_reset(self, scope_cleared_state=True):
        """What the node does after any reset: outputs at the new state."""
        node = self.node
        self.follow_bodies()
        node.outputs.refresh_subscribers()
        t0, step = sim_time_ns(node.world.time), node.world.step_index
        node.outputs.send_clock(t0, step)
        node.outputs.send_state(node.world, t0, step)
        node.pacer.restart(time.monotonic())
        node.finished = False
        if scope_cleared_state:
            node.faulted = ""

    @property
    def faulted(self):
        return self.node.faulted

    def static_moved(self):
        w = self.node.world
        self.node.outputs.send_bodies(w, sim_time_ns(w.time), w.step_index)

    def quit(self):
        self.node.finished = True
        self.node.get_logger().info("SetSimulationState STATE_QUITTING: stopping")

    def set_paused(self, paused):
        self.node.set_parameters([Parameter("paused", Parameter.Type.BOOL, bool(paused))])

    def simulation_state(self):
        if not self.node.paused:
            self.stopped = False  # played (e.g. through unpause_physics)
            return SimulationState.STATE_PLAYING
        return SimulationState.STATE_STOPPED if self.stopped else SimulationState.STATE_PAUSED

    # -- queries ---------------------------------------------------------------
    def _features(self, _request, response):
        response.features = SimulatorFeatures(features=FEATURES, spawn_formats=[SPAWN_FORMAT], custom_info=CUSTOM_INFO)
        return response

    def _get_entities(self, request, response):
        try:
            rows = matching(self.node.world, request.filters, self.entities.spawned)
        except EntityError as exc:
            response.result = failed(exc.code, exc.message)
            return response
        response.entities = [self.node.world.model.names[i] for i in rows]
        response.result = ok()
        return response

    def _get_entities_states(self, request, response):
        w = self.node.world
        try:
            rows = matching(w, request.filters, self.entities.spawned)
        except EntityError as exc:
            response.result = failed(exc.code, exc.message)
            return response
        response.entities = [w.model.names[i] for i in rows]
        response.states = [state_msg(self.entities.state(n), "world", w.time) for n in response.entities]
        response.result = ok()
        return response

    def _entity_index(self, name, response):
        i = self.node.world.model.index.get(name)
        if i is None:
            names = ", ".join(self.node.world.model.names)
            response.result = failed(Result.RESULT_NOT_FOUND, f"no entity named {name!r}; entities are {names}")
        return i

    def _get_entity_info(self, request, response):
        i = self._entity_index(request.entity, response)
        if i is not None:
            response.info = info(self.node.world.model, i, self.entities.spawned)
            response.result = ok()
        return response

    def _get_entity_bounds(self, request, response):
        i = self._entity_index(request.entity, response)
        if i is not None:
            response.bounds = bounds(self.node.world.model, i)
            response.result = ok()
        return response

    def _get_entity_state(self, request, response):
        w = self.node.world
        try:
            motion = self.entities.state(request.entity)
        except EntityError as exc:
            response.result = failed(exc.code, exc.message)
            return response
        response.state = state_msg(motion, "world", w.time)
        response.result = ok()
        return response

    def _get_simulation_state(self, _request, response):
        response.state = SimulationState(state=self.simulation_state())
        response.result = ok()
        return response

    # -- stepping ---------------------------------------------------------------
    def step(self, steps):
        """Step `steps` times while paused; None, or why it cannot."""
        node = self.node
        if node.faulted:
            return f"cannot step: {node.faulted}; reset the simulation"
        if not node.paused:
            return "the simulation is playing: pause it first (SetSimulationState STATE_PAUSED)"
        self.stopped = False
        node.outputs.refresh_subscribers()  # whoever asked for the steps sees their outputs
        for _ in range(int(steps)):
            node._advance(publish_all=True)
            if node.faulted:
                return f"the step failed: {node.faulted}"
        return None

    def _step_simulation(self, request, response):
        w = self.node.world
        self.node.outputs.record_request(f"{self.requests_topic}/step_simulation", request, sim_time_ns(w.time), w.step_index)
        if request.steps < 1:
            response.result = failed(Result.RESULT_OPERATION_FAILED, f"steps = {request.steps}: ask for 1 or more")
            return response
        why = self.step(request.steps)
        response.result = ok(f"step {w.step_index}, t = {w.time:.9g} s") if why is None else failed(Result.RESULT_OPERATION_FAILED, why)
        return response


def spawn_results(entities, requests):
    """SpawnEntities: each request in order; (overall Result, SpawnResults)."""
    results = []
    for request in requests:
        try:
            name = entities.spawn(request)
            results.append(SpawnResult(result=ok(), entity_name=name))
        except EntityError as exc:
            results.append(SpawnResult(result=failed(exc.code, exc.message)))
    bad = sum(r.result.result != OK for r in results)
    if bad:
        code = srv.SpawnEntities.Response.ENTITIES_SPAWN_FAILED
        return failed(code, f"{bad} of {len(requests)} spawn requests failed: see results"), results
    return ok(), results


__all__ = ["SimServices", "spawn_results", "EntityState"]
