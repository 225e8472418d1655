"""The standard's SimulateSteps action, `~/simulate_steps` of the node.

rclpy's EventsExecutor (the node's default, main.py) does not resume an
action's execute coroutine, so the action server lives on a small helper
node (`<node>_actions`) spun by a MultiThreadedExecutor on its own thread,
under the physics node's name. The world is only ever touched on the main
thread: the execute callback asks for one step at a time through
`MainThreadCalls` (a queue and a main-thread timer that runs only while
calls are waiting: the EventsExecutor has no guard conditions) and waits
for it, publishes the feedback, and checks for a cancel between steps.
"""

import queue
import threading

import rclpy
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rclpy.qos import QoSProfile, ReliabilityPolicy
from simulation_interfaces.action import SimulateSteps
from simulation_interfaces.msg import Result

from msg_adapters import sim_time_ns

ACTION_NAME = "simulate_steps"
# One feedback per step comes fast: a deep reliable queue keeps each one for
# a client that asks for a deep queue too (rclpy's default client keeps 10).
FEEDBACK = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)


class MainThreadCalls:
    """Run functions on the thread that spins `node`, from other threads."""

    POLL_S = 0.0005  # the timer's period while calls wait
    REARM_S = 0.05  # a caller re-arms the timer this often (it may have just stopped)

    def __init__(self, node):
        from rclpy.clock import Clock, ClockType

        self._calls = queue.SimpleQueue()
        self._timer = node.create_timer(self.POLL_S, self._drain, clock=Clock(clock_type=ClockType.STEADY_TIME))
        self._timer.cancel()

    def _drain(self):
        while True:
            try:
                fn, done, box = self._calls.get_nowait()
            except queue.Empty:
                self._timer.cancel()
                return
            try:
                box.append((fn(), None))
            except Exception as exc:  # handed back to the caller's thread
                box.append((None, exc))
            done.set()

    def call(self, fn, timeout=None):
        done, box = threading.Event(), []
        self._calls.put((fn, done, box))
        waited = 0.0
        self._timer.reset()
        while not done.wait(self.REARM_S):
            waited += self.REARM_S
            if timeout is not None and waited >= timeout:
                raise TimeoutError("the physics thread did not answer")
            self._timer.reset()
        value, error = box[0]
        if error is not None:
            raise error
        return value


class SimulateStepsServer:
    def __init__(self, physics_node, services):
        self.services = services
        self.calls = MainThreadCalls(physics_node)
        self.node = rclpy.create_node(
            physics_node.get_name() + "_actions", namespace=physics_node.get_namespace(), context=physics_node.context
        )
        self.requests_topic = f"{services.requests_topic}/{ACTION_NAME}"
        self.server = ActionServer(
            self.node,
            SimulateSteps,
            f"{physics_node.get_fully_qualified_name()}/{ACTION_NAME}",
            execute_callback=self._execute,
            goal_callback=lambda _goal: GoalResponse.ACCEPT,
            cancel_callback=lambda _handle: CancelResponse.ACCEPT,
            callback_group=ReentrantCallbackGroup(),
            feedback_pub_qos_profile=FEEDBACK,
        )
        self.executor = MultiThreadedExecutor(num_threads=2, context=physics_node.context)
        self.executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, name="simulate_steps", daemon=True)
        self._thread.start()

    def _spin(self):
        try:
            self.executor.spin()
        except Exception:  # the context shut down under it
            pass

    def close(self):
        self.executor.shutdown(timeout_sec=1.0)
        self._thread.join(timeout=2.0)
        self.node.destroy_node()

    # -- on the helper thread ----------------------------------------------------
    def _execute(self, handle):
        steps = int(handle.request.steps)
        result = SimulateSteps.Result()
        why = self.calls.call(lambda: self._begin(handle.request))
        for done in range(1, steps + 1):
            if why is not None:
                break
            if handle.is_cancel_requested:
                handle.canceled()
                result.result = Result(result=Result.RESULT_OK, error_message=f"cancelled after {done - 1} of {steps} steps")
                return result
            why = self.calls.call(lambda: self.services.step(1))
            if why is None:
                handle.publish_feedback(SimulateSteps.Feedback(completed_steps=done, remaining_steps=steps - done))
        if why is not None:
            handle.abort()
            result.result = Result(result=Result.RESULT_OPERATION_FAILED, error_message=why)
            return result
        handle.succeed()
        result.result = Result(result=Result.RESULT_OK, error_message=f"{steps} steps")
        return result

    # -- on the physics thread -------------------------------------------------------
    def _begin(self, goal):
        """Record the goal; None if stepping may start, else why not."""
        node = self.services.node
        w = node.world
        node.outputs.record_request(self.requests_topic, goal, sim_time_ns(w.time), w.step_index)
        if goal.steps < 1:
            return f"steps = {goal.steps}: ask for 1 or more"
        if node.faulted:
            return f"cannot step: {node.faulted}; reset the simulation"
        if not node.paused:
            return "the simulation is playing: pause it first (SetSimulationState STATE_PAUSED)"
        return None
