"""`README_results.md` and the README's results section, rebuilt from the JSON files
the studies wrote, so the reading always states what the latest tables show.
"""
import hashlib
import os
import re
import statistics

from . import engines
from . import markdown as md
from .accuracy import LABELS, TARGETS, orders_table, reading_table
from .problems import INTEGRATORS, ORDERS_EXPECTED, PROBLEMS
from .results_io import DEFAULT_OUT, read_json, write_text
from .stability_cases import isolated_verdict, long_run_verdict, passive_verdict

README = os.path.join(os.path.dirname(DEFAULT_OUT), os.pardir, "README.md")
END = "<!-- results:end -->"
# the begin marker of a section this module wrote carries its digest
# (`<!-- results:begin sha1=… -->`): a section whose text no longer matches it
# was edited by hand, and is never overwritten
_REGION = re.compile(r"<!-- results:begin(?: sha1=(?P<sha>[0-9a-f]{40}))? -->\n(?P<body>.*?)"
                     + re.escape(END), re.S)
ORDER_SLACK = 0.3      # a measured order this far from the expected one is called out
# What explains an order outside the expected band, where the cause is known.
ORDER_NOTES = {
    ("free_top", "semi_implicit_euler"):
        "on a torque-free body semi-implicit Euler turns the body by the same second-order "
        "torque-free splitting as velocity Verlet (physics_core/free_rotation.py); its "
        "translation stays first order",
    ("free_top", "rk4"): "above 4: at least fourth order over this range of steps",
}


def write(out, update_readme=False, readme=README):
    """README_results.md in `out`; with `update_readme`, also the results section
    of `readme` (update_section)."""
    body = build(out, prefix="")
    written = [write_text(out, "README_results.md", "# physics-bench results\n\n" + body)]
    if update_readme and os.path.exists(readme):
        rel = os.path.relpath(out, os.path.dirname(os.path.abspath(readme)))
        section = "## Results\n\n" + build(out, prefix=rel + "/", level=3)
        if update_section(readme, section):
            written.append(os.path.abspath(readme))
        else:
            written.append(f"not {os.path.abspath(readme)}: its results section holds hand "
                           "edits (README_results.md has the regenerated one)")
    return written


def update_section(readme, section):
    """Put `section` between the results markers of `readme` (appended if it has
    none), unless the text there is not what this module last wrote: then the
    file is left as it is. Returns whether it was written."""
    with open(readme, encoding="utf-8") as f:
        text = f.read()
    found = _REGION.search(text)
    if found and found["sha"] != _digest(found["body"]):
        return False
    block = f"<!-- results:begin sha1={_digest(section + chr(10))} -->\n{section}\n{END}"
    if found:
        text = text[:found.start()] + block + text[found.end():]
    else:
        text = text.rstrip("\n") + "\n\n" + block + "\n"
    with open(readme, "w", encoding="utf-8") as f:
        f.write(text)
    return True


def _digest(text):
    return hashlib.sha1(text.encode("utf-8")).hexdigest()


def build(out, prefix="", level=2):
    h = "#" * level
    parts = [
        "Regenerate with `physics-bench all` (about half an hour) or `physics-bench all --quick` "
        "(CI-sized, a few minutes); each study alone with `physics-bench accuracy|stability|"
        f"scale|effects`. Tables: [benchmarks/results/]({prefix or './'}) (`*.md`, raw data in "
        "`*.json`). "
        "Times are CPU seconds of `world.step` on the machine named in each table, best of "
        "several timed chunks.\n",
    ]
    short = _in_short(out)
    if short:
        parts.append(short)
    for title, fn in (("Accuracy of the integrators", _accuracy), ("Contacts", _contacts),
                      ("Stability", _stability), ("Scale", _scale), ("Cost of each effect", _effects),
                      ("The ROS 2 node in real time", _node),
                      ("Cross-check against PyBullet and MuJoCo", _crosscheck)):
        parts.append(f"{h} {title}\n")
        parts.append(fn(out, prefix, level + 1))
    others = _other_tables(out)
    if others:
        parts.append(f"{h} Other results\n")
        parts.append(" · ".join(f"[{name}]({prefix}{name})" for name in others) + "\n")
    return "\n".join(parts)


OWN_TABLES = {"accuracy.md", "contacts.md", "stability.md", "scale.md", "effects.md",
              "node_realtime.md", "crosscheck.md", "README_results.md"}


