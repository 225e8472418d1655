"""Wrench and impulse commands: checking them, and applying them to a world.

The same `CommandApplier` runs in the live node and in `--resimulate`, so a
recorded session is re-applied through exactly the code that first applied it.
"""

from dataclasses import dataclass

import numpy as np

from msg_adapters.frames import rotate_to_world
from msg_adapters.wrenches import is_world_frame
from physics_core.command_limits import MAX_ANGULAR_IMPULSE, MAX_FORCE, MAX_IMPULSE, MAX_TORQUE, magnitude

WRENCH = "wrench"
IMPULSE = "impulse"

# Why a command was dropped; also the diagnostics keys.
UNKNOWN_BODY = "unknown_body"
NON_FINITE = "non_finite"
UNKNOWN_FRAME = "unknown_frame"
STATIC_BODY = "static_body"
REJECTED = "rejected_by_engine"
OUT_OF_RANGE = "out_of_range"  # beyond physics_core/command_limits.py
QUEUE_FULL = "queue_full"  # beyond the queue bounds of limits.py
MALFORMED = "malformed"  # bytes that do not deserialize as a WrenchStamped
DISCARDED_ON_RESET = "reset"  # queued when the world was reset
DROP_REASONS = (
    UNKNOWN_BODY,
    NON_FINITE,
    OUT_OF_RANGE,
    UNKNOWN_FRAME,
    STATIC_BODY,
    QUEUE_FULL,
    MALFORMED,
    DISCARDED_ON_RESET,
    REJECTED,
)

# (force bound, torque bound, units) of each command kind: a wrench's force
# and torque are held, an impulse's are a linear and an angular impulse.
BOUNDS = {
    WRENCH: (MAX_FORCE, MAX_TORQUE, ("N", "N·m")),
    IMPULSE: (MAX_IMPULSE, MAX_ANGULAR_IMPULSE, ("N·s", "N·m·s")),
}


@dataclass
class Command:
    """One received command. `force`/`torque` are N and N·m for a wrench,
    N·s and N·m·s for an impulse, in the axes named by `frame`."""

    kind: str  # WRENCH or IMPULSE
    body: str
    frame: str
    force: np.ndarray
    torque: np.ndarray
    topic: str = ""
    raw: bytes = b""  # the message as received (CDR), recorded verbatim

    @property
    def in_body_axes(self):
        return not is_world_frame(self.frame)


def check(command, model):
    """None if `command` can be applied to a world with `model`, else the
    drop reason (one of DROP_REASONS)."""
    index = model.index.get(command.body)
    if index is None:
        return UNKNOWN_BODY
    if not (np.all(np.isfinite(command.force)) and np.all(np.isfinite(command.torque))):
        return NON_FINITE
    if out_of_range(command):
        return OUT_OF_RANGE
    if not (is_world_frame(command.frame) or command.frame == command.body):
        return UNKNOWN_FRAME
    if bool(model.is_static[index]):
        return STATIC_BODY
    return None


def out_of_range(command):
    """'' if the command's loads are within BOUNDS, else what is beyond them."""
    force_limit, torque_limit, (force_unit, torque_unit) = BOUNDS.get(command.kind, BOUNDS[WRENCH])
    for what, v, limit, unit in (
        ("force" if command.kind == WRENCH else "linear impulse", command.force, force_limit, force_unit),
        ("torque" if command.kind == WRENCH else "angular impulse", command.torque, torque_limit, torque_unit),
    ):
        size = magnitude(v)
        if not size <= limit:
            return f"{what} of magnitude {size:.3g} {unit} is beyond the limit {limit:g} {unit}"
    return ""


class CommandApplier:
    """Applies commands at a step boundary and keeps what is held.

    A wrench is held until replaced; a zero wrench clears it. A wrench given
    in a body's own axes stays in those axes while the body turns (like a
    thruster): it is turned into world axes again before every step.
    """

    def __init__(self, world):
        self.world = world
        self._body_axes = {}  # body -> (force, torque) in body axes
        self._held_since = {}  # body -> step index when its wrench was set

    def apply(self, command):
        """Apply one command now. Raises the engine's CommandError if the
        engine refuses it."""
        w = self.world
        name = command.body
        if command.kind == WRENCH:
            cleared = not (np.any(command.force) or np.any(command.torque))
            if command.in_body_axes and not cleared:
                self._body_axes[name] = (command.force.copy(), command.torque.copy())
                force, torque = self._to_world(name, command.force, command.torque)
            else:
                self._body_axes.pop(name, None)
                force, torque = command.force, command.torque
            w.apply_force(name, force)
            w.apply_torque(name, torque)
            if cleared:
                self._held_since.pop(name, None)
            else:
                self._held_since[name] = w.step_index
        elif command.kind == IMPULSE:
            linear, angular = command.force, command.torque
            if command.in_body_axes:
                linear, angular = self._to_world(name, linear, angular)
            if np.any(linear):
                w.apply_impulse(name, linear)
            if np.any(angular):
                w.apply_angular_impulse(name, angular)
        else:
            raise ValueError(f"unknown command kind {command.kind!r}")

    def expired(self, timeout_s):
        """Bodies whose held wrench is older than `timeout_s` sim seconds."""
        if timeout_s <= 0:
            return []
        now = self.world.step_index
        limit = timeout_s / self.world.dt
        return [name for name, since in self._held_since.items() if now - since >= limit - 1e-9]

    def prepare_step(self):
        """Turn body-axis wrenches into world axes at the current orientation."""
        for name, (force, torque) in self._body_axes.items():
            f, t = self._to_world(name, force, torque)
            self.world.apply_force(name, f)
            self.world.apply_torque(name, t)

    def let_go(self, name):
        """Forget what `name` holds (it was frozen: it takes no more loads)."""
        self._body_axes.pop(name, None)
        self._held_since.pop(name, None)

    def forget(self):
        """Drop everything held (after the world is reset)."""
        self._body_axes.clear()
        self._held_since.clear()

    def forget_body(self, name):
        """Drop what is held for a body that left the world."""
        self._body_axes.pop(name, None)
        self._held_since.pop(name, None)

    def _to_world(self, name, force, torque):
        q = self.world.state.quat[self.world.model.index[name]]
        return rotate_to_world(q, force), rotate_to_world(q, torque)


def clear_command(body, topic=""):
    """The zero wrench that lets go of `body` (used when a wrench times out)."""
    return Command(WRENCH, body, "world", np.zeros(3), np.zeros(3), topic=topic)
