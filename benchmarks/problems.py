"""The smooth test problems of the accuracy study, each a scene with an exact answer.

A Problem builds its scene for any (integrator, dt, substeps), says how long
to simulate, and measures the relative error of a finished run against its
closed form (closed_form.py). Step sizes are chosen per integrator as a
number of steps per characteristic time (an oscillation period, an orbit, a
drag time), from coarse enough to show the error to fine enough to reach
the asymptotic order without hitting round-off.
"""
import math
from dataclasses import dataclass
from typing import Callable, Dict, Tuple

import numpy as np

from physics_core import quaternion as qt

from . import closed_form as cf

INTEGRATORS = ("explicit_euler", "semi_implicit_euler", "velocity_verlet", "rk4")
ORDERS_EXPECTED = {"explicit_euler": 1, "semi_implicit_euler": 1, "velocity_verlet": 2, "rk4": 4}


@dataclass(frozen=True)
class Problem:
    key: str
    title: str
    exact: str                                  # the closed form, for the tables
    time_scale: float                           # s, the unit of "steps per time scale"
    horizon: Tuple[float, float]                # (quick, full) simulated seconds
    quick: Dict[str, Tuple[int, int]]           # integrator -> (coarsest, finest) steps per time scale
    full: Dict[str, Tuple[int, int]]
    build: Callable[[str, float, int], dict]    # (integrator, dt, substeps) -> scene dict
    error: Callable[[object], float]            # finished World -> relative error
    adaptive_dt: float = 0.0                    # s, output step of the adaptive runs (0: time_scale / 16)

    def adaptive_step(self):
        return self.adaptive_dt or self.time_scale / 16

    def dts(self, integrator, quick):
        """Step sizes from coarse to fine, halving."""
        lo, hi = (self.quick if quick else self.full)[integrator]
        out, n = [], lo
        while n <= hi:
            out.append(self.time_scale / n)
            n *= 2
        return out

    def duration(self, quick):
        return self.horizon[0] if quick else self.horizon[1]


def _sphere(name, mass, **kw):
    body = {"name": name, "shape": {"type": "sphere", "radius": 0.05}, "mass": mass}
    body.update(kw)
    return body


# ---- harmonic and damped oscillator: a spring to a fixed point -----------
OSC_MASS, OSC_K = 1.0, 4.0 * math.pi ** 2      # ω₀ = 2π rad/s: period 1 s
OSC_X0, OSC_V0 = 0.1, 0.0
DAMPED_ZETA = 0.1


def _oscillator(damping):
    def build(integrator, dt, substeps):
        return {"dt": dt, "substeps": substeps, "integrator": integrator,
                "bodies": [_sphere("bob", OSC_MASS, position=[OSC_X0, 0.0, 0.0],
                                   velocity=[OSC_V0, 0.0, 0.0])],
                "springs": [{"a": "bob", "b": "world", "stiffness": OSC_K, "rest_length": 0.0,
                             "damping": damping}]}
    return build


def _oscillator_error(zeta):
    w0 = math.sqrt(OSC_K / OSC_MASS)

    def error(world):
        b = world.body("bob")
        if zeta:
            x, v = cf.damped(world.time, w0, zeta, OSC_X0, OSC_V0)
        else:
            x, v = cf.harmonic(world.time, w0, OSC_X0, OSC_V0)
        # phase-space distance, in units of the initial amplitude
        return math.hypot(b.position[0] - x, (b.velocity[0] - v) / w0) / OSC_X0
    return error


HARMONIC = Problem(
    key="harmonic", title="Harmonic oscillator",
    exact="x = x₀ cos ω₀t, ω₀ = 2π rad/s (spring k = 4π² N/m, m = 1 kg)",
    time_scale=1.0, horizon=(1.3, 5.3),
    quick={"explicit_euler": (256, 4096), "semi_implicit_euler": (32, 512),
           "velocity_verlet": (16, 256), "rk4": (8, 128)},
    full={"explicit_euler": (128, 4096), "semi_implicit_euler": (16, 2048),
          "velocity_verlet": (8, 1024), "rk4": (4, 512)},
    build=_oscillator(0.0), error=_oscillator_error(0.0))

DAMPED = Problem(
    key="damped", title="Damped oscillator",
    exact="x = e^{−ζω₀t}(A cos ω_d t + B sin ω_d t), ζ = 0.1, ω₀ = 2π rad/s",
    time_scale=1.0, horizon=(1.3, 5.3),
    quick={"explicit_euler": (256, 4096), "semi_implicit_euler": (32, 512),
           "velocity_verlet": (16, 256), "rk4": (8, 128)},
    full={"explicit_euler": (128, 4096), "semi_implicit_euler": (16, 2048),
          "velocity_verlet": (8, 1024), "rk4": (4, 512)},
    build=_oscillator(2.0 * DAMPED_ZETA * math.sqrt(OSC_K * OSC_MASS)),
    error=_oscillator_error(DAMPED_ZETA))


