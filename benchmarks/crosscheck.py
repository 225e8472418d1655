"""`physics-bench crosscheck`: this engine, PyBullet and MuJoCo against the course's closed forms.

    physics-bench crosscheck [--quick] [--out DIR] [--engines physics_core pybullet mujoco]

Six scenes with a closed form (benchmarks/crosscheck_scenes.py: slide to
stop, bounce apex, roll at 5/7, incline hold and slide, 20-box stack drift,
1000:1 mass ratio), the same start in every engine, dt = 1/240 s, each
engine at its default solver settings with what was set stated
(benchmarks/crosscheck_engines.py). One row per scene: the closed form, each
engine's value and its error, and which engine is closest. PyBullet and
MuJoCo are optional (`pip install .[compare]`): a missing one is named and
its columns read "not installed". `--quick` runs the stack for 5 s and the
mass ratio for 2 s instead of 10 s and 5 s.

Writes crosscheck.md and crosscheck.json into DIR (default benchmarks/results).
"""
import math
import sys
import warnings
from time import perf_counter

from . import crosscheck_engines as ce
from . import crosscheck_scenes as cs
from . import markdown as md
from .pile_compare import installed
from .progress import Progress
from .results_io import machine, write_json, write_text

# Why an engine differs from the closed form where the cause is a property of its model
# (not of this run's numbers); quoted under the table.
MODEL_NOTES = {
    "slide": "PyBullet and MuJoCo are given μ = μ_k, so only their sliding friction is tested. "
             "A semi-implicit step that moves a body by its whole velocity change stops "
             "v0 dt / 2 − a dt² f (1 − f) / 2 = 6.24 mm short of the continuous distance (f = 0.49, "
             "the fraction of a step left when it stops); the peers are near that. This engine "
             "moves a body by half of what friction at its kinetic bound changed, the exact motion "
             "under that constant force (½ a h², COURSE.md 4; physics_core/collision/kinetic_drift.py), "
             "so it is on x = v0 t − ½ a t² after every whole step and stops short only by the last, "
             "partial one, f² a dt² / 2 = 8 µm. The peers' own distances are longer than the "
             "semi-implicit one by what their contacts lose while they form (measured): PyBullet's "
             "first steps take 0.15, 0.41, 0.68 μ_k g dt as its box sinks into the floor (5.7 mm "
             "after 100 steps); MuJoCo's soft contact throws the box up at 0.42 m/s in its second "
             "step and it slides 20 steps in the air, without friction.",
    "bounce": "MuJoCo has no coefficient of restitution: C_R is mapped to the damping ratio of its "
              f"contact spring, ζ = {ce.mujoco_dampratio(cs.C_R):.4f} (a linear spring–damper's e = "
              "exp(−ζπ/√(1−ζ²))), with solref timeconst "
              f"{ce.mujoco_timeconst(cs.C_R):.3g} s so that the step resolves the spring (with its "
              "default 0.02 s the apex was 0.42 m). PyBullet's bounce comes out 6 % high.",
    "roll": "MuJoCo at condim 3 (condim 6 would add rolling friction, which the closed form has not). "
            "PyBullet and this engine land on 5/7 to rounding: friction at the contact point keeps the "
            "angular momentum about it, and both reach that point on the ball's surface. MuJoCo ends "
            "0.05 % low.",
    "incline_hold": "PyBullet and MuJoCo have one μ; here it is μ_s, so their hold is the same "
                    "Coulomb test as the course's. MuJoCo's contacts are soft: friction holds by "
                    "a regularised force, which creeps.",
    "incline_slide": "PyBullet and MuJoCo get μ = μ_k for this row (with one μ they cannot hold "
                     "at μ_s and slide at μ_k in one scene; this engine does).",
    "stack": "MuJoCo's soft contacts settle into each other under load (a spring of its "
             "solref per contact), which adds up over the 19 contacts below the top.",
    "mass_ratio": "A sink of the cube's full height, 0.2 m, is the light cube squeezed out from under the "
                  "heavy one; MuJoCo's soft contact is compressed by the 1,000 kg load instead.",
}


def measure(engine, row):
    """(value, settings, status): status None when measured, else why not."""
    if not installed(engine):
        return None, None, "not installed"
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            reader = ce.build(engine, row.spec)
            value = float(row.measure(reader, row.spec))
    except Exception as exc:                      # a peer failing is a result, not a crash
        return None, None, f"failed: {type(exc).__name__}: {exc}"
    if not math.isfinite(value):
        return None, reader.settings, "no value (non-finite)"
    return value, reader.settings, None


def closest(row_data):
    errs = {e: v["error"] for e, v in row_data["engines"].items() if v["error"] is not None}
    if not errs:
        return []
    best = min(errs.values())
    return [e for e, err in errs.items() if err <= best + 1e-12]