def _other_tables(out):
    """Tables other studies wrote into the same folder (linked, not restated)."""
    if not os.path.isdir(out):
        return []
    return sorted(f for f in os.listdir(out) if f.endswith(".md") and f not in OWN_TABLES)


def _crosscheck(out, prefix, level):
    from .crosscheck import readings, table
    data = read_json(out, "crosscheck.json")
    if not data:
        return "_Not run yet: `physics-bench crosscheck`._\n"
    wins = sum("physics_core" in r["closest"] for r in data["rows"])
    return "\n".join([
        f"`physics-bench crosscheck{' --quick' if data['quick'] else ''}` ({data['seconds']:.0f} s; "
        f"settings and model notes in [crosscheck.md]({prefix}crosscheck.md)): the course's closed "
        "forms on the same scenes in the three engines, same start, dt = 1/240 s, each engine at its "
        "default solver settings, every body awake. PyBullet and MuJoCo have one friction "
        "coefficient; each row gives them the one its closed form uses (peers' μ). This engine is "
        f"closest on {wins} of {len(data['rows'])} rows."
        + (f" Not installed: {', '.join(data['missing'])}." if data["missing"] else "") + "\n",
        table(data), readings(data)])


# ---- accuracy -------------------------------------------------------------------
def _accuracy(out, prefix, level):
    data = read_json(out, "accuracy.json")
    if not data:
        return "_Not run yet: `physics-bench accuracy`._\n"
    problems = [p for p in PROBLEMS if p.key in data["orders"]]
    mode = "quick" if data["quick"] else "full"
    lines = [f"Work–precision study ({mode} run; details in [accuracy.md]({prefix}accuracy.md)): "
             "each integrator on problems with closed-form answers, error at the end of the "
             "run against CPU time per simulated second.\n",
             f"![work–precision]({prefix}accuracy_overview.png)\n",
             "Measured orders (slope of log error against log h, finest runs in the "
             "asymptotic range):\n", orders_table(problems, data["orders"]),
             "\n" + _order_reading(problems, data) + "\n",
             "For this error, use that (CPU time per simulated second to reach it):\n",
             reading_table(problems, data["reading"]),
             "\n" + _cost_reading(problems, data) + "\n",
             "Per problem: " + ", ".join(f"[{p.title.lower()}]({prefix}accuracy_{p.key}.png)"
                                         for p in problems) + ".\n"]
    return "\n".join(lines)


def _in_short(out):
    """One paragraph: which integrator for which error, from the latest accuracy and contact runs."""
    acc = read_json(out, "accuracy.json")
    if not acc:
        return ""
    lines = []
    for target in TARGETS:
        wins = {}
        for key, rd in acc["reading"].items():
            best = rd[f"{target:g}"]["best"]
            if best:
                wins[best] = wins.get(best, 0) + 1
        if wins:
            ranked = sorted(wins, key=lambda k: -wins[k])
            lines.append(f"error ≤ {target:g}: {LABELS[ranked[0]]}"
                         + (f" (or {', '.join(LABELS[k] for k in ranked[1:])} on some problems)"
                            if len(ranked) > 1 else ""))
    con = read_json(out, "contacts.json")
    if con and con.get("bounce"):
        base = [r for r in con["bounce"] if r["substeps"] == 1]
        counts = {}
        for dt in {r["dt"] for r in base}:
            w = min((r for r in base if r["dt"] == dt), key=lambda r: r["error"])["integrator"]
            counts[w] = counts.get(w, 0) + 1
        best = max(counts, key=counts.get)
        n_dts = len({r["dt"] for r in base})
        lines.append(f"with contacts: {LABELS[best]} (most accurate bounces at "
                     f"{counts[best]} of {n_dts} step sizes)")
    return "**In short** — for this error, use that: " + "; ".join(lines) + ".\n"


def _order_reading(problems, data):
    parts = []
    for integ in INTEGRATORS:
        vals = [(p, data["orders"][p.key][integ]["order"]) for p in problems]
        vals = [(p, o) for p, o in vals if o == o]
        if not vals:
            continue
        expected = ORDERS_EXPECTED[integ]
        typical = [o for _, o in vals if abs(o - expected) <= ORDER_SLACK]
        odd = [(p, o) for p, o in vals if abs(o - expected) > ORDER_SLACK]
        text = (f"{LABELS[integ]} {min(typical):.2f}–{max(typical):.2f} (expected {expected})"
                if typical else f"{LABELS[integ]} (expected {expected})")
        if odd:
            text += "; " + ", ".join(
                f"{o:.2f} on the {p.title.lower()}"
                + (f": {ORDER_NOTES[(p.key, integ)]}" if (p.key, integ) in ORDER_NOTES else "")
                for p, o in odd)
        parts.append("- " + text + ".")
    return ("Reading, measured orders:\n\n" + "\n".join(parts) + "\n\nExplicit Euler is first "
            "order and RK4 fourth: halving the step divides their error by 2 and by 16.")


