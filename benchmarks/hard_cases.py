"""The contact hard cases of scenes/, run under generic stability checks.

Every scene file in scenes/ that declares `effects.contacts` is a case. Its
specific physics (does the bullet stop, does the box stay put) is asserted
by the contact tests; here each case must only stay *stable*:

- finite state all along;
- no body deeper into a static plane than its case's measured worst
  (PENETRATION, a fraction of the body's smallest half size) plus one
  substep's gravity sink g h² (the depth a resting contact reaches before
  the push-out answers; round-off elsewhere moves where a stack settles by
  less than that); a case not measured yet may go to the slop, the depth
  position correction leaves alone by design, plus that sink;
- no energy created: the total energy never rises above its start by more
  than ENERGY_GAIN_LIMIT of the energy that moved during the run (plus the
  energy of lifting every body by LIFT_FLOOR, so that a scene at rest is not
  judged on the micro-joules of its position correction);
- nothing flies off: no body gets farther from the origin than it could
  travel at the largest speed the moving energy allows (all of it in the
  lightest body), plus 1 m for the sampling;
- nothing tunnels: no body's centre crosses a static box from one side of
  its thinnest axis to the other within the box's face (a wall or a floor
  slab is never passed through).

Measured on every case at 1, 2 and 5 simulated seconds (the test's, the
quick and the full study's durations; the same values at each): energy rise
exactly 0, penetration as in PENETRATION. The old bounds (25 % of the size,
10 % of the energy, 1 km) were 7 to 10⁶ times what any case reaches.
"""
import glob
import math
import os
import warnings
from dataclasses import dataclass, field
from time import perf_counter

import numpy as np
import yaml

from physics_core import NonFiniteStateError, load_scene
from physics_core import quaternion as qt
from physics_core.shapes import BOX, PLANE, SPHERE

from .repo import REPO

SCENES_DIR = os.path.join(REPO, "scenes")
# worst depth into a plane, of the body's smallest half size, over 1, 2 and 5 s
# (with the contact solve's shock-propagation sweep; before it: box_stack_10
# 1.4e-3, mass_ratio_100 0.038, pyramid_10 6.5e-4)
PENETRATION = {"box_resting": 2.6e-9, "box_stack_10": 6.41e-7, "bullet_wall": 0.0,
               "coincident_spheres": 0.0, "head_on": 0.0, "mass_ratio_100": 6.57e-7,
               "overlapping_spawn": 5.5e-8, "pyramid_10": 3.23e-7}
# measured 0 in every case (the energy never rose above its start); 1e-6 covers
# round-off in the energy sums (~1e-15 of each term) a million times over
ENERGY_GAIN_LIMIT = 1e-6      # of the energy that moved
ROUND_OFF = 1e-9              # of the body size: depths are differences of coordinates ~1 m
LIFT_FLOOR = 1e-3             # m
ESCAPE_MARGIN = 1.0           # m beyond the farthest a body can get at its energy's speed
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
    crossed: list = field(default_factory=list)   # (body, static box) pairs that tunnelled
    seconds: float = 0.0
    cpu_per_sim_second: float = 0.0
    notes: list = field(default_factory=list)
    penetration_limit: float = 0.0     # of the body's smallest half size (see the module docstring)
    escape_limit: float = math.inf     # m from the origin

    def failures(self):
        out = []
        if not self.finite:
            out.append("non-finite state")
        if self.max_penetration > self.penetration_limit:
            out.append(f"penetration {self.max_penetration:.4g} of the body size "
                       f"(limit {self.penetration_limit:.4g})")
        if self.energy_gain > ENERGY_GAIN_LIMIT:
            out.append(f"energy rose by {self.energy_gain:.3g} of the moving energy "
                       f"(limit {ENERGY_GAIN_LIMIT})")
        if self.max_distance > self.escape_limit:
            out.append(f"a body flew {self.max_distance:.4g} m away (its energy allows {self.escape_limit:.4g} m)")
        if self.crossed:
            out.append("passed through a static box: "
                       + ", ".join(f"{a} through {b}" for a, b in self.crossed))
        return out