def run(quick=False, out=None, engines=ce.ENGINES):
    rows = cs.rows(quick)
    prog = Progress("crosscheck", len(rows) * len(engines))
    missing = [e for e in engines if not installed(e)]
    if missing:
        prog.note("not installed (their columns say so): " + ", ".join(missing))
    data = {"quick": quick, "machine": machine(), "dt": cs.DT, "engines": list(engines),
            "missing": missing, "settings": {}, "rows": []}
    start = perf_counter()
    for row in rows:
        rd = {"key": row.key, "title": row.title, "closed_form": row.closed_form,
              "formula": row.formula, "course": row.course, "unit": row.unit,
              "peer_mu": row.spec.peer_mu, "engines": {}}
        for engine in engines:
            t0 = perf_counter()
            value, settings, status = measure(engine, row)
            if settings:
                data["settings"].setdefault(engine, {})[row.key] = settings
            err = None if value is None else abs(value - row.closed_form)
            rd["engines"][engine] = {"value": value, "error": err, "status": status,
                                     "seconds": perf_counter() - t0}
            prog.step(f"{row.key}, {engine}: " + (status or f"{value:.6g} {row.unit} "
                                                  f"(closed form {row.closed_form:.6g})"))
        rd["closest"] = closest(rd)
        data["rows"].append(rd)
    data["seconds"] = perf_counter() - start
    if out:
        write_json(out, "crosscheck.json", data)
        write_text(out, "crosscheck.md", report(data))
    return data


# ---- report ----------------------------------------------------------------------------
def _cell(row, engine):
    v = row["engines"].get(engine)
    if v is None:
        return ["not run", "—"]
    if v["value"] is None:
        return [v["status"], "—"]
    rel = (f" ({100 * v['error'] / abs(row['closed_form']):.2g} %)" if row["closed_form"] else "")
    return [f"{v['value']:.4g}", f"{v['error']:.2e}{rel}"]


def table(data):
    engines = data["engines"]
    head = ["row", "closed form (COURSE.md §)", "exact", "peers' μ"]
    for e in engines:
        head += [ce.TITLES[e], "error"]
    head.append("closest")
    body = []
    for r in data["rows"]:
        cells = [r["title"], f"{r['formula']} (§{r['course']})", f"{r['closed_form']:.4g} {r['unit']}",
                 f"{r['peer_mu']:g}"]
        for e in engines:
            cells += _cell(r, e)
        cells.append(", ".join(ce.TITLES[e] for e in r["closest"]) or "—")
        body.append(cells)
    return md.table(head, body, align="lllr" + "rr" * len(engines) + "l")


def readings(data):
    """One line per row: who is closest, by how much, and the model reason where known."""
    lines = []
    for r in data["rows"]:
        errs = {e: v["error"] for e, v in r["engines"].items() if v["error"] is not None}
        parts = ", ".join(f"{ce.TITLES[e]} {errs[e]:.2g} {r['unit']}" for e in errs)
        who = ", ".join(ce.TITLES[e] for e in r["closest"]) or "no engine"
        note = MODEL_NOTES.get(r["key"], "")
        lines.append(f"- **{r['key']}**: closest {who} (errors: {parts}).{' ' + note if note else ''}")
    return "\n".join(lines) + "\n"


def settings_lines(data):
    out = []
    for e in data["engines"]:
        s = data["settings"].get(e)
        if not s:
            out.append(f"- {ce.TITLES[e]}: " + ("not installed" if e in data["missing"] else "no run"))
            continue
        distinct = sorted(set(s.values()), key=list(s.values()).index)
        out.append(f"- {ce.TITLES[e]}: " + " / ".join(distinct))
    return "\n".join(out) + "\n"


def report(data):
    wins = sum(1 for r in data["rows"] if r["closest"] == ["physics_core"] or
               "physics_core" in r["closest"])
    return "\n".join([
        "# Cross-check against PyBullet and MuJoCo\n",
        f"Run: `physics-bench crosscheck{' --quick' if data['quick'] else ''}`, {data['machine']}, "
        f"{data['seconds']:.0f} s. Same start in every engine, dt = 1/{round(1 / data['dt'])} s, "
        "every body awake, no damping. Error: |value − closed form|. This engine is closest "
        f"on {wins} of {len(data['rows'])} rows."
        + (f" Not installed: {', '.join(data['missing'])}." if data["missing"] else "") + "\n",
        table(data),
        "Settings (what each engine was given; the rest is its default):\n",
        settings_lines(data),
        "Reading:\n",
        readings(data)])


def main(argv=None):
    import argparse
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", default=None)
    ap.add_argument("--engines", nargs="+", default=list(ce.ENGINES), choices=ce.ENGINES)
    args = ap.parse_args(argv)
    data = run(args.quick, args.out, tuple(args.engines))
    sys.stdout.write(report(data))


if __name__ == "__main__":
    main()
