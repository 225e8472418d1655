"""The contact part of `physics-bench accuracy` (contact_scenes.py):

- bouncing ball: apex-height error against integrator × dt × substeps, and cost;
- time of impact: bisection iterations against impact-time error,
  penetration and the cost of the ccd stage, for a bullet and a thin wall;
- stack: solver iterations against the drift of a box stack, and cost.

Writes `contacts.md`, `contacts.json`, `contacts_bounce.png`,
`contacts_toi.png`, `contacts_stack.png`; skips with the reason when the
engine cannot simulate contacts.
"""
import math
import warnings
from time import perf_counter

import numpy as np

from physics_core import NonFiniteStateError, load_scene

from . import contact_scenes as cs
from . import markdown as md
from . import plotting
from .accuracy import LABELS
from .contact_support import available, skipped
from .orders import fit_order
from .problems import INTEGRATORS
from .progress import Progress
from .results_io import machine, write_json, write_text

BOUNCE_DTS = {True: (1 / 60, 1 / 120, 1 / 240, 1 / 480),
              False: (1 / 30, 1 / 60, 1 / 120, 1 / 240, 1 / 480, 1 / 960, 1 / 1920)}
BOUNCE_SUBSTEPS = {True: (4,), False: (2, 4, 8)}
TOI_ITERATIONS = {True: (1, 2, 4, 8, 16, 30), False: (1, 2, 3, 4, 6, 8, 12, 16, 20, 24, 30)}
TOI_SUBSTEPS = {True: (4,), False: (2, 4, 8)}
TOI_OFFSETS = {True: 4, False: 12}      # impact at this many fractions of the step
TOI_AFTER = 0.1                          # s simulated after the impact
STACK = {True: (8, (1, 2, 4, 8, 16, 32), 2.0), False: (10, (1, 2, 4, 8, 16, 32, 64), 5.0)}


def run(quick=False, out=None):
    ok, why = available()
    if not ok:
        msg = f"contact studies skipped: contacts are not available ({why})"
        Progress("contacts", 1).note(msg)
        data = {"quick": quick, "skipped": why}
        if out:
            write_json(out, "contacts.json", data)
            write_text(out, "contacts.md", skipped("Contact accuracy", why))
        return data
    boxes, iters, _ = STACK[quick]
    total = (len(INTEGRATORS) * (len(BOUNCE_DTS[quick]) + len(BOUNCE_SUBSTEPS[quick]))
             + len(TOI_ITERATIONS[quick]) + 1 + len(TOI_SUBSTEPS[quick]) + len(iters))
    prog = Progress("contacts", total)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)    # friction-table fallbacks of test scenes
        data = {"quick": quick, "machine": machine(), "bounce": bounce_study(quick, prog),
                "toi": toi_study(quick, prog), "stack": stack_study(quick, prog)}
    data["bounce_orders"] = {
        integ: dict(zip(("order", "points"), fit_order(
            [r["h"] for r in data["bounce"] if r["integrator"] == integ and r["substeps"] == 1],
            [r["error"] for r in data["bounce"] if r["integrator"] == integ and r["substeps"] == 1])))
        for integ in INTEGRATORS}
    if out:
        write_json(out, "contacts.json", data)
        write_text(out, "contacts.md", report(data))
        plot_bounce(data, f"{out}/contacts_bounce.png")
        plot_toi(data, f"{out}/contacts_toi.png")
        plot_stack(data, f"{out}/contacts_stack.png")
    return data


# ---- bouncing ball ---------------------------------------------------------------
def bounce_run(integrator, dt, substeps):
    world = load_scene(cs.bounce(integrator, dt, substeps))
    g = -float(world.model.gravity[2])
    ball = world.model.index["ball"]
    apexes, prev_vz, elapsed = [], 0.0, 0.0
    steps = round(cs.BOUNCE_DURATION / dt)
    try:
        for _ in range(steps):
            t0 = perf_counter()
            world.step()
            elapsed += perf_counter() - t0
            z, vz = world.state.pos[ball, 2], world.state.vel[ball, 2]
            if prev_vz < 0.0 <= vz:
                # apex of the free flight that starts from this state (exact ballistics)
                apexes.append(z - cs.BOUNCE_RADIUS + vz * vz / (2.0 * g))
            prev_vz = vz
    except NonFiniteStateError:
        pass
    exact = cs.bounce_apexes_exact()
    got = apexes[:cs.BOUNCES]
    err = (max(abs(a - e) for a, e in zip(got, exact)) / cs.BOUNCE_H0
           if len(got) == len(exact) else float("inf"))
    return {"integrator": integrator, "dt": dt, "substeps": substeps, "h": dt / substeps,
            "apexes": got, "error": err, "cpu_per_sim_second": elapsed / (steps * dt)}


