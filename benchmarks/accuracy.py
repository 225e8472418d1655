"""`physics-bench accuracy`: the work–precision study of the four integrators.

For every problem of problems.py and every integrator, runs a ladder of
step sizes (substeps = 1) and a few substep variants at the coarsest dt,
measures the relative error against the closed form and the CPU time per
simulated second, fits the convergence order, and writes
`accuracy.md`, `accuracy.json` and one `accuracy_<problem>.png` per problem
(error against step size, and error against cost), plus
`accuracy_overview.png` (all work–precision panels in one figure).

`integrator: adaptive` (error-controlled Dormand–Prince 5(4)) runs a ladder
of requested accuracies on every problem at one coarse output step
(Problem.adaptive_dt) and sits on the same plots; its table compares the
achieved error with the requested one, and its cost with the cheapest fixed
step that reaches the same achieved error.
"""
import math
from time import perf_counter

from physics_core import load_scene

from . import markdown as md
from . import plotting
from .orders import cost_for_error, fit_order
from .timing import CHUNKS, MIN_TIMED
from .problems import INTEGRATORS, ORDERS_EXPECTED, PROBLEMS
from .progress import Progress
from .results_io import machine, write_json, write_text
from .timing import run_for

TARGETS = (1e-2, 1e-4, 1e-6)          # relative errors the reading answers for
SUBSTEPS = {True: (4,), False: (2, 4, 8)}
LABELS = {"explicit_euler": "explicit Euler", "semi_implicit_euler": "semi-implicit Euler",
          "velocity_verlet": "velocity Verlet", "rk4": "RK4", "adaptive": "adaptive DP5(4)"}
TOLERANCES = {True: (1e-3, 1e-5, 1e-7, 1e-9), False: (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9)}
ADAPTIVE = "adaptive"


def plan(problems, quick):
    """(problem, integrator, dt, substeps) for every run of the study."""
    runs = []
    for p in problems:
        for integ in INTEGRATORS:
            dts = p.dts(integ, quick)
            runs += [(p, integ, dt, 1) for dt in dts]
            finest = dts[-1]
            runs += [(p, integ, dts[0], s) for s in SUBSTEPS[quick] if dts[0] / s >= finest * 0.999]
    return runs


def measure(problem, integrator, dt, substeps, duration):
    world = load_scene(problem.build(integrator, dt, substeps))
    world, timed = run_for(world, duration)
    # the engine may add sub-steps of its own for a spring too stiff for dt
    effective = int(getattr(world, "substeps", substeps))
    return {"problem": problem.key, "integrator": integrator, "dt": dt, "substeps": substeps,
            "effective_substeps": effective, "h": dt / effective, "steps": timed.steps,
            "time": world.time, "error": problem.error(world),
            "seconds_per_step": timed.seconds_per_step,
            "cpu_per_sim_second": timed.seconds_per_sim_second}


def measure_adaptive(problem, tolerance, duration):
    """One adaptive run at the problem's output step. Its steps cost more near
    periapsis than far from it, so the run is cut into CHUNKS fixed chunks,
    repeated (at least 3 times, and until MIN_TIMED s are timed), and its cost
    is the sum over chunks of each chunk's best time."""
    dt = problem.adaptive_step()
    scene = problem.build(ADAPTIVE, dt, 1)
    scene["accuracy"] = tolerance
    world = load_scene(scene)
    n = max(1, round(duration / dt))
    bounds = sorted({round(n * c / CHUNKS) for c in range(CHUNKS + 1)})
    best = [math.inf] * (len(bounds) - 1)
    timed, runs = 0.0, 0
    while runs < 3 or timed < MIN_TIMED:
        world.reset()
        before = world.integration_stats
        for c, (a, b) in enumerate(zip(bounds, bounds[1:])):
            t0 = perf_counter()
            world.step(b - a)
            elapsed = perf_counter() - t0
            best[c], timed = min(best[c], elapsed), timed + elapsed
        runs += 1
    total = world.integration_stats
    counts = {k: total[k] - before[k] for k in ("internal_steps", "rejected_steps", "force_evaluations")}
    return {"problem": problem.key, "integrator": ADAPTIVE, "tolerance": tolerance, "dt": dt,
            "substeps": 1, "effective_substeps": 1, "h": world.time / max(counts["internal_steps"], 1),
            "steps": n, "time": world.time, "error": problem.error(world), **counts,
            "smallest_step_s": total["smallest_step_s"],
            "seconds_per_step": sum(best) / n, "cpu_per_sim_second": sum(best) / world.time}


