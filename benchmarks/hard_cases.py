"""The contact hard cases of scenes/, run under generic stability checks.

Every scene file in scenes/ that declares `effects.contacts` is a case. Its
specific physics (does the bullet stop, does the box stay put) is asserted
by the contact tests; here each case must only stay *stable*:

- finite state all along;
- no body deeper than PENETRATION_LIMIT of its own size into a static plane
  (nothing tunnels through the ground);
- no energy created: the total energy never rises above its start by more
  than ENERGY_GAIN_LIMIT of the energy that moved during the run (plus the
  energy of lifting every body by LIFT_FLOOR, so that a scene at rest is not
  judged on the micro-joules of its position correction);
- nothing flies off: every body stays within ESCAPE_RADIUS of the origin.
"""
import glob
import os
import warnings
from dataclasses import dataclass, field
from time import perf_counter

import numpy as np
import yaml

from physics_core import NonFiniteStateError, load_scene
from physics_core import quaternion as qt
from physics_core.shapes import BOX, PLANE, SPHERE

SCENES_DIR = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scenes")
PENETRATION_LIMIT = 0.25      # of the body's smallest half size
ENERGY_GAIN_LIMIT = 0.10      # of the energy that moved
LIFT_FLOOR = 1e-3             # m
ESCAPE_RADIUS = 1.0e3         # m
DURATION = {True: 2.0, False: 5.0}     # simulated seconds (quick, full)
TEST_DURATION = 1.0                    # simulated seconds in the test suite
SAMPLE = 4                    # steps between checks


@dataclass(frozen=True)
class Case:
    name: str
    path: str
    bodies: int


def discover(directory=SCENES_DIR):
    cases = []
    for path in sorted(glob.glob(os.path.join(directory, "*.yaml"))):
        try:
            with open(path, encoding="utf-8") as f:
                data = yaml.safe_load(f) or {}
        except (OSError, yaml.YAMLError):
            continue
        if isinstance(data, dict) and "contacts" in (data.get("effects") or {}):
            name = os.path.splitext(os.path.basename(path))[0]
            cases.append(Case(name, path, len(data.get("bodies") or [])))
    return cases


@dataclass
class HardCaseResult:
    name: str
    bodies: int
    steps: int
    finite: bool = True
    max_penetration: float = 0.0       # of the body's smallest half size
    energy_gain: float = 0.0           # of the energy that moved
    max_distance: float = 0.0          # m from the origin
    seconds: float = 0.0
    cpu_per_sim_second: float = 0.0
    notes: list = field(default_factory=list)

    def failures(self):
        out = []
        if not self.finite:
            out.append("non-finite state")
        if self.max_penetration > PENETRATION_LIMIT:
            out.append(f"penetration {self.max_penetration:.3g} of the body size "
                       f"(limit {PENETRATION_LIMIT})")
        if self.energy_gain > ENERGY_GAIN_LIMIT:
            out.append(f"energy rose by {self.energy_gain:.3g} of the moving energy "
                       f"(limit {ENERGY_GAIN_LIMIT})")
        if self.max_distance > ESCAPE_RADIUS:
            out.append(f"a body flew {self.max_distance:.3g} m away")
        return out


def _plane_penetration(model, state):
    """Depth of every dynamic body into every static plane, in units of its smallest half size."""
    planes = np.flatnonzero(model.shape_type == PLANE)
    dyn = np.flatnonzero(~model.is_static & (model.shape_type != PLANE))
    if not len(planes) or not len(dyn):
        return 0.0
    worst = 0.0
    size = np.where(model.shape_type[dyn] == SPHERE, model.radius[dyn],
                    model.half_extents[dyn].min(axis=1))
    for p in planes:
        n = model.plane_normal[p]
        height = state.pos[dyn] @ n - model.plane_offset[p]
        extent = model.radius[dyn].copy()
        boxes = model.shape_type[dyn] == BOX
        if boxes.any():
            local_n = qt.rotate_inverse(state.quat[dyn][boxes], np.broadcast_to(n, (boxes.sum(), 3)))
            # a box reaches Σ |n_body,k| h_k along the plane normal
            extent[boxes] = np.einsum("ij,ij->i", np.abs(local_n), model.half_extents[dyn][boxes])
        worst = max(worst, float(np.max((extent - height) / size)))
    return max(worst, 0.0)


def run(case, quick=True, duration=None):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)    # friction-table fallbacks
        world = load_scene(case.path)
    steps = round((duration or DURATION[quick]) / world.dt)
    r = HardCaseResult(case.name, case.bodies, steps)
    e0 = world.energy()
    e_max, e_min, ke_max = e0, e0, world.kinetic_energy()
    t0 = perf_counter()
    try:
        for _ in range(0, steps, SAMPLE):
            world.step(SAMPLE)
            e = world.energy()
            e_max, e_min = max(e_max, e), min(e_min, e)
            ke_max = max(ke_max, world.kinetic_energy())
            r.max_penetration = max(r.max_penetration, _plane_penetration(world.model, world.state))
            r.max_distance = max(r.max_distance, float(np.abs(world.state.pos).max()))
            if r.max_distance > ESCAPE_RADIUS:
                break
    except NonFiniteStateError as e:
        r.finite = False
        r.notes.append(str(e)[:200])
    r.seconds = perf_counter() - t0
    r.cpu_per_sim_second = r.seconds / max(world.time, 1e-12)
    g = 0.0 if world.model.gravity is None else float(np.linalg.norm(world.model.gravity))
    lift = float(np.sum(np.where(world.model.is_static, 0.0, world.model.mass))) * g * LIFT_FLOOR
    moved = ke_max + (e0 - e_min) + lift + 1e-9
    r.energy_gain = max(0.0, e_max - e0) / moved
    return r
