"""Speed of the physics core without contacts: steps per second and the cost of each effect.

    python -m benchmarks.core_speed [--quick]

Three measurements, each a row of `run()`:

- `one_body_gravity`: one sphere under gravity, steps/s (target ≥ 20,000);
- `many_bodies_drag`: 10,000 spheres under gravity and quadratic drag,
  body-steps/s (target ≥ 5,000,000);
- `effect:<name>`: the cost of each effect, one at a time on the same bodies
  (empty scene, +gravity, +drag, +gravitation on fewer bodies, +buoyancy,
  +springs), read from `world.profile`'s per-stage timings; it shows that an
  undeclared effect costs nothing and that a gravity-only scene costs no more
  than the empty scene plus the gravity stage.

Timing follows `timeit`: a run is cut into chunks and the fastest chunk is
kept (load on the machine only ever adds time); its per-stage profile is the
one reported. Chunks are timed in process CPU time, so time the process spends
descheduled by other load does not count; the per-stage figures are
`world.profile`'s (wall-clock) shares of that chunk, scaled to its CPU time.
Scenes compared with each other are timed in interleaved rounds. This is a benchmark, not a
test: nothing here asserts.
"""
import argparse
import sys
from time import perf_counter, process_time

if __package__ in (None, ""):            # run as a script: make `physics_core` importable
    import os
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import numpy as np

from physics_core import load_scene

ONE_BODY_TARGET = 20_000          # steps/s
MANY_BODIES_TARGET = 5_000_000    # body-steps/s
EFFECTS = ("empty", "gravity", "drag", "gravitation", "buoyancy", "springs")
GRAVITATION_MAX = 300             # bodies in the gravitation row: its cost grows as n²
STAGE_KEYS = ("integrate", "force:gravity", "force:gravitation", "force:drag", "force:buoyancy",
              "force:springs", "impulses", "finite")


# ---- scenes -------------------------------------------------------------------

