"""The step boundary: queued commands in arrival order, then one engine step.

`Stepper` owns the order of operations so the node and `--resimulate` share
it; neither publishes nor records anything here.

A step that leaves some bodies non-finite (NonFiniteStateError) is undone,
those bodies are frozen (physics_core/isolation.py) and the step is run
again without them, so one bad body never stops the world; the same code
runs in `--resimulate`, so a recorded fault is reproduced. The queue is
bounded per body and in total (limits.py).
"""

import collections
from collections import deque
from dataclasses import dataclass, field

from physics_core import NonFiniteStateError
from physics_core.isolation import restore, snapshot

from .commands import QUEUE_FULL, CommandApplier, clear_command
from .limits import MAX_QUEUED_PER_BODY, MAX_QUEUED_TOTAL

# Times one step is undone and retried with more bodies frozen before the
# world is given up on (the caller halts it until a reset).
MAX_ISOLATIONS_PER_STEP = 3


@dataclass
class Boundary:
    """What happened at one step boundary, for the caller to publish/record."""

    step: int  # step index the commands were applied at (before stepping)
    time: float  # sim time of that boundary, s
    applied: list = field(default_factory=list)
    rejected: list = field(default_factory=list)  # (command, error)
    isolated: list = field(default_factory=list)  # names of the bodies frozen at this step
    faults: list = field(default_factory=list)  # the NonFiniteStateErrors that froze them
    failure: Exception = None  # the engine's error if the step could not be made


class Stepper:
    def __init__(self, world, command_timeout=0.0, error_types=(ValueError,)):
        self.world = world
        self.command_timeout = float(command_timeout)
        self.applier = CommandApplier(world)
        self._queue = deque()
        self._per_body = collections.Counter()
        self._errors = error_types
        self.isolated = []  # bodies frozen since the last reset, in order
        self.resets = 0  # times the world went back to its scene (session_history.py follows them)

    def submit(self, command):
        """Queue `command` for the next boundary; None, or QUEUE_FULL if a
        bound (limits.py) is reached and the command was not queued."""
        if len(self._queue) >= MAX_QUEUED_TOTAL or self._per_body[command.body] >= MAX_QUEUED_PER_BODY:
            return QUEUE_FULL
        self._queue.append(command)
        self._per_body[command.body] += 1
        return None

    @property
    def pending(self):
        return len(self._queue)

    def advance(self):
        """Apply the queued commands, let go of timed-out wrenches, step once."""
        w = self.world
        boundary = Boundary(step=w.step_index, time=w.time)
        self._apply_queue(boundary)
        for name in self.applier.expired(self.command_timeout):
            command = clear_command(name)
            self.applier.apply(command)
            boundary.applied.append(command)
        self._step(boundary)
        return boundary

    def _apply_queue(self, boundary):
        queue = self._queue
        while queue:
            command = queue.popleft()
            try:
                self.applier.apply(command)
            except self._errors as exc:
                boundary.rejected.append((command, exc))
            else:
                boundary.applied.append(command)
        self._per_body.clear()

    def _step(self, boundary):
        """One engine step; undone and retried with the bodies it names frozen
        when it leaves a non-finite state."""
        w = self.world
        for attempt in range(MAX_ISOLATIONS_PER_STEP + 1):
            self.applier.prepare_step()
            before = snapshot(w.state)
            try:
                w.step()
                return
            except NonFiniteStateError as exc:
                # Finite commands can still drive a state to inf (loads within
                # bounds on a body of 1e-9 kg); the step is undone either way.
                restore(w.state, before)
                frozen = w.isolate(exc.bodies) if attempt < MAX_ISOLATIONS_PER_STEP else []
                if not frozen:
                    boundary.failure = exc
                    return
                for name in frozen:
                    self.applier.let_go(name)
                self.isolated += frozen
                boundary.isolated += frozen
                boundary.faults.append(exc)
            except Exception as exc:  # an engine bug: keep the world as it was, the caller halts
                restore(w.state, before)
                boundary.failure = exc
                return

    def drop_commands(self):
        """Forget queued and held commands (the world keeps its state).
        Returns the queued commands dropped."""
        dropped = list(self._queue)
        self._queue.clear()
        self._per_body.clear()
        self.applier.forget()
        return dropped

    def reset(self):
        """World back to its initial state; queued and held commands dropped.
        Returns the queued commands dropped."""
        dropped = list(self._queue)
        self._queue.clear()
        self._per_body.clear()
        self.applier.forget()
        self.world.reset()
        self.isolated = []
        self.resets += 1
        return dropped