def _cost_reading(problems, data):
    out = []
    for target in TARGETS:
        wins = {}
        for p in problems:
            best = data["reading"][p.key][f"{target:g}"]["best"]
            wins.setdefault(best, []).append(p.title.lower())
        ranked = sorted(((k, v) for k, v in wins.items() if k), key=lambda kv: -len(kv[1]))
        if not ranked:
            out.append(f"- error ≤ {target:g}: no integrator reaches it in this grid.")
            continue
        first, probs = ranked[0]
        text = (f"- error ≤ {target:g}: **{LABELS[first]}** is cheapest on {len(probs)} of "
                f"{len(problems)} problems")
        others = [f"{LABELS[k]} on the {', '.join(v)}" for k, v in ranked[1:]]
        none = wins.get(None)
        if others:
            text += " (" + "; ".join(others) + ")"
        if none:
            text += f"; nothing reaches it on the {', '.join(none)}"
        out.append(text + ".")
    sub = _substep_ratio(data["rows"])
    if sub:
        out.append(f"- Sub-steps give the same error as the equivalent smaller dt (same h) at "
                   f"{100 * sub[0]:.0f}–{100 * sub[1]:.0f} % of its cost (median "
                   f"{100 * sub[2]:.0f} %): the work outside the integrator (finite check, "
                   "stage timing, commands) is paid once per step, not per sub-step.")
    euler_wins = any(data["reading"][p.key][f"{t:g}"]["best"] == "explicit_euler"
                     for p in problems for t in TARGETS)
    if not euler_wins:
        out.append("- Explicit Euler is never the cheapest way to any of these errors: use it "
                   "only to show what the others fix.")
    return "Reading:\n\n" + "\n".join(out)


def _substep_ratio(rows):
    ratios = []
    for r in rows:
        if r["substeps"] <= 1:
            continue
        twin = [b for b in rows if b["problem"] == r["problem"] and b["integrator"] == r["integrator"]
                and b["substeps"] == 1 and abs(b["h"] / r["h"] - 1.0) < 1e-6]
        if twin and abs(twin[0]["error"] / r["error"] - 1.0) < 0.05:
            ratios.append(r["cpu_per_sim_second"] / twin[0]["cpu_per_sim_second"])
    if not ratios:
        return None
    return min(ratios), max(ratios), statistics.median(ratios)


