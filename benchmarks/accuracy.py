"""`physics-bench accuracy`: the work–precision study of the four integrators.

For every problem of problems.py and every integrator, runs a ladder of
step sizes (substeps = 1) and a few substep variants at the coarsest dt,
measures the relative error against the closed form and the CPU time per
simulated second, fits the convergence order, and writes
`accuracy.md`, `accuracy.json` and one `accuracy_<problem>.png` per problem
(error against step size, and error against cost), plus
`accuracy_overview.png` (all work–precision panels in one figure).
"""
from physics_core import load_scene

from . import markdown as md
from . import plotting
from .orders import cost_for_error, fit_order
from .problems import INTEGRATORS, ORDERS_EXPECTED, PROBLEMS
from .progress import Progress
from .results_io import machine, write_json, write_text
from .timing import run_for

TARGETS = (1e-2, 1e-4, 1e-6)          # relative errors the reading answers for
SUBSTEPS = {True: (4,), False: (2, 4, 8)}
LABELS = {"explicit_euler": "explicit Euler", "semi_implicit_euler": "semi-implicit Euler",
          "velocity_verlet": "velocity Verlet", "rk4": "RK4"}


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


def run(quick=False, out=None, only=None):
    problems = [p for p in PROBLEMS if not only or p.key in only]
    runs = plan(problems, quick)
    prog = Progress("accuracy", len(runs))
    rows = []
    for p, integ, dt, sub in runs:
        r = measure(p, integ, dt, sub, p.duration(quick))
        rows.append(r)
        prog.step(f"{p.key:9s} {integ:19s} dt={dt:.3g} s ×{sub}: error {r['error']:.2e}, "
                  f"{r['cpu_per_sim_second']:.3g} s CPU per simulated s")
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
            for integ in INTEGRATORS:
                mine = [r for r in rows if r["problem"] == p.key and r["integrator"] == integ]
                costs[integ] = cost_for_error([r["cpu_per_sim_second"] for r in mine],
                                              [r["error"] for r in mine], target)
            reached = {k: v[0] for k, v in costs.items() if v is not None}
            best = min(reached, key=reached.get) if reached else None
            reading[p.key][f"{target:g}"] = {"costs": costs, "best": best}
    return {"orders": orders, "reading": reading}


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
    header = ["problem", "error ≤"] + [LABELS[i] for i in INTEGRATORS] + ["use"]
    rows = []
    for p in problems:
        for target in TARGETS:
            rd = reading[p.key][f"{target:g}"]
            cells = [p.title, f"{target:g}"]
            for integ in INTEGRATORS:
                c = rd["costs"][integ]
                cells.append("not reached" if c is None else ("≤ " if c[1] else "") + md.seconds(c[0]))
            cells.append(LABELS[rd["best"]] if rd["best"] else "—")
            rows.append(cells)
    return md.table(header, rows, align="ll" + "r" * len(INTEGRATORS) + "l")


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
    for p in problems:
        parts.append(f"\n## {p.title}\n")
        parts.append(f"Exact: {p.exact}. Simulated {p.duration(data['quick']):.3g} s.\n")
        parts.append(f"![{p.title}](accuracy_{p.key}.png)\n")
        rows = [r for r in data["rows"] if r["problem"] == p.key]
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
    base = [r for r in rows if r["problem"] == p_key and r["integrator"] == integ and r["substeps"] == 1]
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
        for integ in INTEGRATORS:
            _series(ax, rows, p.key, integ, "cpu_per_sim_second", LABELS[integ])
        ax.set_title(p.title, fontsize=9)
        ax.set_xlabel("CPU s per simulated s", fontsize=8)
        ax.tick_params(labelsize=7)
    axes[0].set_ylabel("relative error")
    axes[0].legend(fontsize=7)
    plotting.save(fig, path)
