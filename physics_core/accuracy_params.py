"""Settings of error-controlled integration: `integrator: adaptive` and `accuracy:`.

    integrator: adaptive          # implied when `accuracy:` is given without an integrator
    accuracy: 1.0e-6              # a number: relative tolerance, and the absolute one in SI units
    accuracy:                     # or a mapping (every key optional)
      relative: 1.0e-6            # fraction of the size of each quantity
      absolute: 1.0e-6            # a number (m, m/s, rad, rad/s alike) or a mapping of
                                  #   position (m), velocity (m/s), orientation (rad),
                                  #   angular_velocity (rad/s)
      min_step: 1.0e-9            # s; default dt / substeps × 1e-6
      max_step: 0.001             # s; default dt / substeps (the interval itself)
      method: dormand_prince      # dormand_prince (5(4), 6 force evaluations a step) or
                                  #   bogacki_shampine (3(2), 3 a step)

The tolerances are for the error of the run, not of one step: local errors
add up over the internal steps and the dynamics amplify them (a velocity
error at the periapsis of an e = 0.9 orbit becomes a phase error that grows
all orbit long: one orbit's final error is ~10³ times the local tolerance
of its steps). So each internal step's estimated local error is held to
LOCAL_SHARE = 1e-4 of the given tolerances, and on the closed-form problems
of `physics-bench accuracy` (one e = 0.9 orbit, 5 damped periods, 4 s of
drag fall, 30 periods of a stiff spring) the final error is within the
requested accuracy; a run N times longer drifts up to ~N times further.

The error norm (adaptive_kernels.py) is per body: for each of position,
velocity, orientation and angular velocity, |local error estimate| /
(absolute + relative × the larger size at the step's two ends), both
tolerances × LOCAL_SHARE, and the body's error the largest of the four; a
step is accepted when no body's error exceeds 1.
"""
from dataclasses import dataclass

from .embedded_rk import METHODS

LOCAL_SHARE = 1e-4        # of the run's tolerance, for one internal step's local error
MIN_TOLERANCE = 1e-10     # × LOCAL_SHARE: ~50 ulp of 1, below which the estimate is round-off
MAX_TOLERANCE = 0.1
DEFAULT_TOLERANCE = 1e-6
MIN_STEP_FRACTION = 1e-6  # default min_step as a fraction of the interval dt / substeps
ABSOLUTE_KEYS = ("position", "velocity", "orientation", "angular_velocity")


@dataclass(frozen=True)
class AccuracyParams:
    relative: float = DEFAULT_TOLERANCE
    position: float = DEFAULT_TOLERANCE          # m
    velocity: float = DEFAULT_TOLERANCE          # m/s
    orientation: float = DEFAULT_TOLERANCE       # rad (|Δq| of the unit quaternion ≈ half the angle)
    angular_velocity: float = DEFAULT_TOLERANCE  # rad/s
    min_step: float = 0.0                        # s; resolved by parse_accuracy, never 0 in a Model
    max_step: float = 0.0                        # s
    method: str = "dormand_prince"


def _tolerance(reader, key, default):
    return reader.number(key, default, min=MIN_TOLERANCE, max=MAX_TOLERANCE)


def _absolute(reader, default):
    """The four absolute tolerances from `absolute:` (a number or a mapping)."""
    if not reader.has("absolute"):
        return {k: default for k in ABSOLUTE_KEYS}
    if not isinstance(reader.data["absolute"], dict):
        value = _tolerance(reader, "absolute", default)
        return {k: value for k in ABSOLUTE_KEYS}
    ar = reader.sub("absolute")
    ar.only(set(ABSOLUTE_KEYS))
    return {k: _tolerance(ar, k, default) for k in ABSOLUTE_KEYS}


def parse_accuracy(r, integrator, interval):
    """AccuracyParams for `integrator: adaptive` (None for the fixed-step ones);
    `interval` = dt / substeps, s. SceneError names the key on bad input."""
    if integrator != "adaptive":
        if r.has("accuracy"):
            r.fail("accuracy", "no `accuracy:` with a fixed-step integrator (use `integrator: "
                   "adaptive`, or leave `integrator:` out)", integrator)
        return None
    if not r.has("accuracy") or not isinstance(r.data["accuracy"], dict):
        tol = _tolerance(r, "accuracy", DEFAULT_TOLERANCE)
        return AccuracyParams(tol, tol, tol, tol, tol, MIN_STEP_FRACTION * interval, interval)
    ar = r.sub("accuracy")
    ar.only({"relative", "absolute", "min_step", "max_step", "method"})
    rel = _tolerance(ar, "relative", DEFAULT_TOLERANCE)
    absolute = _absolute(ar, rel)
    max_step = ar.number("max_step", interval, positive=True)
    if max_step > interval:
        ar.fail("max_step", f"a step (s) <= dt / substeps = {interval:g} (internal steps end on "
                "every substep)", max_step)
    min_step = ar.number("min_step", min(MIN_STEP_FRACTION * interval, max_step), positive=True)
    if min_step > max_step:
        ar.fail("min_step", f"a step (s) <= max_step = {max_step:g}", min_step)
    method = ar.string("method", "dormand_prince", choices=tuple(METHODS))
    return AccuracyParams(rel, absolute["position"], absolute["velocity"], absolute["orientation"],
                          absolute["angular_velocity"], min_step, max_step, method)
