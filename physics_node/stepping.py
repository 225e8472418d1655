"""The step boundary: queued commands in arrival order, then one engine step.

`Stepper` owns the order of operations so the node and `--resimulate` share
it; neither publishes nor records anything here.
"""

from collections import deque
from dataclasses import dataclass, field

from physics_core import NonFiniteStateError

from .commands import CommandApplier, clear_command


@dataclass
class Boundary:
    """What happened at one step boundary, for the caller to publish/record."""

    step: int  # step index the commands were applied at (before stepping)
    time: float  # sim time of that boundary, s
    applied: list = field(default_factory=list)
    rejected: list = field(default_factory=list)  # (command, error)
    failure: Exception = None  # the engine's error if the step blew up


class Stepper:
    def __init__(self, world, command_timeout=0.0, error_types=(ValueError,)):
        self.world = world
        self.command_timeout = float(command_timeout)
        self.applier = CommandApplier(world)
        self._queue = deque()
        self._errors = error_types

    def submit(self, command):
        self._queue.append(command)

    @property
    def pending(self):
        return len(self._queue)

    def advance(self):
        """Apply the queued commands, let go of timed-out wrenches, step once."""
        w = self.world
        boundary = Boundary(step=w.step_index, time=w.time)
        while self._queue:
            command = self._queue.popleft()
            try:
                self.applier.apply(command)
            except self._errors as exc:
                boundary.rejected.append((command, exc))
            else:
                boundary.applied.append(command)
        for name in self.applier.expired(self.command_timeout):
            command = clear_command(name)
            self.applier.apply(command)
            boundary.applied.append(command)
        self.applier.prepare_step()
        try:
            w.step()
        except NonFiniteStateError as exc:
            # Finite commands can still drive the state to inf (a force of
            # 1e300 N); the caller decides what to do with a broken world.
            boundary.failure = exc
        return boundary

    def reset(self):
        """World back to its initial state; queued and held commands dropped."""
        dropped = len(self._queue)
        self._queue.clear()
        self.applier.forget()
        self.world.reset()
        return dropped