# ---- quadratic-drag fall --------------------------------------------------
DRAG_MASS, DRAG_CD, DRAG_AREA, AIR = 0.1, 0.47, 0.0314, 1.204


def _drag_build(integrator, dt, substeps):
    return {"dt": dt, "substeps": substeps, "integrator": integrator, "gravity": "earth",
            "effects": {"drag": {"model": "quadratic", "fluid_density": AIR}},
            "bodies": [_sphere("ball", DRAG_MASS, drag={"cd": DRAG_CD, "area": DRAG_AREA})]}


def _drag_terminal(world):
    g = -float(world.model.gravity[2])
    return g, math.sqrt(2.0 * DRAG_MASS * g / (AIR * DRAG_CD * DRAG_AREA))


def _drag_error(world):
    g, vt = _drag_terminal(world)
    d, v = cf.quadratic_drag_fall(world.time, g, vt)
    b = world.body("ball")
    # distance in units of v_t²/g, speed in units of v_t
    return math.hypot((-b.position[2] - d) * g / vt ** 2, (-b.velocity[2] - v) / vt)


DRAG_FALL = Problem(
    key="drag_fall", title="Quadratic-drag fall",
    exact="v = v_t tanh(g t / v_t), d = (v_t²/g) ln cosh(g t / v_t), v_t ≈ 10.5 m/s",
    time_scale=1.0, horizon=(2.0, 4.0),
    quick={"explicit_euler": (16, 512), "semi_implicit_euler": (16, 512),
           "velocity_verlet": (8, 256), "rk4": (4, 64)},
    full={"explicit_euler": (16, 4096), "semi_implicit_euler": (16, 4096),
          "velocity_verlet": (8, 1024), "rk4": (4, 256)},
    build=_drag_build, error=_drag_error)


# ---- eccentric Kepler orbit (pairwise gravitation) -------------------------
KEPLER_E, KEPLER_A, SUN, PLANET, G = 0.5, 1.0, 1.0, 1e-3, 1.0
KEPLER_MU = G * (SUN + PLANET)
KEPLER_PERIOD = 2.0 * math.pi * math.sqrt(KEPLER_A ** 3 / KEPLER_MU)


def _kepler_build_for(e):
    def build(integrator, dt, substeps):
        r0, v0 = cf.kepler(0.0, KEPLER_MU, KEPLER_A, e)
        total = SUN + PLANET
        # centre of mass at rest at the origin
        return {"dt": dt, "substeps": substeps, "integrator": integrator,
                "effects": {"gravitation": {"G": G, "softening": 1e-9}},
                "bodies": [_sphere("sun", SUN, position=(-PLANET / total * r0).tolist(),
                                   velocity=(-PLANET / total * v0).tolist()),
                           _sphere("planet", PLANET, position=(SUN / total * r0).tolist(),
                                   velocity=(SUN / total * v0).tolist())]}
    return build


def _kepler_error_for(e):
    def error(world):
        r, _ = cf.kepler(world.time, KEPLER_MU, KEPLER_A, e)
        rel = world.body("planet").position - world.body("sun").position
        return float(np.linalg.norm(rel - r)) / KEPLER_A
    return error


_kepler_build, _kepler_error = _kepler_build_for(KEPLER_E), _kepler_error_for(KEPLER_E)


KEPLER = Problem(
    key="kepler", title="Eccentric Kepler orbit (e = 0.5)",
    exact="Kepler's equation M = E − e sin E, relative orbit of a two-body system, G = 1",
    time_scale=KEPLER_PERIOD, horizon=(1.25 * KEPLER_PERIOD, 5.25 * KEPLER_PERIOD),
    quick={"explicit_euler": (8192, 32768), "semi_implicit_euler": (256, 4096),
           "velocity_verlet": (128, 2048), "rk4": (64, 1024)},
    full={"explicit_euler": (16384, 131072), "semi_implicit_euler": (256, 16384),
          "velocity_verlet": (128, 8192), "rk4": (64, 4096)},
    build=_kepler_build, error=_kepler_error)


