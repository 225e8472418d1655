"""The `physics` node: a timer steps the world, callbacks queue commands,
and every step's outputs are published (and recorded).

The node only translates between ROS and the engine; the step boundary lives
in `stepping.py`, message shapes in `msg_adapters`, the file in `recorder.py`.
"""

import time
import warnings

from geometry_msgs.msg import WrenchStamped
from rcl_interfaces.msg import SetParametersResult
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.serialization import deserialize_message
from std_srvs.srv import Empty, Trigger

from msg_adapters import sim_time_ns, wrench_arrays
from physics_core import CommandError, default_scene_path, load_scene

from .commands import (
    DISCARDED_ON_RESET,
    DROP_REASONS,
    MALFORMED,
    NON_FINITE,
    OUT_OF_RANGE,
    QUEUE_FULL,
    REJECTED,
    STATIC_BODY,
    UNKNOWN_FRAME,
    Command,
    check,
    out_of_range,
)
from .body_topics import ON_DEMAND_TICK_S, BodyTopics
from .diagnostics import DiagnosticsWindow
from .limits import MAX_QUEUED_PER_BODY, MAX_QUEUED_TOTAL, excerpt
from .outputs import Outputs
from .pacing import StepPacer
from .parameters import ParameterValueError, coerce, declare
from .qos import SERVICES
from .recording_control import RecordingControl
from .sim_actions import SimulateStepsServer
from .sim_services import SimServices
from .stepping import Stepper
from .unknown_bodies import UnknownBodyTopics

NODE_NAME = "physics"
# Wall time one timer callback may spend stepping before it lets the
# executor deliver commands and service calls.
TICK_BUDGET_S = 0.02
DROP_WARNING_PERIOD_S = 2.0
# How often the graph is searched for command topics of bodies the scene
# lacks (unknown_bodies.py) and, in a large world, for the bodies' own
# topics peers use (body_topics.py).
GRAPH_SCAN_S = 0.5
# How often the node checks which odometry and marker topics have readers
# (outputs.Outputs.refresh_subscribers): a new subscriber is served within this.
SUBSCRIBER_SCAN_S = 0.2
SUBSCRIBER_SCAN_PARTS = 10


