"""`physics-bench stability`: the stability cases of stability_cases.py and hard_cases.py
as tables (`stability.md`, `stability.json`) and the long-run energy plot
(`stability_long_run.png`).
"""
import random

import numpy as np

from . import hard_cases
from . import markdown as md
from . import plotting
from . import random_scenes as rs
from . import stability_cases as sc
from .accuracy import LABELS
from .contact_support import available as contacts_available
from .problems import INTEGRATORS
from .progress import Progress
from .results_io import machine, write_json, write_text

LONG_STEPS = 100_000
LONG_INTEGRATORS = {True: ("semi_implicit_euler", "velocity_verlet"), False: INTEGRATORS}
RANDOM_SEEDS = {True: 12, False: 60}
STABLE = ("semi_implicit_euler", "velocity_verlet", "rk4")


def run(quick=False, out=None):
    cases = hard_cases.discover()
    ok, why = contacts_available()
    n_random = RANDOM_SEEDS[quick] * 2
    total = len(INTEGRATORS) + len(LONG_INTEGRATORS[quick]) + n_random + (len(cases) if ok else 0)
    prog = Progress("stability", total)

    stiff = []
    for integ in INTEGRATORS:
        r = sc.stiff_spring(integ, duration=1.0)
        stiff.append({**r.__dict__, "bounded": r.bounded})
        prog.step(f"stiff spring, {integ}: max offset {r.max_offset_ratio:.3g}× start, "
                  f"{r.spring_substeps} spring sub-steps")

    long_runs, traces = [], {}
    for integ in LONG_INTEGRATORS[quick]:
        r = sc.long_run(integ, LONG_STEPS)
        row = {**r.__dict__, "bounded": r.bounded, "limit": r.limit}
        trace = row.pop("trace")
        long_runs.append(row)
        # the largest error in each block of 5 samples: an envelope, free of the
        # aliasing that picking every 5th sample of a periodic error would show
        traces[integ] = ([sc.LONG_SAMPLE * min(k + 5, len(trace)) for k in range(0, len(trace), 5)],
                         [max(trace[k:k + 5]) for k in range(0, len(trace), 5)])
        prog.step(f"10⁵ steps of the e = 0.5 orbit, {integ}: max |ΔE/E| {r.max_rel_energy_error:.2e}")

    sweep = _random_sweep(RANDOM_SEEDS[quick], prog)

    hard = []
    if ok:
        for case in cases:
            r = hard_cases.run(case, quick=quick)
            hard.append({**r.__dict__, "failures": r.failures()})
            prog.step(f"hard case {case.name}: {'ok' if not r.failures() else '; '.join(r.failures())}")
    data = {"quick": quick, "machine": machine(), "stiff_spring": stiff, "long_runs": long_runs,
            "random": sweep, "hard_cases": hard, "contacts": {"available": ok, "reason": why},
            "hard_case_files": [c.name for c in cases]}
    if out:
        write_json(out, "stability.json", data)
        write_text(out, "stability.md", report(data))
        plot_long_runs(traces, f"{out}/stability_long_run.png")
    return data


def _random_sweep(seeds, prog):
    out = {}
    for kind, make in (("passive", rs.passive_scene), ("isolated", rs.isolated_scene)):
        for integ in INTEGRATORS:
            out[f"{kind}:{integ}"] = {"scenes": 0, "non_finite": 0, "max_energy_gain": 0.0,
                                      "max_momentum_drift": 0.0}
        for seed in range(seeds):
            for integ in INTEGRATORS:
                r = sc.run_random(make(random.Random(seed), integ))
                row = out[f"{kind}:{integ}"]
                row["scenes"] += 1
                row["non_finite"] += int(not r.finite)
                if r.finite:
                    row["max_energy_gain"] = max(row["max_energy_gain"], r.energy_gain)
                    row["max_momentum_drift"] = max(row["max_momentum_drift"], r.momentum_drift)
            prog.step(f"random {kind} scene seed {seed}")
    return out