def bounce_study(quick, prog):
    rows = []
    for integ in INTEGRATORS:
        dts = BOUNCE_DTS[quick]
        plan = [(dt, 1) for dt in dts] + [(dts[0], s) for s in BOUNCE_SUBSTEPS[quick]]
        for dt, sub in plan:
            r = bounce_run(integ, dt, sub)
            rows.append(r)
            prog.step(f"bounce {integ} dt=1/{round(1 / dt)} ×{sub}: apex error {r['error']:.2e}")
    return rows


# ---- time of impact -----------------------------------------------------------------
def toi_run(ccd, iterations, start_gap, substeps=1, dt=cs.BULLET_DT):
    world = load_scene(cs.bullet(dt, start_gap, ccd, iterations, substeps))
    b = world.model.index["bullet"]
    touch_x = -(cs.WALL_HALF + cs.BULLET_RADIUS)        # centre of the ball when it touches
    t_star = start_gap / cs.BULLET_SPEED
    steps = math.ceil((t_star + TOI_AFTER) / dt)
    deepest, elapsed = touch_x, 0.0
    for _ in range(steps):
        t0 = perf_counter()
        world.step()
        elapsed += perf_counter() - t0
        deepest = max(deepest, world.state.pos[b, 0])
    x, vx = world.state.pos[b, 0], world.state.vel[b, 0]
    tunnelled = bool(x > 0.0)
    # how far past the touching position the ball got (through the wall: infinite)
    depth = float("inf") if tunnelled else deepest - touch_x
    if vx < 0.0 and not tunnelled:
        # extrapolate the free rebound back to where it left the wall
        t_est = world.time - (touch_x - x) / (-vx)
        time_error = abs(t_est - t_star)
    else:
        time_error = float("nan")
    ccd_time = world.profile.get("ccd", 0.0)
    return {"tunnelled": tunnelled, "time_error": time_error, "penetration": max(depth, 0.0),
            "rebound_speed": float(-vx), "ccd_seconds_per_step": ccd_time / steps,
            "seconds_per_step": elapsed / steps}


def toi_study(quick, prog):
    n = TOI_OFFSETS[quick]
    step = cs.BULLET_SPEED * cs.BULLET_DT
    # impacts spread evenly across the step, away from its ends
    gaps = [2.0 + step * (k + 0.5) / n for k in range(n)]
    rows = []
    plan = ([(False, 0, 1)] + [(True, k, 1) for k in TOI_ITERATIONS[quick]]
            + [(True, TOI_ITERATIONS[quick][-1], s) for s in TOI_SUBSTEPS[quick]])
    for ccd, iterations, substeps in plan:
        runs = [toi_run(ccd, iterations, gap, substeps) for gap in gaps]
        times = [r["time_error"] for r in runs if r["time_error"] == r["time_error"]]
        rows.append({
            "ccd": ccd, "ccd_iterations": iterations, "substeps": substeps, "runs": len(runs),
            "tunnelled": sum(r["tunnelled"] for r in runs),
            "max_time_error": max(times) if times else float("nan"),
            "mean_time_error": float(np.mean(times)) if times else float("nan"),
            "max_penetration": max(r["penetration"] for r in runs),
            "mean_rebound_speed": float(np.mean([r["rebound_speed"] for r in runs])),
            "ccd_seconds_per_step": float(np.mean([r["ccd_seconds_per_step"] for r in runs])),
            "seconds_per_step": float(np.mean([r["seconds_per_step"] for r in runs]))})
        r = rows[-1]
        prog.step(f"time of impact, {'ccd off' if not ccd else f'{iterations} halvings'} ×{substeps}: "
                  f"{r['tunnelled']}/{len(runs)} tunnelled, max time error {r['max_time_error']:.2e} s")
    return rows


# ---- stack ------------------------------------------------------------------------------
def stack_study(quick, prog):
    boxes, iterations, duration = STACK[quick]
    rows = []
    for it in iterations:
        world = load_scene(cs.stack(boxes, it))
        p0 = world.state.pos.copy()
        steps = round(duration / world.dt)
        t0 = perf_counter()
        try:
            world.step(steps)
            finite = True
        except NonFiniteStateError:
            finite = False
        elapsed = perf_counter() - t0
        d = world.state.pos - p0
        dyn = ~world.model.is_static
        rows.append({"boxes": boxes, "iterations": it, "duration": duration, "finite": finite,
                     "max_horizontal_drift": float(np.abs(d[dyn, :2]).max()),
                     "top_sink": float(-d[dyn][-1, 2]),
                     "max_drift": float(np.linalg.norm(d[dyn], axis=1).max()),
                     "cpu_per_sim_second": elapsed / (steps * world.dt)})
        prog.step(f"stack of {boxes}, {it} iterations: drift {rows[-1]['max_drift']:.3g} m")
    return rows