def fixed_cost_at(rows, error):
    """(cost, how) of reaching `error` on one integrator's runs: interpolated
    on its work–precision line ("≤" when its coarsest run already does), or,
    below its finest run's error, extrapolated along the line through its two
    most accurate runs ("extrapolated"); None if neither applies."""
    c = cost_for_error([r["cpu_per_sim_second"] for r in rows], [r["error"] for r in rows], error)
    if c is not None:
        return c[0], "≤" if c[1] else ""
    pts = sorted(((r["error"], r["cpu_per_sim_second"]) for r in rows
                  if math.isfinite(r["error"]) and 0 < r["error"] < 0.3), key=lambda p: p[0])[:2]
    if len(pts) < 2 or not (pts[0][0] < pts[1][0] and pts[0][1] > pts[1][1]) or error >= pts[0][0]:
        return None
    (e1, c1), (e0, c0) = pts
    slope = math.log(c1 / c0) / math.log(e0 / e1)     # cost ∝ error^(−slope)
    return c1 * (e1 / error) ** slope, "extrapolated"


def run(quick=False, out=None, only=None):
    problems = [p for p in PROBLEMS if not only or p.key in only]
    runs = plan(problems, quick)
    adaptive_runs = [(p, tol) for p in problems for tol in TOLERANCES[quick]]
    prog = Progress("accuracy", len(runs) + len(adaptive_runs))
    rows = []
    for p, integ, dt, sub in runs:
        r = measure(p, integ, dt, sub, p.duration(quick))
        rows.append(r)
        prog.step(f"{p.key:9s} {integ:19s} dt={dt:.3g} s ×{sub}: error {r['error']:.2e}, "
                  f"{r['cpu_per_sim_second']:.3g} s CPU per simulated s")
    for p, tol in adaptive_runs:
        r = measure_adaptive(p, tol, p.duration(quick))
        rows.append(r)
        prog.step(f"{p.key:9s} adaptive accuracy={tol:g}: error {r['error']:.2e}, "
                  f"{r['internal_steps']} internal steps, {r['cpu_per_sim_second']:.3g} s CPU per simulated s")
    summary = summarise(problems, rows)
    data = {"quick": quick, "machine": machine(), "rows": rows, **summary}
    if out:
        write_json(out, "accuracy.json", data)
        write_text(out, "accuracy.md", report(problems, data))
        for p in problems:
            plot_problem(p, rows, summary["orders"][p.key], f"{out}/accuracy_{p.key}.png")
        plot_overview(problems, rows, summary["orders"], f"{out}/accuracy_overview.png")
    return data


def summarise(problems, rows):
    orders, reading = {}, {}
    for p in problems:
        orders[p.key], reading[p.key] = {}, {}
        for integ in INTEGRATORS:
            base = [r for r in rows if r["problem"] == p.key and r["integrator"] == integ
                    and r["substeps"] == 1]
            order, used = fit_order([r["h"] for r in base], [r["error"] for r in base])
            orders[p.key][integ] = {"order": order, "points": used}
        for target in TARGETS:
            costs = {}
            for integ in INTEGRATORS + (ADAPTIVE,):
                mine = [r for r in rows if r["problem"] == p.key and r["integrator"] == integ]
                costs[integ] = cost_for_error([r["cpu_per_sim_second"] for r in mine],
                                              [r["error"] for r in mine], target)
            reached = {k: v[0] for k, v in costs.items() if v is not None}
            best = min(reached, key=reached.get) if reached else None
            reading[p.key][f"{target:g}"] = {"costs": costs, "best": best}
    return {"orders": orders, "reading": reading, "adaptive": adaptive_reading(problems, rows)}


def adaptive_reading(problems, rows):
    """Per adaptive run: achieved against requested error, and the cheapest
    fixed-step integrator's cost at the same achieved error (fixed_cost_at);
    ratio = adaptive cost / that cost."""
    out = []
    for p in problems:
        fixed = [r for r in rows if r["problem"] == p.key and r["integrator"] != ADAPTIVE]
        for r in (r for r in rows if r["problem"] == p.key and r["integrator"] == ADAPTIVE):
            best = None
            for integ in INTEGRATORS:
                c = fixed_cost_at([f for f in fixed if f["integrator"] == integ], r["error"])
                if c is not None and (best is None or c[0] < best[1]):
                    best = (integ, c[0], c[1])
            out.append({"problem": p.key, "tolerance": r["tolerance"], "error": r["error"],
                        "internal_steps": r["internal_steps"], "rejected_steps": r["rejected_steps"],
                        "cost": r["cpu_per_sim_second"],
                        "best_fixed": best[0] if best else None,
                        "best_fixed_cost": best[1] if best else None,
                        "best_fixed_how": best[2] if best else None,
                        "ratio": r["cpu_per_sim_second"] / best[1] if best else None})
    return out