# Kepler at e = 0.9: periapsis at a(1 − e) = 0.1, where the planet moves
# √19 ≈ 4.4 times faster than on a circle and the time scale r/v is ~300 times
# shorter than at apoapsis: the case where a fixed step wastes its work.
ECCENTRIC_E = 0.9
ECCENTRIC = Problem(
    key="kepler_e09", title="Eccentric Kepler orbit (e = 0.9)",
    exact="Kepler's equation M = E − e sin E, relative orbit of a two-body system, G = 1",
    time_scale=KEPLER_PERIOD, horizon=(1.25 * KEPLER_PERIOD, 3.25 * KEPLER_PERIOD),
    quick={"explicit_euler": (65536, 131072), "semi_implicit_euler": (2048, 16384),
           "velocity_verlet": (1024, 16384), "rk4": (256, 4096)},
    full={"explicit_euler": (65536, 262144), "semi_implicit_euler": (1024, 65536),
          "velocity_verlet": (512, 65536), "rk4": (128, 16384)},
    build=_kepler_build_for(ECCENTRIC_E), error=_kepler_error_for(ECCENTRIC_E))


# ---- stiff spring: k = 1e6 N/m on 1 kg, ω₀ = 1000 rad/s ----------------------
# At the node's usual 240 Hz a fixed integrator is unstable by itself (ω dt ≈ 4);
# the World then adds spring substeps (World.spring_substeps), the adaptive
# integrator's controller finds the stable size on its own.
STIFF_K, STIFF_X0 = 1e6, 0.01
STIFF_W0 = math.sqrt(STIFF_K / OSC_MASS)


def _stiff_build(integrator, dt, substeps):
    return {"dt": dt, "substeps": substeps, "integrator": integrator,
            "bodies": [_sphere("bob", OSC_MASS, position=[STIFF_X0, 0.0, 0.0])],
            "springs": [{"a": "bob", "b": "world", "stiffness": STIFF_K, "rest_length": 0.0}]}


def _stiff_error(world):
    b = world.body("bob")
    x, v = cf.harmonic(world.time, STIFF_W0, STIFF_X0, 0.0)
    return math.hypot(b.position[0] - x, (b.velocity[0] - v) / STIFF_W0) / STIFF_X0


STIFF = Problem(
    key="stiff_spring", title="Stiff spring (k = 1e6 N/m)",
    exact="x = x₀ cos ω₀t, ω₀ = 1000 rad/s (spring k = 10⁶ N/m, m = 1 kg, x₀ = 1 cm)",
    time_scale=2.0 * math.pi / STIFF_W0, horizon=(0.05, 0.2),
    quick={"explicit_euler": (2048, 8192), "semi_implicit_euler": (32, 512),
           "velocity_verlet": (16, 256), "rk4": (8, 128)},
    full={"explicit_euler": (2048, 32768), "semi_implicit_euler": (16, 2048),
          "velocity_verlet": (8, 1024), "rk4": (4, 512)},
    build=_stiff_build, error=_stiff_error, adaptive_dt=1.0 / 240.0)


# ---- torque-free asymmetric top ---------------------------------------------
TOP_HALF = (0.3, 0.2, 0.1)       # I_x < I_y < I_z for a box of mass 1 kg
TOP_OMEGA = (4.0, 0.0, 4.0)      # rad/s: about the largest-inertia axis, with a large wobble
_TOP_INERTIA = tuple(1.0 / 3.0 * (TOP_HALF[(i + 1) % 3] ** 2 + TOP_HALF[(i + 2) % 3] ** 2)
                     for i in range(3))
FREE_TOP = cf.FreeTop(_TOP_INERTIA, TOP_OMEGA[0], TOP_OMEGA[2])


def _top_build(integrator, dt, substeps):
    return {"dt": dt, "substeps": substeps, "integrator": integrator,
            "bodies": [{"name": "top", "shape": {"type": "box", "half_extents": list(TOP_HALF)},
                        "mass": 1.0, "angular_velocity": list(TOP_OMEGA)}]}


def _top_error(world):
    b = world.body("top")
    w_body = qt.rotate_inverse(b.orientation[None], b.angular_velocity[None])[0]
    return float(np.linalg.norm(w_body - FREE_TOP.omega_body(world.time))) / np.linalg.norm(TOP_OMEGA)


TOP = Problem(
    key="free_top", title="Torque-free asymmetric top",
    exact="body-frame ω = (A₁ cn τ, A₂ sn τ, A₃ dn τ), Jacobi elliptic functions",
    time_scale=FREE_TOP.period, horizon=(1.3 * FREE_TOP.period, 2.3 * FREE_TOP.period),
    quick={"explicit_euler": (512, 4096), "semi_implicit_euler": (512, 4096),
           "velocity_verlet": (512, 4096), "rk4": (16, 256)},
    full={"explicit_euler": (256, 16384), "semi_implicit_euler": (128, 4096),
          "velocity_verlet": (128, 4096), "rk4": (8, 512)},
    build=_top_build, error=_top_error)


PROBLEMS = (HARMONIC, DAMPED, DRAG_FALL, KEPLER, ECCENTRIC, STIFF, TOP)