# ---- report ----------------------------------------------------------------------------
def report(data):
    quick = data["quick"]
    boxes, _, duration = STACK[quick]
    ord_cells = []
    for integ in INTEGRATORS:
        o = data["bounce_orders"][integ]
        ord_cells.append(f"{LABELS[integ]} {o['order']:.2f}" if o["order"] == o["order"]
                         else f"{LABELS[integ]} —")
    parts = [
        "# Contact accuracy and cost\n",
        f"Run: `physics-bench accuracy{' --quick' if quick else ''}`, {data['machine']}.\n",
        "## Bouncing ball: apex heights against integrator, dt and substeps\n",
        f"A ball (r = {cs.BOUNCE_RADIUS} m, C_R = {cs.BOUNCE_E}) dropped from "
        f"{cs.BOUNCE_H0} m on a static plane: exact apexes h_n = C_R^(2n) h₀. Error: the "
        f"largest |h_n − exact| / h₀ over the first {cs.BOUNCES} bounces, each apex taken "
        "from the state just after the bounce (z + v²/2g). Measured orders: "
        + ", ".join(ord_cells) + ".\n",
        "![bounce](contacts_bounce.png)\n",
        md.table(["integrator", "dt (s)", "substeps", "apex heights (m)", "error",
                  "CPU s / sim s"],
                 [[LABELS[r["integrator"]], f"1/{round(1 / r['dt'])}", r["substeps"],
                   " ".join(f"{a:.3f}" for a in r["apexes"]), md.sci(r["error"]),
                   md.sci(r["cpu_per_sim_second"])] for r in data["bounce"]],
                 align="lrrlrr"),
        f"Exact: {' '.join(f'{a:.3f}' for a in cs.bounce_apexes_exact())}.\n",
        "## Time of impact: bisection iterations against impact time, penetration and cost\n",
        f"A {2 * cs.BULLET_RADIUS * 100:.0f} cm ball at {cs.BULLET_SPEED:g} m/s "
        f"({cs.BULLET_SPEED * cs.BULLET_DT:.2f} m per 1/{round(1 / cs.BULLET_DT)} s step) "
        f"against a {2 * cs.WALL_HALF * 100:.0f} cm static wall, elastic, started so that the "
        f"impact falls at {TOI_OFFSETS[quick]} evenly spread fractions of a step. "
        "Impact-time error: the rebound is extrapolated back to the touching position "
        "and compared with the exact t*. Penetration: the deepest overlap with the wall "
        "seen at the end of a step. ccd_tolerance is set to 10⁻¹² so the iteration count "
        "alone stops the bisection.\n",
        "![time of impact](contacts_toi.png)\n",
        md.table(["ccd", "bisection halvings", "substeps", "tunnelled", "max impact-time error",
                  "mean impact-time error", "max penetration (m)", "rebound speed (m/s)",
                  "ccd stage / step", "step"],
                 [["off" if not r["ccd"] else "on", r["ccd_iterations"] if r["ccd"] else "—",
                   r["substeps"], f"{r['tunnelled']}/{r['runs']}",
                   # with a run through the wall there is no rebound to time
                   md.seconds(r["max_time_error"]) if not r["tunnelled"] else "—",
                   md.seconds(r["mean_time_error"]) if not r["tunnelled"] else "—",
                   "through the wall" if r["max_penetration"] == float("inf")
                   else md.sci(r["max_penetration"]),
                   md.num(r["mean_rebound_speed"]), md.seconds(r["ccd_seconds_per_step"]),
                   md.seconds(r["seconds_per_step"])] for r in data["toi"]],
                 align="lrrrrrrrrr"),
        f"## Stack: solver iterations against drift\n",
        f"{boxes} boxes (0.5 m cubes, 1 kg, C_R = 0) stacked on the ground, dt = 1/60 s, "
        f"sleep off, run {duration:g} s. Exact: nothing moves. Drift: the largest "
        "displacement of any box; sink: how far the top box went down.\n",
        "![stack](contacts_stack.png)\n",
        md.table(["iterations", "max drift (m)", "max horizontal drift (m)", "top box sink (m)",
                  "CPU s / sim s", "finite"],
                 [[r["iterations"], md.sci(r["max_drift"]), md.sci(r["max_horizontal_drift"]),
                   md.sci(r["top_sink"]), md.sci(r["cpu_per_sim_second"]),
                   "yes" if r["finite"] else "**no**"] for r in data["stack"]]),
    ]
    return "\n".join(parts)