# ---- Markdown -----------------------------------------------------------------
def orders_table(problems, orders):
    header = ["problem"] + [f"{LABELS[i]} (expect {ORDERS_EXPECTED[i]})" for i in INTEGRATORS]
    rows = []
    for p in problems:
        cells = [p.title]
        for integ in INTEGRATORS:
            o = orders[p.key][integ]
            cells.append("—" if o["order"] != o["order"] else f"{o['order']:.2f} ({o['points']} pts)")
        rows.append(cells)
    return md.table(header, rows, align="l" + "r" * len(INTEGRATORS))


def reading_table(problems, reading):
    columns = INTEGRATORS + ((ADAPTIVE,) if ADAPTIVE in next(iter(reading.values()))[f"{TARGETS[0]:g}"]["costs"]
                             else ())
    header = ["problem", "error ≤"] + [LABELS[i] for i in columns] + ["use"]
    rows = []
    for p in problems:
        for target in TARGETS:
            rd = reading[p.key][f"{target:g}"]
            cells = [p.title, f"{target:g}"]
            for integ in columns:
                c = rd["costs"][integ]
                cells.append("not reached" if c is None else ("≤ " if c[1] else "") + md.seconds(c[0]))
            cells.append(LABELS[rd["best"]] if rd["best"] else "—")
            rows.append(cells)
    return md.table(header, rows, align="ll" + "r" * len(columns) + "l")


def adaptive_table(problems, entries):
    header = ["problem", "accuracy", "achieved error", "achieved / requested", "internal steps",
              "rejected", "CPU s / sim s", "cheapest fixed step at that error", "adaptive / fixed"]
    rows = []
    for p in problems:
        for e in (e for e in entries if e["problem"] == p.key):
            how = e["best_fixed_how"]
            fixed = "not reached by the grid" if e["best_fixed"] is None else (
                f"{LABELS[e['best_fixed']]} {'≤ ' if how == '≤' else ''}{md.sci(e['best_fixed_cost'])}"
                + (" (extrapolated)" if how == "extrapolated" else ""))
            rows.append([p.title, f"{e['tolerance']:g}", md.sci(e["error"]),
                         f"{e['error'] / e['tolerance']:.2g}", e["internal_steps"], e["rejected_steps"],
                         md.sci(e["cost"]), fixed, "—" if e["ratio"] is None else f"{e['ratio']:.2f}"])
    return md.table(header, rows, align="lrrrrrrlr")


def adaptive_verdict(problems, entries):
    """Plain words: where the adaptive mode is not at or below the best fixed step."""
    lines = []
    for p in problems:
        mine = [e for e in entries if e["problem"] == p.key and e["ratio"] is not None]
        worse = [e for e in mine if e["ratio"] > 1.0]
        if not mine:
            continue
        if worse:
            lines.append(f"- {p.title}: above the cheapest fixed step at "
                         + ", ".join(f"accuracy {e['tolerance']:g} (×{e['ratio']:.2f}, vs "
                                     f"{LABELS[e['best_fixed']]}"
                                     + (", extrapolated" if e["best_fixed_how"] == "extrapolated" else "")
                                     + ")" for e in worse)
                         + (f"; at or below it at the other {len(mine) - len(worse)}."
                            if len(worse) < len(mine) else "."))
        else:
            lines.append(f"- {p.title}: at or below the cheapest fixed step at all {len(mine)} "
                         "accuracies.")
    return "\n".join(lines)


