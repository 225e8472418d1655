"""The `physics` node: a timer steps the world, callbacks queue commands,
and every step's outputs are published (and recorded).

The node only translates between ROS and the engine; the step boundary lives
in `stepping.py`, message shapes in `msg_adapters`, the file in `recorder.py`.
"""

import os
import re
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
    DROP_REASONS,
    IMPULSE,
    NON_FINITE,
    REJECTED,
    STATIC_BODY,
    UNKNOWN_BODY,
    UNKNOWN_FRAME,
    WRENCH,
    Command,
    check,
)
from .diagnostics import DiagnosticsWindow
from .outputs import Outputs
from .pacing import StepPacer
from .parameters import ParameterValueError, coerce, declare
from .qos import COMMANDS, per_body_events
from .recorder import INTEGRATION_METADATA, SCENE_MEDIA_TYPE, SESSION_METADATA, Recorder, chunk_size_for
from .session import engine_version, integration_metadata, session_metadata
from .stepping import Stepper

NODE_NAME = "physics"
# Wall time one timer callback may spend stepping before it lets the
# executor deliver commands and service calls.
TICK_BUDGET_S = 0.02
DROP_WARNING_PERIOD_S = 2.0
# How often the graph is searched for command topics of bodies the scene lacks.
UNKNOWN_BODY_SCAN_S = 0.5
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
            self.world = load_scene(self.scene_path)
        for w in caught:
            self.get_logger().warning(str(w.message))
        self.model = self.world.model
        self.finished = False
        self.faulted = ""  # why the world cannot step, until reset
        self.paused = self.settings.paused
        self.stepper = Stepper(self.world, self.settings.command_timeout, error_types=(CommandError, ValueError))
        self.pacer = StepPacer(self.world.dt, self.settings.real_time_factor)
        self.window = DiagnosticsWindow(self.world, DROP_REASONS)
        self._last_warning = {}
        self._unknown_body_subs = {}

        self.recorder = None
        if self.settings.record:
            self.recorder = Recorder(
                self.settings.record,
                chunk_size=chunk_size_for(len(self.model.names)),
                library=f"physics_node {engine_version()}",
            ).open()
        try:
            self._connect()
        except BaseException:
            self.close()  # a half-built node still leaves a readable file
            raise

    def _connect(self):
        """Publishers, subscriptions, services and timers; first outputs."""
        sink = self.recorder if self.foxglove is None else self.foxglove.attach(self, self.recorder)
        self.outputs = Outputs(self, self.model, sink, odometry=self.settings.odometry)
        if self.recorder is not None:
            self._start_recording()

        self._command_topics = {}
        _, command_events = per_body_events()
        for name in self.model.names:
            for kind in (WRENCH, IMPULSE):
                sub = self.create_subscription(
                    WrenchStamped,
                    f"~/{name}/{kind}",
                    self._command_callback(name, kind),
                    COMMANDS,
                    raw=True,
                    event_callbacks=command_events,
                )
                self._command_topics[(name, kind)] = sub.topic_name

        self.create_service(Empty, "pause_physics", self._on_pause)
        self.create_service(Empty, "unpause_physics", self._on_unpause)
        self.create_service(Empty, "reset_simulation", self._on_reset)
        self.create_service(Empty, "reset_world", self._on_reset)
        self.create_service(Trigger, "~/step", self._on_step)
        self.add_on_set_parameters_callback(self._check_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)

        # Wall-clock timers: the node is the source of sim time, so its own
        # timers must never wait on /clock.
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        self._tick = self.create_timer(self.pacer.tick_period(), self._on_tick, clock=steady)
        self.create_timer(1.0, self._on_diagnostics, clock=steady)
        self.create_timer(UNKNOWN_BODY_SCAN_S, self._scan_for_unknown_bodies, clock=steady)
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
    def _start_recording(self):
        name = os.path.basename(self.scene_path) or "scene.yaml"
        text = self.model.source_text
        self.recorder.add_attachment(name, text.encode(), SCENE_MEDIA_TYPE)
        self.recorder.add_metadata(
            SESSION_METADATA, session_metadata(self.settings, self.scene_path, self.world, self.get_fully_qualified_name())
        )

    def close(self):
        """Finish the recording, if any, and stop serving Foxglove. Called on every exit path."""
        if self.recorder is not None:
            try:
                stats = integration_metadata(self.world)
                if stats and self.recorder.is_open:
                    self.recorder.add_metadata(INTEGRATION_METADATA, stats)
            finally:
                self.recorder.close()
        if self.foxglove is not None:
            self.foxglove.close()

    # -- stepping -----------------------------------------------------------
    def _on_tick(self):
        if self.paused or self.finished:
            return
        start = time.monotonic()
        due = self.pacer.due(start)
        taken = 0
        while due is None or taken < due:
            self._advance()
            taken += 1
            if self.paused or self.finished or time.monotonic() - start > TICK_BUDGET_S:
                break
        self.pacer.took(taken)

    def _advance(self, publish_all=False):
        loop_start = time.perf_counter()
        boundary = self.stepper.advance()
        applied_ns = sim_time_ns(boundary.time)
        for command in boundary.applied:
            self.outputs.record_command(command, applied_ns, boundary.step)
        for command, error in boundary.rejected:
            self._drop(command.topic, REJECTED, str(error))
        if boundary.failure is not None:
            self._halt(boundary.failure)
            return
        w = self.world
        now_ns = sim_time_ns(w.time)
        self.outputs.send_clock(now_ns, w.step_index)
        if publish_all or w.step_index % self.settings.publish_every == 0:
            self.outputs.send_state(w, now_ns, w.step_index)
        self.window.stepped(len(boundary.applied), time.perf_counter() - loop_start)
        duration = self.settings.duration
        if duration > 0 and w.time >= duration - 0.5 * w.dt:
            self.finished = True
            self.get_logger().info(f"reached duration {duration:g} s of sim time after {w.step_index} steps")

    def _halt(self, error):
        """The state went non-finite: stop stepping until a reset."""
        self.faulted = str(error)
        self.set_parameters([Parameter("paused", Parameter.Type.BOOL, True)])
        self.get_logger().error(f"simulation stopped: {error}; call reset_simulation to start again")

    # -- commands -------------------------------------------------------------
    def _command_callback(self, body, kind):
        def on_message(raw):
            msg = deserialize_message(raw, WrenchStamped)
            frame, force, torque = wrench_arrays(msg)
            topic = self._command_topics[(body, kind)]
            command = Command(kind, body, frame, force, torque, topic=topic, raw=raw)
            reason = check(command, self.model)
            if reason is not None:
                self._drop(topic, reason, _explain(reason, command))
                return
            self.stepper.submit(command)

        return on_message

    def _drop(self, topic, reason, detail):
        self.window.dropped(reason)
        now = time.monotonic()
        last, pending = self._last_warning.get(reason, (0.0, 0))
        if now - last < DROP_WARNING_PERIOD_S:
            self._last_warning[reason] = (last, pending + 1)
            return
        more = f" (+{pending} more since the last warning)" if pending else ""
        self.get_logger().warning(f"dropped a command on {topic}: {detail}{more}")
        self._last_warning[reason] = (now, 0)

    def _scan_for_unknown_bodies(self):
        """Count commands sent to bodies the scene does not have: the graph is
        scanned for command topics under this node and each unknown one gets a
        subscription that only drops and counts."""
        prefix = re.escape(self.get_fully_qualified_name())
        pattern = re.compile(rf"^{prefix}/([^/]+)/({WRENCH}|{IMPULSE})$")
        for topic, _types in self.get_topic_names_and_types():
            match = pattern.match(topic)
            if not match or match.group(1) in self.model.index or topic in self._unknown_body_subs:
                continue
            body = match.group(1)
            detail = f"no body named {body!r}; bodies are {', '.join(self.model.names)}"

            def on_unknown(_raw, topic=topic, detail=detail):
                self._drop(topic, UNKNOWN_BODY, detail)

            self._unknown_body_subs[topic] = self.create_subscription(
                WrenchStamped, topic, on_unknown, COMMANDS, raw=True, event_callbacks=per_body_events()[1]
            )

    # -- services -------------------------------------------------------------
    def _on_pause(self, _request, response):
        self.set_parameters([Parameter("paused", Parameter.Type.BOOL, True)])
        return response

    def _on_unpause(self, _request, response):
        self.set_parameters([Parameter("paused", Parameter.Type.BOOL, False)])
        return response

    def _on_reset(self, _request, response):
        discarded = self.stepper.reset()
        self.outputs.refresh_subscribers()
        t0 = sim_time_ns(self.world.time)
        step = self.world.step_index
        self.outputs.record_reset(t0, step)
        self.outputs.send_clock(t0, step)
        self.outputs.send_state(self.world, t0, step)
        self.pacer.restart(time.monotonic())
        self.finished = False
        self.faulted = ""
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
            try:
                coerce(p.name, p.value)
            except ParameterValueError as exc:
                return SetParametersResult(successful=False, reason=str(exc))
            if p.name == "paused" and p.value is False and self.faulted:
                return SetParametersResult(successful=False, reason=f"{self.faulted}; call reset_simulation first")
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

    # -- diagnostics ------------------------------------------------------------
    def _on_diagnostics(self):
        msg = self.window.report(
            sim_time_ns(self.world.time),
            hardware_id=self.get_fully_qualified_name(),
            paused=self.paused,
            fault=self.faulted,
            target_rtf=self.settings.real_time_factor,
            recording=self.recorder.path if self.recorder else "",
        )
        self.outputs.send_diagnostics(msg, sim_time_ns(self.world.time), self.world.step_index)


def _explain(reason, command):
    if reason == NON_FINITE:
        return "force or torque has a NaN or infinite component"
    if reason == UNKNOWN_FRAME:
        return f"frame_id {command.frame!r} is neither 'world' (or empty) nor the body's own name {command.body!r}"
    if reason == STATIC_BODY:
        return f"{command.body!r} is static and takes no forces"
    return reason
