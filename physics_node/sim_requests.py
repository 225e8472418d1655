"""The simulator-standard requests that change the world, applied to a
context: the live node's SimServices, or resimulate's stand-in. Both run
this one function, so a recorded request does the same thing again.

A context has `entities` (entities.Entities), `stopped`, and the hooks
`set_paused(bool)`, `after_reset(state_cleared)`, `static_moved()` and
`simulation_state()`.
"""

from geometry_msgs.msg import Point, Pose, Quaternion, Twist, Vector3
from simulation_interfaces.msg import EntityState, Result, SimulationState
from simulation_interfaces.srv import ResetSimulation, SetSimulationState

from msg_adapters import sim_time_ns, time_msg

from .entities import EntityError

# Recorded requests travel on <node>/requests/<service name>.
REQUESTS_SUFFIX = "/requests"
# A file spawned from a uri is attached to the recording as read, under this
# media type and the name `spawn:<uri>`, in the order read.
SPAWN_MEDIA_TYPE = "application/vnd.physics-node.spawn+yaml"
SPAWN_ATTACHMENT_PREFIX = "spawn:"
CHANGING = ("spawn_entity", "spawn_entities", "delete_entity", "set_entity_state", "reset_simulation",
            "set_simulation_state")  # fmt: skip


def _ok():
    return Result(result=Result.RESULT_OK)


def apply_request(ctx, name, request, response):
    """Apply one request; fills `response` or raises EntityError."""
    e = ctx.entities
    if name == "spawn_entity":
        response.entity_name = e.spawn(request)
    elif name == "spawn_entities":
        from .sim_services import spawn_results

        response.result, response.results = spawn_results(e, request.spawn_requests)
        return response
    elif name == "delete_entity":
        e.delete(request.entity)
    elif name == "set_entity_state":
        e.set_state(request.entity, request.state)
        if e.world.model.is_static[e.world.model.index[request.entity]]:
            ctx.static_moved()
    elif name == "reset_simulation":
        e.reset(request.scope)
        ctx.after_reset(request.scope in (0, 255) or bool(request.scope & ResetSimulation.Request.SCOPE_STATE))
    elif name == "set_simulation_state":
        _set_simulation_state(ctx, request.state.state)
    else:
        raise ValueError(f"not a world-changing request: {name}")
    response.result = _ok()
    return response


def _set_simulation_state(ctx, target):
    """The standard's transitions: stopped = paused at the initial state
    (a full reset); played and paused as `paused`; quitting ends the node."""
    S, R = SimulationState, SetSimulationState.Response
    current = ctx.simulation_state()
    if target == current:
        raise EntityError(R.ALREADY_IN_TARGET_STATE, f"the simulation is already in state {target}")
    if target == S.STATE_PLAYING:
        if getattr(ctx, "faulted", ""):
            raise EntityError(R.STATE_TRANSITION_ERROR, f"cannot play: {ctx.faulted}; reset the simulation")
        ctx.stopped = False
        ctx.set_paused(False)
    elif target == S.STATE_PAUSED:
        if current == S.STATE_STOPPED:
            raise EntityError(R.INCORRECT_TRANSITION, "pausing a stopped simulation: play it, or step it")
        ctx.set_paused(True)
    elif target == S.STATE_STOPPED:
        ctx.set_paused(True)
        ctx.entities.reset(ResetSimulation.Request.SCOPE_ALL)
        ctx.after_reset(True)
        ctx.stopped = True
    elif target == S.STATE_QUITTING:
        ctx.quit()
    elif target in (S.STATE_NO_WORLD, S.STATE_LOADING_WORLD):
        raise EntityError(R.INCORRECT_TRANSITION, "the world cannot be unloaded or loaded (no LoadWorld/UnloadWorld)")
    else:
        raise EntityError(Result.RESULT_FEATURE_UNSUPPORTED, f"unknown simulation state {target}")


def state_msg(motion, frame_id, time_s):
    """simulation_interfaces/EntityState of a Motion (acceleration: zero)."""
    msg = EntityState()
    msg.header.frame_id = frame_id
    msg.header.stamp = time_msg(sim_time_ns(time_s))
    p, q = motion.pos, motion.quat
    msg.pose = Pose(
        position=Point(x=float(p[0]), y=float(p[1]), z=float(p[2])),
        orientation=Quaternion(w=float(q[0]), x=float(q[1]), y=float(q[2]), z=float(q[3])),
    )
    v, w = motion.vel, motion.omega
    msg.twist = Twist(
        linear=Vector3(x=float(v[0]), y=float(v[1]), z=float(v[2])),
        angular=Vector3(x=float(w[0]), y=float(w[1]), z=float(w[2])),
    )
    return msg