# ---- contacts -------------------------------------------------------------------
def _contacts(out, prefix, level):
    data = read_json(out, "contacts.json")
    if not data:
        return "_Not run yet: `physics-bench accuracy`._\n"
    if data.get("skipped"):
        return f"_Skipped: contacts are not available ({data['skipped']})._\n"
    lines = [f"Details in [contacts.md]({prefix}contacts.md).\n"]
    bounce = [r for r in data["bounce"] if r["error"] == r["error"] and r["error"] != float("inf")]
    if bounce:
        best = min(bounce, key=lambda r: r["error"])
        per = {}
        for integ in INTEGRATORS:
            mine = [r for r in bounce if r["integrator"] == integ and r["substeps"] == 1]
            if mine:
                per[integ] = min(mine, key=lambda r: r["dt"])
        lines.append(
            f"**Bouncing ball** (apex heights C_R^(2n) h₀): the smallest error is "
            f"{best['error']:.2g} h₀ ({LABELS[best['integrator']]}, dt = 1/{round(1 / best['dt'])} s"
            f"{', ×' + str(best['substeps']) + ' sub-steps' if best['substeps'] > 1 else ''}); at the "
            "finest dt: " + ", ".join(f"{LABELS[k]} {v['error']:.2g}" for k, v in per.items())
            + ". " + _bounce_reading(data["bounce"])
            + f"\n\n![bounce]({prefix}contacts_bounce.png)\n")
    toi = data["toi"]
    off = [r for r in toi if not r["ccd"]]
    on = [r for r in toi if r["ccd"] and r["substeps"] == 1]
    subs = [r for r in toi if r["ccd"] and r["substeps"] > 1]
    if on:
        lo, hi = on[0], on[-1]
        text = "**Time of impact** (10 cm ball at 50 m/s against a 4 cm wall, 1/60 s steps): "
        if off:
            text += (f"without ccd the ball goes through the wall in {off[0]['tunnelled']} of "
                     f"{off[0]['runs']} runs, ")
        text += (f"with ccd in {sum(r['tunnelled'] for r in on)} of {sum(r['runs'] for r in on)}. "
                 f"The impact-time error is {md.seconds(lo['max_time_error'])} at "
                 f"{lo['ccd_iterations']} halving(s) and {md.seconds(hi['max_time_error'])} at "
                 f"{hi['ccd_iterations']}, for a ccd stage cost of {md.seconds(lo['ccd_seconds_per_step'])}"
                 f" → {md.seconds(hi['ccd_seconds_per_step'])} per step")
        if subs:
            text += ("; sub-steps cut it to " + ", ".join(
                f"{md.seconds(r['max_time_error'])} (×{r['substeps']})" for r in subs))
        dt = 1.0 / 60.0
        if hi["max_time_error"] > 0.5 * dt:
            text += (". More halvings do not help past a few: the error stays near one step "
                     "because a body that hits is stopped at its time of impact and the rest of "
                     "that (sub)step is not simulated again, so the rebound starts up to one "
                     "(sub)step late; sub-steps shorten that lag, halvings do not")
        text += (". Penetration at the end of a step: " +
                 ", ".join(sorted({md.sci(r["max_penetration"]) for r in on})) + " m.")
        lines.append(text + f"\n\n![time of impact]({prefix}contacts_toi.png)\n")
    stack = data["stack"]
    if stack:
        good = next((r for r in stack if r["finite"] and r["max_drift"] <= 0.01), None)
        lines.append(
            f"**Stack** of {stack[0]['boxes']} boxes, {stack[0]['duration']:g} s at 1/60 s: drift "
            + ", ".join(f"{r['max_drift']:.2g} m at {r['iterations']}" for r in stack)
            + " iterations. "
            + (f"The fewest iterations that keep every box within 1 cm: {good['iterations']} "
               f"({good['cpu_per_sim_second']:.2g} s CPU per simulated second)."
               if good else "No iteration count of this grid kept every box within 1 cm.")
            + f"\n\n![stack]({prefix}contacts_stack.png)\n")
    return "\n".join(lines)


def _bounce_reading(rows):
    """Which integrator is most accurate at each dt, and who bounces higher than C_R allows."""
    from .contact_scenes import bounce_apexes_exact
    exact = bounce_apexes_exact()
    base = [r for r in rows if r["substeps"] == 1]
    winners = {}
    for dt in sorted({r["dt"] for r in base}, reverse=True):
        at = [r for r in base if r["dt"] == dt]
        winners[dt] = min(at, key=lambda r: r["error"])["integrator"]
    kinds = set(winners.values())
    text = (f"{_cap(LABELS[kinds.pop()])} is the most accurate at every dt of the grid"
            if len(kinds) == 1 else "Most accurate per dt: " + ", ".join(
                f"1/{round(1 / dt)} s {LABELS[w]}" for dt, w in winners.items()))
    coarse = max(r["dt"] for r in base)
    high = []
    for integ in INTEGRATORS:
        mine = sorted((r for r in base if r["integrator"] == integ), key=lambda r: -r["dt"])
        r = next((r for r in mine if r["dt"] < coarse), None)     # the second coarsest, 1/60 s
        if r and len(r["apexes"]) == len(exact) and all(a > e + 0.01 for a, e in
                                                          zip(r["apexes"][1:], exact[1:])):
            high.append((integ, r))
    if high:
        # the apexes of velocity Verlet if it is among them: explicit Euler is expected to gain
        integ, r = next(((i, r) for i, r in high if i == "velocity_verlet"), high[0])
        names = [LABELS[i] for i, _ in high]
        text += (". " + _cap(", ".join(names[:-1]) + " and " + names[-1] if len(names) > 1 else names[0])
                 + f" bounce higher than C_R allows at coarse steps ({LABELS[integ]} at dt = "
                 f"1/{round(1 / r['dt'])} s: "
                 + ", ".join(f"{a:.2f}" for a in r["apexes"]) + " m against "
                 + ", ".join(f"{e:.2f}" for e in exact)
                 + " m): each bounce keeps more than C_R² of the energy")
    return text + "."


def _cap(text):
    return text[:1].upper() + text[1:]


def _bold_fail(verdict):
    return "**fail**" if verdict == "fail" else verdict