def _bodies(n, boxes=False, spacing=2.0):
    """n bodies on a square grid at z = 10 m (above any fluid), moving sideways so drag
    and dampers have work; alternate boxes when `boxes`."""
    side = int(np.ceil(np.sqrt(n)))
    out = []
    for i in range(n):
        x, y = (i % side) * spacing, (i // side) * spacing
        if boxes and i % 2:
            shape = {"type": "box", "half_extents": [0.2, 0.15, 0.1]}
        else:
            shape = {"type": "sphere", "radius": 0.1}
        out.append({"name": f"b{i}", "shape": shape, "mass": 1.0, "position": [x, y, 10.0],
                    "velocity": [1.0, 0.5, 0.0]})
    return out


def scene_for(effect, n):
    """The scene for one row of the effect-cost table: `n` bodies plus one effect."""
    sc = {"dt": 1.0 / 240.0, "integrator": "semi_implicit_euler", "bodies": _bodies(n, boxes=True)}
    if effect in ("gravity", "buoyancy"):
        sc["gravity"] = "earth"
    if effect == "drag":
        sc["effects"] = {"drag": {"model": "quadratic"}}
    elif effect == "gravitation":
        sc["effects"] = {"gravitation": {"G": 6.673e-11}}
    elif effect == "buoyancy":
        # half the bodies in the water so the submerged-volume work is real
        for b in sc["bodies"][::2]:
            b["position"][2] = -0.05
        sc["effects"] = {"buoyancy": {"fluid_density": 1000.0, "linear_damping": 1.0}}
    elif effect == "springs":
        sc["springs"] = [{"a": f"b{i}", "b": f"b{i + 1}", "stiffness": 50.0, "rest_length": 2.0,
                          "damping": 0.1} for i in range(n - 1)]
    return sc


# ---- timing -------------------------------------------------------------------

def time_world(world, chunks=10, chunk_seconds=0.005):
    """(seconds per step, {stage: seconds per step}) of the fastest of `chunks` chunks."""
    return time_worlds([world], chunks, chunk_seconds)[0]


def time_worlds(worlds, chunks=10, chunk_seconds=0.005):
    """Time several worlds in interleaved rounds (one chunk of each per round), so that a
    change of load on the machine hits them alike. Each chunk runs enough steps to last
    about `chunk_seconds`. Per world, the fastest chunk's (seconds per step,
    {stage: seconds per step})."""
    sizes = []
    for w in worlds:
        w.step(2)                                          # warm-up: first allocations
        n, t0 = 0, perf_counter()
        while perf_counter() - t0 < 0.2 * chunk_seconds:   # estimate the cost of a step
            w.step()
            n += 1
        sizes.append(max(1, int(chunk_seconds * n / (perf_counter() - t0))))
    best = [None] * len(worlds)
    for _ in range(chunks):
        for i, (world, size) in enumerate(zip(worlds, sizes)):
            before = dict(world.profile)
            c0, w0 = process_time(), perf_counter()
            world.step(size)
            cpu, wall = process_time() - c0, perf_counter() - w0
            elapsed = cpu / size
            if best[i] is None or elapsed < best[i][0]:
                # the profile is wall clock: keep its shares of the step, scaled to the CPU time
                scale = cpu / wall / size if wall > 0 else 0.0
                stages = {k: (world.profile[k] - before.get(k, 0.0)) * scale for k in world.profile}
                best[i] = (elapsed, stages)
    return best


def _row(name, world, per_step, stages, **extra):
    n = world.model.n
    row = {"name": name, "bodies": n, "substeps": world.substeps, "step_us": per_step * 1e6,
           "steps_per_s": 1.0 / per_step, "body_steps_per_s": n / per_step,
           "stage_names": list(world.stage_names)}
    for k in STAGE_KEYS:
        row[k + "_us"] = stages.get(k, 0.0) * 1e6
    row.update(extra)
    return row


def run(quick=False):
    """Every measurement as a list of dict rows (see the module docstring)."""
    rows = []

    chunks, chunk_seconds = (8, 0.005) if quick else (30, 0.02)
    world = load_scene({"gravity": "earth", "bodies": _bodies(1)})
    per_step, stages = time_world(world, chunks, chunk_seconds)
    rows.append(_row("one_body_gravity", world, per_step, stages, target=ONE_BODY_TARGET,
                     measure="steps_per_s", met=1.0 / per_step >= ONE_BODY_TARGET))

    n_many = 10_000
    world = load_scene({"gravity": "earth", "effects": {"drag": {"model": "quadratic"}},
                        "bodies": _bodies(n_many, spacing=0.5)})
    per_step, stages = time_world(world, chunks, chunk_seconds)
    rows.append(_row("many_bodies_drag", world, per_step, stages, target=MANY_BODIES_TARGET,
                     measure="body_steps_per_s", met=n_many / per_step >= MANY_BODIES_TARGET))

    for n in ((2, 100) if quick else (2, 1000)):
        worlds, labels = [], []
        for effect in EFFECTS:
            count = min(n, GRAVITATION_MAX) if effect == "gravitation" else n     # O(n²) pairs
            worlds.append(load_scene(scene_for(effect, count)))
            labels.append(effect)
        if n > GRAVITATION_MAX:           # the empty baseline for the smaller gravitation scene
            worlds.append(load_scene(scene_for("empty", GRAVITATION_MAX)))
            labels.append("empty")
        timed = time_worlds(worlds, chunks, chunk_seconds)
        for world, effect, (per_step, stages) in zip(worlds, labels, timed):
            rows.append(_row(f"effect:{effect}", world, per_step, stages, effect=effect))
    _add_empty_comparison(rows)
    return rows


def _add_empty_comparison(rows):
    """For each effect row: its step time minus the empty scene's (same body count), and
    the empty step plus the effect's own stage, which a scene should not exceed."""
    empty = {r["bodies"]: r for r in rows if r.get("effect") == "empty"}
    for r in rows:
        base = empty.get(r["bodies"])
        if r.get("effect") in (None, "empty") or base is None:
            continue
        stage = sum(r[f"force:{e}_us"] for e in ("gravity", "gravitation", "drag", "buoyancy", "springs"))
        r["vs_empty_us"] = r["step_us"] - base["step_us"]
        r["empty_plus_stages_us"] = base["step_us"] + stage


# ---- report -------------------------------------------------------------------

def gravity_only_checks(rows):
    """Per body count: (bodies, gravity-only step, empty step, gravity stage) in µs, and
    whether step ≤ empty + stage within timing noise (10 % or 1 µs, whichever is larger)."""
    empty = {r["bodies"]: r for r in rows if r.get("effect") == "empty"}
    out = []
    for r in rows:
        if r.get("effect") == "gravity" and r["bodies"] in empty:
            base, stage = empty[r["bodies"]]["step_us"], r["force:gravity_us"]
            bound = base + stage
            out.append((r["bodies"], r["step_us"], base, stage,
                        r["step_us"] <= max(bound * 1.10, bound + 1.0)))
    return out


def markdown(rows):
    out = ["### Core speed (no contacts)", "",
           "| measurement | bodies | result | target | met |", "| --- | ---: | ---: | ---: | --- |"]
    for r in rows:
        if "target" in r:
            value = r[r["measure"]]
            unit = "steps/s" if r["measure"] == "steps_per_s" else "body-steps/s"
            out.append(f"| {r['name']} | {r['bodies']} | {value:,.0f} {unit} | {r['target']:,} | "
                       f"{'yes' if r['met'] else 'NO'} |")
    out += ["", "### Cost of each effect (semi-implicit Euler, µs per step, fastest chunk)", "",
            "| scene | bodies | sub-steps | step | integrate | own force stage | integrator's own work | finite "
            "| step − empty | empty + own stage |",
            "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for r in rows:
        e = r.get("effect")
        if e is None:
            continue
        forces = sum(r[k + "_us"] for k in STAGE_KEYS if k.startswith("force:"))
        cells = ["empty" if e == "empty" else "+" + e, r["bodies"], r["substeps"], f"{r['step_us']:.1f}",
                 f"{r['integrate_us']:.1f}", "—" if e == "empty" else f"{r[f'force:{e}_us']:.1f}",
                 f"{r['integrate_us'] - forces:.1f}", f"{r['finite_us']:.1f}"]
        if e == "empty":
            cells += ["—", "—"]
        else:
            cells += [f"{r['vs_empty_us']:+.1f}", f"{r['empty_plus_stages_us']:.1f}"]
        out.append("| " + " | ".join(str(c) for c in cells) + " |")
    out += [""]
    for n, step, base, stage, ok in gravity_only_checks(rows):
        out.append(f"- gravity only, {n} bodies: {step:.1f} µs per step against empty {base:.1f} µs "
                   f"+ gravity stage {stage:.1f} µs = {base + stage:.1f} µs: "
                   + ("no extra cost, within timing noise (10 % or 1 µs)" if ok
                      else "COSTS MORE than empty + gravity"))
    out += ["", "`integrate` contains the force stages (each integrator calls them), so the "
            "integrator's own work is `integrate` minus the force stages. `+buoyancy` also declares "
            "gravity (F = ρ g V needs g); its own stage is the buoyancy stage only, and since buoyancy "
            "can turn a box, its scene also runs the rotational update (free rotation and torque), "
            "which is most of its extra cost. `+springs` joins neighbours at their centres, so it "
            "turns nothing. `+gravitation` uses at most "
            f"{GRAVITATION_MAX} bodies (O(n²) pairs), compared with an empty scene of as many bodies."]
    return "\n".join(out) + "\n"


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--quick", action="store_true", help="short runs, fewer bodies")
    args = p.parse_args(argv)
    print(markdown(run(quick=args.quick)))


if __name__ == "__main__":
    main()