# ---- plots -----------------------------------------------------------------------------------
def plot_bounce(data, path):
    fig, (ax_h, ax_c) = plotting.figure(ncols=2)
    for integ in INTEGRATORS:
        base = [r for r in data["bounce"] if r["integrator"] == integ and r["substeps"] == 1]
        sub = [r for r in data["bounce"] if r["integrator"] == integ and r["substeps"] > 1]
        for ax, x in ((ax_h, "h"), (ax_c, "cpu_per_sim_second")):
            ax.plot([r[x] for r in base], [r["error"] for r in base], color=plotting.COLORS[integ],
                    marker=plotting.MARKERS[integ], label=LABELS[integ])
            ax.plot([r[x] for r in sub], [r["error"] for r in sub], color=plotting.COLORS[integ],
                    marker=plotting.MARKERS[integ], linestyle="none", markerfacecolor="none",
                    markersize=10)
    ax_h.set_xlabel("h = dt / substeps (s)")
    ax_c.set_xlabel("CPU seconds per simulated second")
    for ax in (ax_h, ax_c):
        ax.set_ylabel("apex-height error / h₀")
    ax_h.set_title("Bouncing ball: convergence")
    ax_c.set_title("Bouncing ball: work–precision")
    ax_h.legend(fontsize=8)
    plotting.save(fig, path)


def plot_toi(data, path):
    rows = [r for r in data["toi"] if r["ccd"] and r["substeps"] == 1]
    subs = [r for r in data["toi"] if r["ccd"] and r["substeps"] > 1]
    fig, (ax_i, ax_c) = plotting.figure(ncols=2)
    ax_i.set_xscale("linear")
    it = [r["ccd_iterations"] for r in rows]
    ax_i.plot(it, [r["max_time_error"] for r in rows], marker="o", label="max impact-time error (s)")
    ax_i.plot(it, [min(max(r["max_penetration"], 1e-12), 1.0) for r in rows], marker="s",
              label="max penetration (m, floor 1e-12)")
    ax_i.axhline(cs.BULLET_DT, color="0.5", linestyle=":", label="one step (s)")
    ax_i.set_xlabel("bisection halvings (ccd_iterations)")
    ax_i.set_title("Time of impact: error against halvings")
    ax_i.legend(fontsize=8)
    ax_c.plot([r["ccd_seconds_per_step"] for r in rows], [r["max_time_error"] for r in rows],
              marker="o")
    for r in rows:
        ax_c.annotate(str(r["ccd_iterations"]), (r["ccd_seconds_per_step"], r["max_time_error"]),
                      fontsize=7, xytext=(3, 3), textcoords="offset points")
    ax_c.plot([r["ccd_seconds_per_step"] for r in subs],
              [r["max_time_error"] for r in subs], marker="D", linestyle="none",
              markerfacecolor="none", color="tab:purple", label="substeps > 1")
    for r in subs:
        ax_c.annotate(f"×{r['substeps']}", (r["ccd_seconds_per_step"], r["max_time_error"]),
                      fontsize=7, xytext=(3, -9), textcoords="offset points", color="tab:purple")
    ax_c.legend(fontsize=8)
    ax_c.set_xlabel("ccd stage CPU seconds per step")
    ax_c.set_ylabel("max impact-time error (s)")
    ax_c.set_title("Time of impact: error against cost")
    plotting.save(fig, path)


def plot_stack(data, path):
    rows = data["stack"]
    fig, (ax_i, ax_c) = plotting.figure(ncols=2)
    drift = [max(r["max_drift"], 1e-9) for r in rows]
    ax_i.plot([r["iterations"] for r in rows], drift, marker="o")
    ax_i.set_xlabel("solver iterations per step")
    ax_i.set_ylabel("max drift of a box (m)")
    ax_i.set_title(f"Stack of {rows[0]['boxes']}: drift against iterations")
    ax_c.plot([r["cpu_per_sim_second"] for r in rows], drift, marker="o")
    for r, d in zip(rows, drift):
        ax_c.annotate(str(r["iterations"]), (r["cpu_per_sim_second"], d), fontsize=7,
                      xytext=(3, 3), textcoords="offset points")
    ax_c.set_xlabel("CPU seconds per simulated second")
    ax_c.set_ylabel("max drift of a box (m)")
    ax_c.set_title("Stack: drift against cost")
    plotting.save(fig, path)