# ---- stability --------------------------------------------------------------------
def _stability(out, prefix, level):
    data = read_json(out, "stability.json")
    if not data:
        return "_Not run yet: `physics-bench stability`._\n"
    lines = [f"Details in [stability.md]({prefix}stability.md); the same checks are "
             "`tests/test_stability.py` in `make test`.\n"]
    rows = [[f"stiff spring k = 10⁶ N/m, m = 1 kg, dt = 1/240 s, {LABELS[r['integrator']]}",
             f"{r['spring_substeps']} automatic spring sub-steps, max displacement "
             f"{r['max_offset_ratio']:.3g} × start",
             "pass" if r["bounded"] else ("exempt" if r["integrator"] == "explicit_euler" else "**fail**")]
            for r in data["stiff_spring"]]
    rows += [[f"10⁵ steps, e = 0.5 orbit, {LABELS[r['integrator']]}",
              f"max abs(ΔE/E) {r['max_rel_energy_error']:.2g}, last/first tenth "
              f"{r['last_tenth'] / max(r['first_tenth'], 1e-300):.2f}",
              _bold_fail(long_run_verdict(r))] for r in data["long_runs"]]
    for key, v in data["random"].items():
        kind, integ = key.split(":")
        if kind == "passive":
            verdict = passive_verdict(integ, v["non_finite"], v["max_energy_gain"])
            rows.append([f"{v['scenes']} random passive scenes, {LABELS[integ]}",
                         f"{v['non_finite']} non-finite, max energy gain {v['max_energy_gain']:.2g} "
                         "of the largest kinetic energy", _bold_fail(verdict)])
        else:
            verdict = isolated_verdict(v["non_finite"], v["max_momentum_drift"])
            rows.append([f"{v['scenes']} random isolated scenes, {LABELS[integ]}",
                         f"max momentum drift {v['max_momentum_drift']:.2g}", _bold_fail(verdict)])
    for r in data.get("hard_cases", []):
        rows.append([f"hard case `{r['name']}` ({r['bodies']} bodies)",
                     f"penetration {r['max_penetration']:.2g} of size, energy rise "
                     f"{r['energy_gain']:.2g}", "pass" if not r["failures"] else
                     "**fail: " + "; ".join(r["failures"]) + "**"])
    if not data["contacts"]["available"]:
        rows.append(["contact hard cases", "contacts not available", "skipped"])
    lines.append(md.table(["case", "measured", "result"], rows, align="lll"))
    lines.append(f"\n![energy over 10⁵ steps]({prefix}stability_long_run.png)\n")
    return "\n".join(lines)


# ---- scale --------------------------------------------------------------------------
def _scale(out, prefix, level):
    from .scale import by_size, pyramid_table, ratio, stage_table
    data = read_json(out, "scale.json")
    if not data:
        return "_Not run yet: `physics-bench scale`._\n"
    if data.get("skipped"):
        return f"_Skipped: contacts are not available ({data['skipped']})._\n"
    lines = [f"Details in [scale.md]({prefix}scale.md). Box pyramid, dt = 1/240 s, "
             f"{data['iterations']} solver iterations, every body awake, one process per run. "
             "The `… vs this engine` columns say how many times faster than this engine each "
             "peer is (MuJoCo with its default Newton solver and with CG), `this / fastest "
             "peer` this engine's steps/s over the fastest peer's.\n",
             f"![pyramid]({prefix}scale_pyramid.png)\n", pyramid_table(data["pyramid"]),
             "\n" + _behind(data, by_size, ratio) + "\n",
             "Where this engine's step time goes (share of the step per stage):\n",
             stage_table(data["pyramid"])]
    piles = data.get("piles") or {}
    if "skipped" in piles:
        lines.append(f"\nSphere piles: _skipped, {piles['skipped']}._\n")
    elif piles.get("rows"):
        from .scale import pile_tables
        lines += [f"\n**Sphere piles** (spheres dropped in columns that topple into a pile, the "
                  "first second; `this / …` is this engine's steps/s over the other's):\n",
                  pile_tables(piles), _pile_behind(piles["rows"])]
    return "\n".join(lines)


