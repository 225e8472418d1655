"""`--measure` specs: what to read from a world, and how to reduce it over a run.

    BODY.QUANTITY[.COMPONENT][:REDUCER]   ball.position.z:max, ball.speed:mean, ball.contacts:sum
    WORLD_QUANTITY[.COMPONENT][:REDUCER]  energy:min, momentum.x:end, contacts.begin:sum
    MODULE.PATH:FUNCTION[:REDUCER]         mypkg.metrics:apex (called with the World, returns a number)

Body quantities: position, velocity, angular_velocity (x, y, z or norm),
orientation (w, x, y, z), speed (|v|), contacts (events touching the body in
the step; `.begin` only the contacts that began). World quantities: energy,
kinetic_energy, momentum and angular_momentum (x, y, z or norm), contacts
(events in the step, `.begin` only begins), time.

Reducers: max, min, mean, sum — over every step, the initial state included
(t = 0, then after each step); end (the default) and initial read once.
"""
import importlib
import math

import numpy as np

from physics_core import BEGIN

from .design import SweepError

REDUCERS = ("max", "min", "mean", "sum", "end", "initial")
PER_STEP = ("max", "min", "mean", "sum")
_AXES = {"x": 0, "y": 1, "z": 2}
_QUAT_AXES = {"w": 0, "x": 1, "y": 2, "z": 3}
BODY_VECTORS = ("position", "velocity", "angular_velocity")
_STATE = {"position": "pos", "velocity": "vel", "angular_velocity": "omega", "orientation": "quat"}
WORLD_QUANTITIES = ("energy", "kinetic_energy", "momentum", "angular_momentum", "contacts", "time")


class Measure:
    """One column: `spec` names it; `bind(world)` gives the reader of a number."""

    def __init__(self, spec):
        self.spec = spec.strip()
        head, reducer = self.spec, "end"
        if ":" in self.spec and self.spec.rsplit(":", 1)[1] in REDUCERS:
            head, reducer = self.spec.rsplit(":", 1)
        self.reducer = reducer
        self.per_step = reducer in PER_STEP
        if ":" in head:
            self.function = _import_function(head, self.spec)
            self.body, self.quantity, self.component = None, None, None
        else:
            self.function = None
            self.body, self.quantity, self.component = _parse_quantity(head, self.spec)

    def check(self, model):
        """Raise SweepError if the scene has no such body."""
        if self.body is not None and self.body not in model.index:
            raise SweepError(f"--measure {self.spec!r}: no body {self.body!r}; bodies are: "
                             + ", ".join(model.names))

    def bind(self, world):
        if self.function is not None:
            return _number_of(self.function, self.spec)
        if self.body is None:
            return _world_reader(self.quantity, self.component)
        self.check(world.model)
        return _body_reader(world.model.index[self.body], self.quantity, self.component)


def _import_function(head, spec):
    module, _, name = head.rpartition(":")
    try:
        fn = getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError) as e:
        raise SweepError(f"--measure {spec!r}: cannot import {name!r} from {module!r} ({e})") from None
    if not callable(fn):
        raise SweepError(f"--measure {spec!r}: {module}.{name} is not callable")
    return fn


def _parse_quantity(head, spec):
    parts = head.split(".")
    if parts[0] == "world":
        parts = parts[1:]
    if parts and parts[0] in WORLD_QUANTITIES:
        return None, parts[0], _component(parts[0], parts[1:], spec, world=True)
    if len(parts) < 2:
        raise SweepError(f"--measure {spec!r}: expected BODY.QUANTITY or one of {', '.join(WORLD_QUANTITIES)}"
                         f", with :{'|:'.join(REDUCERS)}")
    body, quantity = parts[0], parts[1]
    if quantity not in BODY_VECTORS + ("orientation", "speed", "contacts"):
        raise SweepError(f"--measure {spec!r}: {quantity!r} is not a body quantity (position, velocity, "
                         "angular_velocity, orientation, speed, contacts)")
    return body, quantity, _component(quantity, parts[2:], spec, world=False)


def _component(quantity, rest, spec, world):
    vectors = ("momentum", "angular_momentum") if world else BODY_VECTORS
    if len(rest) > 1:
        raise SweepError(f"--measure {spec!r}: one component at most")
    c = rest[0] if rest else None
    if quantity == "contacts":
        ok = c in (None, "begin")
    elif quantity == "orientation":
        ok = c in _QUAT_AXES
    elif quantity in vectors:
        ok = c in ("x", "y", "z", "norm")
    else:
        ok = c is None
    if not ok:
        raise SweepError(f"--measure {spec!r}: {quantity!r} takes {_component_help(quantity, vectors)}")
    return c


def _component_help(quantity, vectors):
    if quantity == "contacts":
        return "no component, or .begin"
    if quantity == "orientation":
        return "a component .w, .x, .y or .z"
    if quantity in vectors:
        return "a component .x, .y, .z or .norm"
    return "no component"


def _body_reader(i, quantity, component):
    if quantity == "speed":
        return lambda w: math.sqrt(float(w.state.vel[i] @ w.state.vel[i]))
    if quantity == "contacts":
        return lambda w: float(_contact_rows(w, component == "begin", i))
    attr = _STATE[quantity]
    if component == "norm":
        return lambda w: float(np.linalg.norm(getattr(w.state, attr)[i]))
    c = (_QUAT_AXES if quantity == "orientation" else _AXES)[component]
    return lambda w: float(getattr(w.state, attr)[i, c])


def _world_reader(quantity, component):
    if quantity == "contacts":
        return lambda w: float(_contact_rows(w, component == "begin", None))
    if quantity == "time":
        return lambda w: float(w.time)
    if quantity in ("energy", "kinetic_energy"):
        return lambda w: float(getattr(w, quantity)())
    if component == "norm":
        return lambda w: float(np.linalg.norm(getattr(w, quantity)()))
    c = _AXES[component]
    return lambda w: float(getattr(w, quantity)()[c])


def _contact_rows(world, begin_only, body):
    ev = world.contacts
    mask = np.ones(len(ev), bool) if body is None else (ev.body_a == body) | (ev.body_b == body)
    if begin_only:
        mask &= ev.event == BEGIN
    return int(np.count_nonzero(mask))


def _number_of(fn, spec):
    def read(world):
        v = fn(world)
        if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
            raise SweepError(f"--measure {spec!r}: the function returned {type(v).__name__}, expected a number")
        return float(v)
    return read


class Reduction:
    """Running max/min/mean/sum of one reader; end and initial read once."""

    def __init__(self, measure, world):
        self.measure, self.read = measure, measure.bind(world)
        self.value, self.count = None, 0
        if measure.reducer != "end":
            self.observe(world)

    def observe(self, world):
        x, r = self.read(world), self.measure.reducer
        if self.value is None:
            self.value = x
        elif r == "max":
            self.value = max(self.value, x)
        elif r == "min":
            self.value = min(self.value, x)
        else:                      # mean and sum keep the sum; mean divides at the end
            self.value += x
        self.count += 1

    def result(self, world):
        r = self.measure.reducer
        if r == "end":
            return self.read(world)
        if r == "mean":
            return self.value / self.count
        return self.value
