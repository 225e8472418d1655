"""Errors raised by the physics core.

Every error message names what was wrong and where, so a user can fix the
scene file or the command without reading the engine's source.
"""
import reprlib

# A bad value is quoted this short: a value can be megabytes long (or, before
# aliases were refused, an exponentially expanded YAML alias).
_QUOTE = reprlib.Repr()
_QUOTE.maxlevel, _QUOTE.maxlist, _QUOTE.maxtuple, _QUOTE.maxdict = 3, 6, 6, 4
_QUOTE.maxstring, _QUOTE.maxother, _QUOTE.maxlong = 80, 80, 40
QUOTE_CHARS = 160


def quote(value) -> str:
    """repr(value), cut to at most QUOTE_CHARS characters."""
    text = _QUOTE.repr(value)
    return text if len(text) <= QUOTE_CHARS else text[:QUOTE_CHARS - 1] + "…"


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
            detail += f", got {quote(got)}"
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