class WallCrossing:
    """Which side of each static box's thinnest axis every dynamic body is on."""

    def __init__(self, model, state):
        self.model = model
        self.walls = np.flatnonzero(model.is_static & (model.shape_type == BOX))
        self.bodies = np.flatnonzero(~model.is_static)
        self.side0 = self._sides(state) if len(self.walls) else None

    def _local(self, state):
        out = []
        for w in self.walls:
            d = state.pos[self.bodies] - state.pos[w]
            q = np.broadcast_to(state.quat[w], (len(self.bodies), 4))
            out.append(qt.rotate_inverse(q, d))
        return np.array(out)                                   # (walls, bodies, 3)

    def _sides(self, state):
        local = self._local(state)
        axis = np.argmin(self.model.half_extents[self.walls], axis=1)
        return np.sign(np.take_along_axis(local, axis[:, None, None], axis=2)[..., 0])

    def crossed(self, state):
        """[(body name, wall name)] that are now on the other side, within the face."""
        if self.side0 is None:
            return []
        m = self.model
        local = self._local(state)
        h = m.half_extents[self.walls]
        axis = np.argmin(h, axis=1)
        side = np.sign(np.take_along_axis(local, axis[:, None, None], axis=2)[..., 0])
        inside_face = np.ones(side.shape, dtype=bool)
        for k in range(3):
            other = axis != k
            inside_face &= ~other[:, None] | (np.abs(local[..., k]) <= h[:, None, k])
        bad = (side * self.side0 < 0) & inside_face
        return [(m.names[self.bodies[j]], m.names[self.walls[i]]) for i, j in zip(*np.nonzero(bad))]


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


def _smallest_half_size(model):
    dyn = np.flatnonzero(~model.is_static & (model.shape_type != PLANE))
    if not len(dyn):
        return math.inf
    size = np.where(model.shape_type[dyn] == SPHERE, model.radius[dyn], model.half_extents[dyn].min(axis=1))
    return float(size.min())


def penetration_limit(case_name, world):
    """The case's measured worst plus one substep's gravity sink g h², both in
    units of the smallest body's half size; the slop for a case not measured."""
    size = _smallest_half_size(world.model)
    if not math.isfinite(size):
        return math.inf
    g = 0.0 if world.model.gravity is None else float(np.linalg.norm(world.model.gravity))
    sink = g * (world.model.dt / world.substeps) ** 2 / size + ROUND_OFF
    if case_name in PENETRATION:
        return PENETRATION[case_name] + sink
    slop = world.contact_system.params.slop if world.contact_system is not None else 0.0
    return slop / size + sink


def escape_limit(world, start_radius, moved):
    """Farthest a body can be after `world.time` at the speed of all the moving
    energy in the lightest dynamic body, plus ESCAPE_MARGIN."""
    m = world.model.mass[~world.model.is_static]
    if not len(m):
        return start_radius + ESCAPE_MARGIN
    speed = math.sqrt(2.0 * moved / float(m.min()))
    return start_radius + speed * world.time + ESCAPE_MARGIN


def run(case, quick=True, duration=None):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)    # friction-table fallbacks
        world = load_scene(case.path)
    steps = round((duration or DURATION[quick]) / world.dt)
    r = HardCaseResult(case.name, case.bodies, steps)
    e0 = world.energy()
    e_max, e_min, ke_max = e0, e0, world.kinetic_energy()
    walls = WallCrossing(world.model, world.state)
    r.penetration_limit = penetration_limit(case.name, world)
    start_radius = float(np.abs(world.state.pos).max())
    t0 = perf_counter()
    try:
        for _ in range(0, steps, SAMPLE):
            world.step(SAMPLE)
            for pair in walls.crossed(world.state):
                if pair not in r.crossed:
                    r.crossed.append(pair)
            e = world.energy()
            e_max, e_min = max(e_max, e), min(e_min, e)
            ke_max = max(ke_max, world.kinetic_energy())
            r.max_penetration = max(r.max_penetration, _plane_penetration(world.model, world.state))
            r.max_distance = max(r.max_distance, float(np.abs(world.state.pos).max()))
    except NonFiniteStateError as e:
        r.finite = False
        r.notes.append(str(e)[:200])
    r.seconds = perf_counter() - t0
    r.cpu_per_sim_second = r.seconds / max(world.time, 1e-12)
    g = 0.0 if world.model.gravity is None else float(np.linalg.norm(world.model.gravity))
    lift = float(np.sum(np.where(world.model.is_static, 0.0, world.model.mass))) * g * LIFT_FLOOR
    moved = ke_max + (e0 - e_min) + lift + 1e-9
    r.energy_gain = max(0.0, e_max - e0) / moved
    r.escape_limit = escape_limit(world, start_radius, moved)
    return r
