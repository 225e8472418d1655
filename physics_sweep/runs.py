"""One run, in-process: the run's scene from the plan, the world stepped for
the duration, the measures reduced, and one row (a dict) out.

The row depends only on the plan and the run's parameters and seed: the
world is built anew from a copy of the scene dict, so a run gives the same
bits in any process that runs the same engine build (serial, or any Ray
worker). A run that raises — an invalid scene value, a non-finite state, a
user measure that fails — returns its error in the row instead.
"""
import copy
import hashlib
import json
import os
import socket
import time
import warnings
from dataclasses import dataclass, field
from functools import lru_cache

import physics_core
from physics_core import World, build_model

from .design import Design, Perturb, SweepError, Vary, perturb, seed_rng, set_key
from .measures import Measure, Reduction

DEFAULT_PERTURB = ("position=0.001",)   # 1 mm per component, every dynamic body, when --seeds has no --perturb


@dataclass(frozen=True)
class SweepPlan:
    """Everything a worker needs to compute any run of the sweep (put once in Ray's object store)."""
    scene: dict
    scene_source: str
    design: Design
    duration: float
    measures: tuple = ()
    perturbs: tuple = ()
    engine_version: str = field(default=physics_core.__version__)

    @classmethod
    def make(cls, scene, vary=(), *, seeds=None, samples=None, design_seed=0, duration=1.0,
             measures=(), perturbs=None):
        """Parse and check every spec against the scene (SweepError/SceneError name what is wrong)."""
        data, source = _scene_data(scene)
        _check_counts(duration, seeds, samples)
        design = Design(tuple(v if isinstance(v, Vary) else Vary.parse(v) for v in vary),
                        samples, seeds, int(design_seed))
        if perturbs is None:
            perturbs = DEFAULT_PERTURB if seeds else ()
        plan = cls(data, source, design, float(duration), tuple(m.strip() for m in measures),
                   tuple(p if isinstance(p, Perturb) else Perturb.parse(p) for p in perturbs))
        plan.check()
        return plan

    def check(self):
        """Every key path resolves on the scene, every measure parses and names a
        body of it; the first run's scene has no unknown key (a typo would fail every run)."""
        model = build_model(self.scene)
        for m in self.measures:
            Measure(m).check(model)
        first = next(self.design.runs(), None)
        if first is not None:
            scene = self.scene_for(first)
            try:
                build_model(scene)
            except physics_core.SceneError as e:
                if e.got == "unknown key":
                    raise SweepError(f"--vary: the scene has no such key: {e}") from None

    def scene_for(self, run):
        scene = copy.deepcopy(self.scene)
        for vary, (_, value) in zip(self.design.vary, run.params):
            set_key(scene, vary.steps, value)
        if run.seed is not None:
            perturb(scene, self.perturbs, seed_rng(self.design.design_seed, run.seed))
        return scene

    def fingerprint(self):
        """What a results file must match to be resumed."""
        return {
            "scene_sha256": hashlib.sha256(json.dumps(self.scene, sort_keys=True).encode()).hexdigest(),
            "vary": [f"{v.key}={v.values!r}" for v in self.design.vary],
            "samples": self.design.samples, "seeds": self.design.seeds,
            "design_seed": self.design.design_seed, "duration": self.duration,
            "measures": list(self.measures), "perturbs": [f"{p.key}={p.sigma!r}" for p in self.perturbs],
        }


def _check_counts(duration, seeds, samples):
    if isinstance(duration, bool) or not (isinstance(duration, (int, float)) and duration > 0):
        raise SweepError(f"--duration: a number of seconds > 0, got {duration!r}")
    for name, n in (("--seeds", seeds), ("--samples", samples)):
        if n is not None and (isinstance(n, bool) or not isinstance(n, int) or n < 1):
            raise SweepError(f"{name}: an integer >= 1, got {n!r}")


def _scene_data(scene):
    from physics_core.scene_loader import read_scene_source
    if isinstance(scene, str) and scene == "default":
        scene = physics_core.default_scene_path()
    data, source, _, _ = read_scene_source(scene)
    if not isinstance(data, dict):
        raise SweepError(f"{source}: a scene mapping, got {type(data).__name__}")
    return data, source


@lru_cache(maxsize=64)
def _measure(spec):
    return Measure(spec)


def worker_name():
    return f"{socket.gethostname()}:{os.getpid()}"


def execute(plan, run):
    """The row of one run: run_id, seed, parameters, measures, steps, wall_s,
    cpu_s, engine_version, worker, error (None when it ran to the end)."""
    row = {"run_id": run.run_id, "seed": run.seed, **dict(run.params)}
    row.update({m: None for m in plan.measures})
    wall, cpu = time.perf_counter(), time.thread_time()
    steps, error = 0, None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")     # friction fallbacks: the same for every run
            world = World(build_model(plan.scene_for(run)))
        steps, values = simulate(world, plan.duration, [_measure(m) for m in plan.measures])
        row.update(values)
    except Exception as e:       # noqa: BLE001 - any failure of a run (user functions included) goes in its row
        error = f"{type(e).__name__}: {e}"
    row.update(steps=steps, wall_s=time.perf_counter() - wall, cpu_s=time.thread_time() - cpu,
               engine_version=plan.engine_version, worker=worker_name(), error=error)
    return row


def simulate(world, duration, measures):
    """Step `world` for round(duration / dt) steps; (steps, {spec: value})."""
    steps = max(1, round(duration / world.dt))
    reductions = [Reduction(m, world) for m in measures]
    every = [r for r in reductions if r.measure.per_step]
    if not every:
        world.step(steps)
    else:
        for _ in range(steps):
            world.step(1)
            for r in every:
                r.observe(world)
    return steps, {r.measure.spec: r.result(world) for r in reductions}


def run_serial(plan, runs=None):
    """Rows of `runs` (default: the whole design), one after another in this process."""
    for run in (plan.design.runs() if runs is None else runs):
        yield execute(plan, run)