class PhysicsNode(Node):
    def __init__(self, parameter_overrides=None, foxglove=None):
        """`foxglove`: a foxglove_server.FoxgloveBridge to serve the world to Foxglove, or None."""
        super().__init__(NODE_NAME, parameter_overrides=parameter_overrides or [])
        self.foxglove = foxglove
        self.settings = declare(self)
        self.scene_path = self.settings.scene or default_scene_path()
        # The loader warns about what it had to assume (e.g. friction pairs
        # it does not know); those belong in the node's log.
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            self.world = load_scene(self.scene_path, max_bodies=self.settings.max_bodies)
        for w in caught:
            self.get_logger().warning(str(w.message))
        self.model = self.world.model
        # More bodies than this at start: their own topics are made when peers use them (body_topics.py).
        self.on_demand = len(self.model.names) > self.settings.topics_on_demand_above
        if self.on_demand and self.settings.odometry == "all":
            raise ParameterValueError(_ALL_ODOMETRY_ON_DEMAND.format(n=len(self.model.names), s=self.settings))
        self.finished = False
        self.faulted = ""  # why the world cannot step, until reset
        self.paused = self.settings.paused
        self.stepper = Stepper(self.world, self.settings.command_timeout, error_types=(CommandError, ValueError))
        self.pacer = StepPacer(self.world.dt, self.settings.real_time_factor)
        self._free_running = False  # a free-run task is queued (_free_run)
        self.window = DiagnosticsWindow(self.world, DROP_REASONS)
        self._last_warning = {}
        self.unknown_bodies = UnknownBodyTopics(self, self.model.names, self._drop)

        self.recording = RecordingControl(self)
        self._pending_record = None  # a file opened by a `record` value being set
        first = self.recording.open(self.settings.record) if self.settings.record else None
        try:
            self._connect(first)
        except BaseException:
            if first is not None and self.recording.recorder is None:
                first.close()
            self.close()  # a half-built node still leaves a readable file
            raise

    @property
    def recorder(self):
        """The Recorder in use, or None."""
        return self.recording.recorder

    def _connect(self, recorder):
        """Publishers, subscriptions, services and timers; first outputs."""
        sink = None if self.foxglove is None else self.foxglove.attach(self, None)
        self.outputs = Outputs(
            self, self.model, sink, odometry=self.settings.odometry, on_demand=self.on_demand,
            history=self.recording.history, on_record_error=self.recording.failed,
        )
        if recorder is not None:
            self.recording.start(recorder, mid_session=False)
        self.body_topics = BodyTopics(self, self.outputs, self._command_callback, on_demand=self.on_demand)
        self.body_topics.add(self.model.names)

        self.create_service(Empty, "pause_physics", self._on_pause, qos_profile=SERVICES)
        self.create_service(Empty, "unpause_physics", self._on_unpause, qos_profile=SERVICES)
        self.create_service(Empty, "reset_simulation", self._on_reset, qos_profile=SERVICES)
        self.create_service(Empty, "reset_world", self._on_reset, qos_profile=SERVICES)
        self.create_service(Trigger, "~/step", self._on_step, qos_profile=SERVICES)
        self.sim = SimServices(self)  # the simulation_interfaces standard
        self.sim_actions = SimulateStepsServer(self, self.sim)
        self.add_on_set_parameters_callback(self._check_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)

        # Wall-clock timers: the node is the source of sim time, so its own
        # timers must never wait on /clock.
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        self._tick = self.create_timer(self.pacer.tick_period(), self._on_tick, clock=steady)
        self.create_timer(1.0, self._on_diagnostics, clock=steady)
        self.create_timer(GRAPH_SCAN_S, self._scan_graph, clock=steady)
        if self.on_demand:
            self.create_timer(ON_DEMAND_TICK_S, self.body_topics.make_queued, clock=steady)
        self.create_timer(
            SUBSCRIBER_SCAN_S / SUBSCRIBER_SCAN_PARTS,
            lambda: self.outputs.poll_subscribers(SUBSCRIBER_SCAN_PARTS),
            clock=steady,
        )

        t0 = sim_time_ns(self.world.time)
        self.outputs.send_bodies(self.world, t0, self.world.step_index)
        self.outputs.send_clock(t0, self.world.step_index)
        self.outputs.send_state(self.world, t0, self.world.step_index)

    # -- recording ----------------------------------------------------------
    def close(self):
        """Finish the recording, if any, and stop serving Foxglove. Called on every exit path."""
        if getattr(self, "sim_actions", None) is not None:
            self.sim_actions.close()
            self.sim_actions = None
        self._discard_pending_record()
        if getattr(self, "recording", None) is not None:
            self.recording.stop()
        if self.foxglove is not None:
            self.foxglove.close()

    def _discard_pending_record(self):
        pending, self._pending_record = getattr(self, "_pending_record", None), None
        if pending is not None:
            pending.close()

    # -- stepping -----------------------------------------------------------
    def _on_tick(self):
        if self.paused or self.finished:
            return
        if self.pacer.unlimited:
            self._start_free_run()
            return
        start = time.monotonic()
        self.pacer.took(self._step_within_budget(self.pacer.due(start), start))

    def _step_within_budget(self, due, start):
        """Up to `due` steps (None: as many as fit) within TICK_BUDGET_S of
        `start`; returns how many were taken."""
        taken = 0
        while due is None or taken < due:
            self._advance()
            taken += 1
            if self.paused or self.finished or time.monotonic() - start > TICK_BUDGET_S:
                break
        return taken

    # At real_time_factor 0 the node steps as fast as it can. Stepping from a
    # timer of period 0 kept that timer always due, and rclpy's EventsExecutor
    # then queued more and more timer events ahead of everything else: a
    # service call waited 1.6 s after 5 s of running and 24 s after 49 s. Each
    # budget of steps is instead a task that queues the next one behind what
    # arrived meanwhile, so a command or call waits at most one budget. The
    # tick timer (pacing.FREE_RUN_CHECK_S) starts the chain, and again after a
    # pause, a reset or a change of real_time_factor ends it.
    def _free_run_wanted(self):
        return self.pacer.unlimited and not (self.paused or self.finished) and self.executor is not None

    def _start_free_run(self):
        if not self._free_running and self._free_run_wanted():
            self._free_running = True
            self.executor.create_task(self._free_run)

    def _free_run(self):
        if not self._free_run_wanted():
            self._free_running = False
            return
        self._step_within_budget(None, time.monotonic())
        self.executor.create_task(self._free_run)

    def _advance(self, publish_all=False):
        loop_start = time.perf_counter()
        boundary = self.stepper.advance()
        applied_ns = sim_time_ns(boundary.time)
        for command in boundary.applied:
            self.outputs.record_command(command, applied_ns, boundary.step)
        for command, error in boundary.rejected:
            self._drop(command.topic, REJECTED, str(error))
        received = sum(1 for c in boundary.applied if c.raw)  # not the node's own timeout clears
        if boundary.isolated:
            self._isolated(boundary, applied_ns)
        if boundary.failure is not None:
            self.window.applied_total += received
            self._halt(boundary.failure)
            return
        w = self.world
        now_ns = sim_time_ns(w.time)
        self.outputs.send_clock(now_ns, w.step_index)
        if publish_all or w.step_index % self.settings.publish_every == 0:
            self.outputs.send_state(w, now_ns, w.step_index)
        self.window.stepped(received, time.perf_counter() - loop_start)
        duration = self.settings.duration
        if duration > 0 and w.time >= duration - 0.5 * w.dt:
            self.finished = True
            self.get_logger().info(f"reached duration {duration:g} s of sim time after {w.step_index} steps")

    def _isolated(self, boundary, time_ns):
        """Bodies frozen after a non-finite state: recorded as an event, logged."""
        self.outputs.record_isolation(boundary.isolated, time_ns, boundary.step)
        for fault in boundary.faults:
            self.get_logger().error(
                f"{excerpt(fault, 400)}: froze {', '.join(boundary.isolated)} where they were before the step; "
                "the rest of the world keeps simulating (reset_simulation brings them back)"
            )

    def _halt(self, error):
        """The state went non-finite: stop stepping until a reset."""
        self.faulted = str(error)
        self.set_parameters([Parameter("paused", Parameter.Type.BOOL, True)])
        self.get_logger().error(f"simulation stopped: {error}; call reset_simulation to start again")

    # -- commands -------------------------------------------------------------
    def _command_callback(self, body, kind):
        def on_message(raw):
            topic = self.body_topics.topics[(body, kind)]
            self.window.received_total += 1
            try:
                frame, force, torque = wrench_arrays(deserialize_message(raw, WrenchStamped))
            except Exception as exc:  # bytes from a peer: never let them reach the executor
                self._drop(topic, MALFORMED, f"not a WrenchStamped ({excerpt(exc, 100)})")
                return
            command = Command(kind, body, frame, force, torque, topic=topic, raw=raw)
            reason = check(command, self.world.model) or self.stepper.submit(command)
            if reason is not None:
                self._drop(topic, reason, _explain(reason, command, self.stepper.isolated))

        return on_message

    def _drop(self, topic, reason, detail):
        self.window.dropped(reason)
        now = time.monotonic()
        last, pending = self._last_warning.get(reason, (0.0, 0))
        if now - last < DROP_WARNING_PERIOD_S:
            self._last_warning[reason] = (last, pending + 1)
            return
        more = f" (+{pending} more since the last warning)" if pending else ""
        self.get_logger().warning(f"dropped a command on {excerpt(topic)}: {excerpt(detail)}{more}")
        self._last_warning[reason] = (now, 0)

    def _scan_graph(self):
        """One look at the graph's topics serves both scans."""
        topics = self.get_topic_names_and_types()
        self.unknown_bodies.scan(topics=topics)
        self.body_topics.found(topics)

    def bodies_changed(self, namespaces=None):
        """Bodies were spawned or deleted (entities.py): topics, outputs and
        the latched body list follow the world's new body list."""
        paths = {n: f"{ns}/{n}" for n, ns in (namespaces or {}).items() if ns}
        self.model = self.world.model
        self.body_topics.remove([n for n in self.outputs.model.names if n not in self.model.index])
        self.unknown_bodies.bodies_changed(self.model.names)  # a spawned body is no longer unknown
        self.outputs.prefix = paths
        self.outputs.bodies_changed(self.model)
        self.body_topics.add(self.model.names, paths)
        if self.foxglove is not None:
            self.foxglove.bodies_changed(self.model)
        t = sim_time_ns(self.world.time)
        self.outputs.send_bodies(self.world, t, self.world.step_index)

    # -- services -------------------------------------------------------------
    def _on_pause(self, _request, response):
        self.set_parameters([Parameter("paused", Parameter.Type.BOOL, True)])
        return response

    def _on_unpause(self, _request, response):
        self.set_parameters([Parameter("paused", Parameter.Type.BOOL, False)])
        return response

    def _on_reset(self, _request, response):
        discarded = len(self.sim.entities.reset(0))  # as ResetSimulation SCOPE_ALL: spawned bodies go too
        for _ in range(discarded):
            self.window.dropped(DISCARDED_ON_RESET)
        self.sim.follow_bodies()
        self.outputs.record_reset(sim_time_ns(self.world.time), self.world.step_index)
        self.sim.after_reset(True)
        note = f"; {discarded} queued commands discarded" if discarded else ""
        self.get_logger().info(f"world reset to its initial state{note}")
        return response

    def _on_step(self, _request, response):
        if self.faulted:
            response.success = False
            response.message = f"cannot step: {self.faulted}; call reset_simulation"
            return response
        if not self.paused:
            response.success = False
            response.message = "not paused: call pause_physics first"
            return response
        self.outputs.refresh_subscribers()  # whoever asked for the step sees its outputs
        self._advance(publish_all=True)
        if self.faulted:
            response.success = False
            response.message = f"the step failed: {self.faulted}"
            return response
        response.success = True
        response.message = f"step {self.world.step_index}, t = {self.world.time:.9g} s"
        return response

    # -- parameters -------------------------------------------------------------
    def _check_parameters(self, params):
        for p in params:
            reason = self._refusal(p)
            if reason:
                return SetParametersResult(successful=False, reason=reason)
        return self._check_record([p.value for p in params if p.name == "record"])

    def _refusal(self, p):
        """Why the value of parameter `p` cannot be taken now, or None."""
        try:
            coerce(p.name, p.value)
        except ParameterValueError as exc:
            return str(exc)
        if p.name == "paused" and p.value is False and self.faulted:
            return f"{self.faulted}; call reset_simulation first"
        if p.name == "odometry" and p.value == "all" and self.on_demand:
            return _ALL_ODOMETRY_ON_DEMAND.format(n=len(self.model.names), s=self.settings)
        return None

    def _check_record(self, paths):
        """A new `record` path is opened here, once every other value passed,
        so that a path --record would refuse is refused the same way."""
        self._discard_pending_record()
        if paths and paths[-1]:
            try:
                self._pending_record = self.recording.open(paths[-1])
            except ParameterValueError as exc:
                return SetParametersResult(successful=False, reason=str(exc))
        return SetParametersResult(successful=True)

    def _apply_parameters(self, params):
        for p in params:
            value = coerce(p.name, p.value)
            setattr(self.settings, p.name, value)
            if p.name == "paused" and value != self.paused:
                self.paused = value
                self.pacer.restart(time.monotonic())
                self.get_logger().info("paused" if value else "running")
            elif p.name == "real_time_factor":
                self.pacer = StepPacer(self.world.dt, value)
                self._tick.timer_period_ns = int(self.pacer.tick_period() * 1e9)
            elif p.name == "command_timeout":
                self.stepper.command_timeout = value
            elif p.name == "odometry":
                self.outputs.set_odometry(value)
            elif p.name == "record":
                pending, self._pending_record = self._pending_record, None
                if pending is not None:
                    self.recording.start(pending)
                else:
                    self.recording.stop()
        self._start_free_run()  # unpaused, or set to run free: not waiting for the tick timer

    # -- diagnostics ------------------------------------------------------------
    def _on_diagnostics(self):
        msg = self.window.report(
            sim_time_ns(self.world.time),
            hardware_id=self.get_fully_qualified_name(),
            paused=self.paused,
            fault=self.faulted,
            target_rtf=self.settings.real_time_factor,
            recording=self.recording.path,
            recording_error=self.recording.error,
            isolated=self.stepper.isolated,
            queued=self.stepper.pending,
            unknown_topics=(len(self.unknown_bodies.subscriptions), len(self.unknown_bodies.ignored)),
            body_topics=(self.body_topics.made, self.body_topics.waiting),
        )
        self.outputs.send_diagnostics(msg, sim_time_ns(self.world.time), self.world.step_index)


_ALL_ODOMETRY_ON_DEMAND = (
    "parameter 'odometry' = 'all' needs an odometry publisher for every body, and this world of {n} bodies "
    "makes its bodies' topics on demand (more than topics_on_demand_above = {s.topics_on_demand_above}); "
    "raise topics_on_demand_above to make them all at start"
)


def _explain(reason, command, isolated=()):
    if reason == NON_FINITE:
        return "force or torque has a NaN or infinite component"
    if reason == OUT_OF_RANGE:
        return out_of_range(command) + " (physics_core/command_limits.py)"
    if reason == UNKNOWN_FRAME:
        return (
            f"frame_id {excerpt(command.frame, 60)!r} is neither 'world' (or empty) "
            f"nor the body's own name {command.body!r}"
        )
    if reason == STATIC_BODY:
        if command.body in isolated:
            return f"{command.body!r} was frozen after its state went non-finite; reset_simulation brings it back"
        return f"{command.body!r} is static and takes no forces"
    if reason == QUEUE_FULL:
        return (
            f"the command queue is full ({MAX_QUEUED_PER_BODY} per body, {MAX_QUEUED_TOTAL} in all, "
            "until the next step applies them); the newest command is dropped"
        )
    return reason