def report(problems, data):
    mode = "quick" if data["quick"] else "full"
    parts = [
        "# Integrator accuracy: work–precision study\n",
        f"Run: `physics-bench accuracy{' --quick' if data['quick'] else ''}` ({mode} mode), "
        f"{data['machine']}.\n",
        "Error: relative distance to the closed-form answer at the end of the run "
        "(phase space for oscillators and the fall, relative position for the orbit, "
        "body-frame ω for the top). Cost: CPU seconds of `world.step` per simulated second "
        "(best chunk of the run, short runs repeated). h = dt / substeps; \"(spring)\" marks "
        "runs where the engine added sub-steps of its own to keep a spring stable "
        "(ω h ≤ 0.5).\n",
        "## Measured orders (slope of log error against log h)\n",
        f"Fitted over the runs with {1e-11:g} < error < 0.3 (the asymptotic regime).\n",
        orders_table(problems, data["orders"]),
        "\n## For this error, use that (CPU time per simulated second to reach it)\n",
        "Interpolated between runs on the work–precision lines; ≤ marks an integrator whose "
        "coarsest run already meets the target; \"not reached\" means no run of this grid "
        "did.\n",
        reading_table(problems, data["reading"]),
    ]
    if data.get("adaptive"):
        parts += [
            "\n## Error-controlled integration (`integrator: adaptive`)\n",
            "Dormand–Prince 5(4) with the PI step-size controller, one output step per "
            "problem (dt below), the requested accuracy on the left. Achieved error: the "
            "problem's error norm above; the engine holds each internal step's local error "
            "to 1e-4 of the request (physics_core/accuracy_params.py), so it lands well below "
            "the request. Cost: the sum of each chunk's best time over repeated runs (the "
            "fixed steps' figure is their single best chunk, which favours them slightly). "
            "Cheapest fixed step: interpolated on each fixed integrator's work–precision line "
            "at the adaptive run's achieved error, or extrapolated along its two most "
            "accurate runs when the error is below what its grid reached. Last column: "
            "adaptive cost over that (≤ 1: adaptive is at or below it).\n",
            adaptive_table(problems, data["adaptive"]),
            "\n" + adaptive_verdict(problems, data["adaptive"]) + "\n"]
    for p in problems:
        parts.append(f"\n## {p.title}\n")
        parts.append(f"Exact: {p.exact}. Simulated {p.duration(data['quick']):.3g} s.\n")
        parts.append(f"![{p.title}](accuracy_{p.key}.png)\n")
        rows = [r for r in data["rows"] if r["problem"] == p.key and r["integrator"] != ADAPTIVE]
        parts.append(md.table(
            ["integrator", "dt (s)", "substeps", "h (s)", "steps", "error", "CPU s / sim s"],
            [[LABELS[r["integrator"]], md.sci(r["dt"], 3), _substeps(r), md.sci(r["h"], 3),
              r["steps"], md.sci(r["error"]), md.sci(r["cpu_per_sim_second"])] for r in rows]))
    return "\n".join(parts)


def _substeps(row):
    if row["effective_substeps"] != row["substeps"]:
        return f"{row['effective_substeps']} (spring)"
    return row["substeps"]


# ---- plots ----------------------------------------------------------------------
def _series(ax, rows, p_key, integ, x, label):
    base = sorted((r for r in rows if r["problem"] == p_key and r["integrator"] == integ
                   and r["substeps"] == 1), key=lambda r: r.get("tolerance", 0.0))
    sub = [r for r in rows if r["problem"] == p_key and r["integrator"] == integ and r["substeps"] > 1]
    color, marker = plotting.COLORS[integ], plotting.MARKERS[integ]
    ax.plot([r[x] for r in base], [r["error"] for r in base], marker=marker, color=color, label=label)
    if sub:
        ax.plot([r[x] for r in sub], [r["error"] for r in sub], marker=marker, color=color,
                linestyle="none", markerfacecolor="none", markersize=10)


def plot_problem(p, rows, orders, path):
    fig, (ax_h, ax_c) = plotting.figure(ncols=2)
    for integ in INTEGRATORS:
        o = orders[integ]["order"]
        label = f"{LABELS[integ]} (order {o:.2f})" if o == o else LABELS[integ]
        _series(ax_h, rows, p.key, integ, "h", label)
        _series(ax_c, rows, p.key, integ, "cpu_per_sim_second", LABELS[integ])
    _series(ax_h, rows, p.key, ADAPTIVE, "h", LABELS[ADAPTIVE] + " (mean internal step)")
    _series(ax_c, rows, p.key, ADAPTIVE, "cpu_per_sim_second", LABELS[ADAPTIVE])
    ax_h.set_xlabel("step h = dt / substeps (s)")
    ax_h.set_ylabel("relative error")
    ax_h.set_title(f"{p.title}: convergence")
    ax_h.legend(fontsize=8)
    ax_c.set_xlabel("CPU seconds per simulated second")
    ax_c.set_ylabel("relative error")
    ax_c.set_title(f"{p.title}: work–precision")
    ax_c.text(0.02, 0.02, "hollow: substeps > 1 at the coarsest dt", transform=ax_c.transAxes,
              fontsize=7, color="0.4")
    plotting.save(fig, path)


def plot_overview(problems, rows, orders, path):
    n = len(problems)
    fig, axes = plotting.figure(ncols=n, width=3.6, height=3.4)
    for ax, p in zip(axes, problems):
        for integ in INTEGRATORS + (ADAPTIVE,):
            _series(ax, rows, p.key, integ, "cpu_per_sim_second", LABELS[integ])
        ax.set_title(p.title, fontsize=9)
        ax.set_xlabel("CPU s per simulated s", fontsize=8)
        ax.tick_params(labelsize=7)
    axes[0].set_ylabel("relative error")
    axes[0].legend(fontsize=7)
    plotting.save(fig, path)