def report(data):
    parts = [
        "# Stability\n",
        f"Run: `physics-bench stability{' --quick' if data['quick'] else ''}`, {data['machine']}. "
        "The same checks run in `make test` (tests/test_stability.py).\n",
        "## Stiff spring: k = 10⁶ N/m, m = 1 kg, dt = 1/240 s (ω dt = 4.2)\n",
        "A plain step at ω dt = 4.2 is unstable for every integrator here (semi-implicit Euler "
        "and Verlet need ω h < 2, RK4 ω h < 2.8). The engine keeps such springs bounded by "
        "**automatic sub-steps**: `world.spring_substeps` is chosen once per scene so the "
        "stiffest spring has ω h ≤ 0.5. Started 1 cm from equilibrium, run 1 s; pass: the "
        f"displacement never exceeds {sc.STIFF_BOUND} × its start.\n",
        md.table(["integrator", "spring sub-steps", "max displacement / start",
                  "max energy rise / oscillation energy", "bounded"],
                 [[LABELS[r["integrator"]], r["spring_substeps"], md.num(r["max_offset_ratio"]),
                   md.num(r["energy_ratio"]), "yes" if r["bounded"] else "**no**"]
                  for r in data["stiff_spring"]]),
        "Explicit Euler multiplies an undamped oscillator's energy by (1 + ω²h²) every "
        "sub-step, so no number of sub-steps keeps it bounded for ever; it is reported, "
        "not required.\n",
        f"## Long runs: 10⁵ steps of the e = 0.5 orbit (256 steps per orbit, ≈ 390 orbits)\n",
        "Pass: max |ΔE/E| under the limit; for semi-implicit Euler and velocity Verlet "
        f"(symplectic) also the last tenth of the run no worse than {sc.DRIFT_GROWTH} × the "
        "first tenth (bounded, not drifting). RK4 is not symplectic: its energy error grows "
        "slowly, and only the limit applies. Explicit Euler gains energy on any orbit (it "
        "escapes here): reported, not required.\n",
        md.table(["integrator", "max abs(ΔE/E)", "first tenth", "last tenth", "final ΔE/E",
                  "limit", "result", "CPU time"],
                 [[LABELS[r["integrator"]], md.sci(r["max_rel_energy_error"]),
                   md.sci(r["first_tenth"]), md.sci(r["last_tenth"]),
                   md.sci(r["final_rel_energy_error"]), md.num(r["limit"]),
                   sc.long_run_verdict(r), md.seconds(r["seconds"])]
                  for r in data["long_runs"]]),
        "![energy error over 10⁵ steps](stability_long_run.png)\n",
        "## Random scenes without contacts\n",
        f"Seeds 0–{RANDOM_SEEDS[data['quick']] - 1} of benchmarks/random_scenes.py, "
        f"{sc.RANDOM_STEPS} steps each. Passive: springs with dampers, drag, gravity, "
        "gravitation; pass: energy never rises by more than "
        + ", ".join(f"{v:g} ({LABELS[k]})" for k, v in sc.ENERGY_GAIN_TOLERANCE.items() if k != "explicit_euler")
        + " of the largest kinetic energy (explicit Euler is "
        "exempt: it gains energy on any oscillator). Isolated: only springs and gravitation "
        f"between bodies; pass: |ΔP| ≤ {sc.MOMENTUM_TOLERANCE:g} of Σ m(|v| + 1 m/s).\n",
        md.table(["scenes", "integrator", "runs", "non-finite", "max energy gain",
                  "max momentum drift"],
                 [[k.split(":")[0], LABELS[k.split(":")[1]], v["scenes"], v["non_finite"],
                   md.sci(v["max_energy_gain"]) if k.startswith("passive") else "—",
                   md.sci(v["max_momentum_drift"]) if k.startswith("isolated") else "—"]
                  for k, v in data["random"].items()], align="llrrrr"),
        "## Contact hard cases (scenes/*.yaml with contacts)\n",
    ]
    if not data["contacts"]["available"]:
        parts.append(f"_Skipped: contacts are not available ({data['contacts']['reason']})._\n")
    elif not data["hard_cases"]:
        parts.append("_No scene in scenes/ declares contacts._\n")
    else:
        parts.append(
            f"Each scene run {hard_cases.DURATION[data['quick']]:g} s. Pass: finite; "
            "penetration into a plane ≤ the case's measured worst plus one substep's gravity "
            "sink g h² (of the body's smallest half size: the limit column); "
            f"energy rise ≤ {hard_cases.ENERGY_GAIN_LIMIT:g} of the energy that moved; "
            "no body farther than the moving energy could carry the lightest one, plus "
            f"{hard_cases.ESCAPE_MARGIN:g} m; no body through a static box "
            "(its centre never crosses to the other side of the box's thinnest axis).\n")
        parts.append(md.table(
            ["case", "bodies", "steps", "max penetration / size", "limit", "energy rise", "CPU s / sim s",
             "result"],
            [[r["name"], r["bodies"], r["steps"], md.num(r["max_penetration"]),
              md.num(r.get("penetration_limit", float("nan"))),
              md.num(r["energy_gain"]), md.num(r["cpu_per_sim_second"]),
              "ok" if not r["failures"] else "**" + "; ".join(r["failures"]) + "**"]
             for r in data["hard_cases"]]))
    return "\n".join(parts)


def plot_long_runs(traces, path):
    fig, (ax,) = plotting.figure()
    ax.set_xscale("linear")
    for integ, (xs, ys) in traces.items():
        ys = np.maximum(np.array(ys, dtype=float), 1e-17)
        ax.plot(xs, ys, color=plotting.COLORS[integ], label=LABELS[integ], linewidth=1)
    ax.set_xlabel("step")
    ax.set_ylabel(f"|ΔE / E₀|, largest in each {5 * sc.LONG_SAMPLE} steps")
    ax.set_title("Energy error over 10⁵ steps, e = 0.5 orbit, 256 steps/orbit")
    ax.legend(fontsize=8)
    plotting.save(fig, path)
