"""Errors raised by the physics core.

Every error message names what was wrong and where, so a user can fix the
scene file or the command without reading the engine's source.
"""


class PhysicsError(Exception):
    """Base class for every error the physics core raises."""


class SceneError(PhysicsError, ValueError):
    """A scene file or dict is invalid.

    ``source`` is the file (or ``<dict>``), ``path`` the key path such as
    ``bodies[2].shape.radius``, ``expected`` what would have been accepted.
    """

    def __init__(self, source: str, path: str, expected: str, got=None):
        self.source = source
        self.path = path
        self.expected = expected
        self.got = got
        where = f"{source}: {path}" if path else source
        detail = f"expected {expected}"
        if got is not None:
            detail += f", got {got!r}"
        super().__init__(f"{where}: {detail}")


class CommandError(PhysicsError, ValueError):
    """A force, torque or impulse command was refused (unknown body, NaN, ...)."""


class NonFiniteStateError(PhysicsError, FloatingPointError):
    """The state became NaN or infinite after a stage; names the stage and body.

    ``stage`` is the stage's name, ``bodies`` the indices of the bodies."""

    def __init__(self, message, stage=None, bodies=()):
        super().__init__(message)
        self.stage = stage
        self.bodies = tuple(int(i) for i in bodies)