def _behind(data, by_size, ratio):
    sizes = by_size(data["pyramid"])
    parts = []
    for n, per in sorted(sizes.items()):
        ours = per.get("physics_core")
        cells = []
        for other in engines.PEERS:
            label, x = engines.LABELS[other], ratio(ours, per.get(other))
            if x is not None:
                cells.append(f"{label} {x:.3g}×" if x >= 1 else f"this engine {1 / x:.3g}× faster than {label}")
        if cells:
            parts.append(f"{n}: " + ", ".join(cells))
    ours = sorted((r for r in data["pyramid"] if r.get("engine") == "physics_core" and "error" not in r),
                  key=lambda r: r["bodies"])
    why = ""
    if ours:
        small, big = ours[0], ours[-1]
        prof = big.get("stage_seconds_per_step") or {}
        total = big["seconds"] / big["steps"]
        top = sorted(prof.items(), key=lambda kv: -kv[1])[:2]
        sprof = small.get("stage_seconds_per_step") or {}
        stotal = small["seconds"] / small["steps"]
        stop = sorted(sprof.items(), key=lambda kv: -kv[1])[:2]
        why = (f" Where the step time goes: with {small['bodies']} body a step costs "
               f"{md.seconds(stotal)} ("
               + " and ".join(f"{k} {100 * v / stotal:.0f} %" for k, v in stop)
               + f"); at {big['bodies']} bodies {md.seconds(total)} ("
               + " and ".join(f"{k} {100 * v / total:.0f} %" for k, v in top) + ").")
    return ("Against the others, per number of bodies (how many times faster than this "
            "engine each is, or this engine's lead): " + "; ".join(parts) + "." + why)


def _pile_behind(rows):
    from .scale import pile_ratios
    parts = []
    for n, ratios in pile_ratios(rows):
        cells = [f"{engines.LABELS[e]} {ratios[e]:.3g}×" if ratios[e] >= 1 else
                 f"this engine {1 / ratios[e]:.3g}× faster than {engines.LABELS[e]}"
                 for e in engines.PEERS if e in ratios]
        if cells:
            parts.append(f"{n}: " + ", ".join(cells))
    return ("\nPiles, times faster than this engine per number of spheres: " + "; ".join(parts)
            + ".\n") if parts else ""


# ---- effects --------------------------------------------------------------------------
def _effects(out, prefix, level):
    data = read_json(out, "effects.json")
    if not data:
        return "_Not run yet: `physics-bench effects`._\n"
    if data.get("skipped"):
        return f"_Skipped: {data['skipped']}._\n"
    from .effects_cost import tables
    return (f"Details in [effects.md]({prefix}effects.md).\n\n" + tables(data["rows"], level))


# ---- the node in real time --------------------------------------------------------

def _node(out, prefix, level):
    data = read_json(out, "node_realtime.json")
    if not data or not data.get("rows"):
        return "_Not run yet: `physics-bench node`._\n"
    rows = data["rows"]
    by_case = {}
    for r in rows:
        by_case.setdefault(r["case"], {})[bool(r["record"])] = r
    header = ["case", "real-time factor (no record / record)", "step CPU, ms (of dt)", "engine CPU, ms",
              "messages per step", "recording: node thread / with writer thread (of dt)"]
    table_rows = []
    for case, pair in by_case.items():
        plain, rec = pair.get(False), pair.get(True)
        any_row = plain or rec
        dt = any_row["dt_ms"]
        rtf = " / ".join("—" if r is None else f"{r['rtf']:.2f}" for r in (plain, rec))
        step = f"{plain['step_cpu_ms']:.3f} ({plain['step_cpu_ms'] / dt:.0%})" if plain else "—"
        engine = f"{plain['engine_cpu_ms']:.3f}" if plain else "—"
        recording = "—"
        if rec and rec.get("record_cpu_ms") is not None:
            writer = rec.get("writer_cpu_ms")
            recording = (f"{rec['record_cpu_ms'] / dt:.1%} / "
                         + ("—" if writer is None else f"{(rec['record_cpu_ms'] + writer) / dt:.1%}"))
        table_rows.append([case, rtf, step, engine, str(any_row.get("messages_per_step", "—")), recording])
    held = [c for c, pair in by_case.items() if all(r["rtf"] >= 0.98 for r in pair.values())]
    missed = [c for c in by_case if c not in held]
    lines = [f"Details and method in [node_realtime.md]({prefix}node_realtime.md): the node spun as "
             "`physics-node` runs it, a subscriber process on `~/poses` and one body's odometry, "
             f"{data['seconds']:g} s of wall time per row, {data['machine']}.\n",
             md.table(header, table_rows, align="lrrrrr"),
             f"Holds real time (factor ≥ 0.98 with and without recording): {'; '.join(held) or 'none'}."
             + (f" Falls behind: {'; '.join(missed)}." if missed else "") + "\n"]
    return "\n".join(lines)
