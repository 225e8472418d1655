"""`physics-bench scale`: this engine beside PyBullet and MuJoCo, 1 to 10,000 bodies.

- box pyramid (pyramid.py), measured here, each engine and size in a fresh
  process (measure.py): steps/s, body-steps/s, peak memory, and where this
  engine's step time goes (its stage profile);
- box piles (box_pile.py), 1 to 1,000 cubes, measured as the pyramid is;
- sphere piles, from benchmarks/pile_compare.py.

With `--repeat R` every measurement is made R times, the engines in turn
within each round, and each engine's fastest run kept: this machine has
slow phases that last whole processes, and the fastest of a few runs is
the figure least moved by them. Within one measurement, a run shorter
than measure.MIN_TIMED (a few bodies' first second takes about a
millisecond) is run again from a freshly built scene until its runs
reach that time (at most measure.MAX_WINDOWS), and the fastest is kept,
for every engine alike.

Writes `scale.md`, `scale.json`, `scale_pyramid.png` and `scale_box_piles.png`.
"""
import importlib
import importlib.util

from . import engines
from . import markdown as md
from . import plotting
from .contact_support import available
from .measure import BUDGET, MAX_WINDOWS, MIN_TIMED, measure
from .progress import Progress
from .results_io import machine, write_json, write_text

SIZES = {True: (1, 10, 100, 1000), False: (1, 10, 100, 1000, 10000)}
BOX_PILE_SIZES = (1, 10, 100, 1000)
# the box piles and the pyramid are timed over their first second, as the sphere
# piles are: a pile's fall, impacts and forming (its first 0.1 s is free fall); the
# pyramid's 2 mm fall, first touches and the wall taking its weight (its first 20
# steps, once its timed window at 1,000 boxes, are only the fall and the touches)
FIRST_SECOND_STEPS = {True: 60, False: 240}


def run(quick=False, out=None, repeat=1):
    """`repeat` rounds of every measurement, the fastest run of each engine
    kept (module docstring)."""
    ok, why = available()
    repeat = max(1, int(repeat))
    data = {"quick": quick, "machine": machine(), "dt": engines.DT,
            "iterations": engines.ITERATIONS, "repeat": repeat}
    if not ok:
        Progress("scale", 1).note(f"skipped: contacts are not available ({why})")
        data["skipped"] = why
    else:
        data["pyramid"] = pyramid_study(quick, repeat)
        data["box_piles"] = box_pile_study(quick, repeat)
        data["piles"] = pile_study(quick, repeat)
    if out:
        write_json(out, "scale.json", data)
        write_text(out, "scale.md", report(data))
        if data.get("pyramid"):
            plot_scale(data["pyramid"], "Box pyramid", f"{out}/scale_pyramid.png")
        if data.get("box_piles"):
            plot_scale(data["box_piles"], "Box piles", f"{out}/scale_box_piles.png")
    return data


def installed(engine):
    return importlib.util.find_spec(engines.module_of(engine)) is not None


def pyramid_study(quick, repeat=1):
    return fresh_process_study("pyramid", "benchmarks.pyramid", SIZES[quick],
                               lambda n: FIRST_SECOND_STEPS[quick], repeat)


def box_pile_study(quick, repeat=1):
    return fresh_process_study("box pile", "benchmarks.box_pile", BOX_PILE_SIZES,
                               lambda n: FIRST_SECOND_STEPS[quick], repeat)


def fresh_process_study(label, module, sizes, steps, repeat=1):
    """Every engine at every size, each in a fresh process (measure.py), on
    the scene `module`.boxes(n) makes, for steps(n) steps; `repeat` rounds
    of all the engines in turn at each size, the fastest run of each kept
    (with every round's steps/s under "rounds"). An engine that ran out of
    its budget (measure.BUDGET) is not run again at that size: each of its
    runs would take the whole budget and report the same early steps."""
    prog = Progress("scale", len(sizes) * len(engines.ENGINES) * repeat)
    rows = []
    for n in sizes:
        kept = {}
        for _ in range(repeat):
            for engine in engines.ENGINES:
                if _ran_short(kept.get(engine)):
                    prog.step(f"{label} {n} boxes, {engine}: not repeated (out of budget)")
                    continue
                r = _measure_one(label, module, n, engine, steps(n), prog)
                _keep_fastest(kept, engine, r)
        rows += [kept[e] for e in engines.ENGINES]
    return rows


def _measure_one(label, module, n, engine, steps, prog):
    if not installed(engine):
        prog.step(f"{label} {n} boxes, {engine}: not installed "
                  "(`make compare-extras` installs PyBullet and MuJoCo)")
        return {"engine": engine, "bodies": n, "error": "not installed"}
    r = measure(module, "boxes", n, engine, steps)
    r.setdefault("bodies", n)
    prog.step(f"{label} {n} boxes, {engine}: "
              + (f"{r['steps_per_second']:.3g} steps/s, peak {r['peak_rss_mb']:.0f} MB"
                 if "error" not in r else f"failed: {r['error']}"))
    return r


def _ran_short(r):
    return bool(r) and "error" not in r and r.get("steps", 0) < r.get("steps_asked", 0)


def _keep_fastest(kept, engine, r):
    """kept[engine]: the fastest run so far, every round's steps/s (None: failed) in its "rounds"."""
    rate = r.get("steps_per_second") if "error" not in r else None
    best = kept.get(engine)
    rounds = best["rounds"] if best else []
    if best is None or (rate is not None and rate > (best.get("steps_per_second") or 0.0)):
        best = r
    kept[engine] = dict(best, rounds=rounds + [rate])


def round_ratios(per):
    """This engine's steps/s over the faster peer's, round by round (rows of one size)."""
    ours = (per.get("physics_core") or {}).get("rounds") or []
    out = []
    for k, mine in enumerate(ours):
        peers = [r["rounds"][k] for e, r in per.items() if e != "physics_core"
                 and k < len(r.get("rounds") or []) and r["rounds"][k]]
        if mine and peers:
            out.append(mine / max(peers))
    return out


PILE_SIZES = {True: (1, 10, 100, 1000), False: (1, 10, 100, 1000, 10000)}


def pile_study(quick, repeat=1):
    """The sphere-pile comparison of benchmarks/pile_compare.py: its rows and stage profiles
    (each engine's fastest of `repeat` runs)."""
    try:
        pile_compare = importlib.import_module("benchmarks.pile_compare")
    except ImportError as e:
        Progress("scale", 1).note(f"sphere piles skipped: benchmarks/pile_compare.py not available ({e})")
        return {"skipped": f"benchmarks/pile_compare.py not available ({e})"}
    note = Progress("scale piles", 1).note
    rows = pile_compare.run(sizes=PILE_SIZES[quick], quick=quick, log=lambda m: note(m.strip()),
                            repeat=repeat)
    profiles = {str(k): v for k, v in getattr(pile_compare.run, "profiles", {}).items()}
    about = next((para for para in (pile_compare.__doc__ or "").split("\n\n")
                  if "scene" in para), "")
    return {"rows": rows, "profiles": profiles, "about": about}


def pile_ratios(rows):
    """[(spheres, {engine: how many times faster than this engine})] from pile_compare's rows."""
    def rate(row, engine):
        try:
            return float(str(row.get(f"{engine} steps/s", "")).split("*")[0].split()[0])
        except (ValueError, IndexError):
            return None
    out = []
    for r in rows:
        ours = rate(r, "physics_core")
        out.append((r.get("spheres"), {e: rate(r, e) / ours for e in engines.PEERS
                                       if ours and rate(r, e)}))
    return out


def pile_tables(piles):
    """pile_compare's own Markdown for its rows and profiles."""
    from . import pile_compare
    out = [pile_compare.markdown(piles["rows"]) + "\n"]
    if piles.get("profiles"):
        out += ["\nWhere this engine's step time goes (sphere piles):\n\n",
                pile_compare.profile_markdown(piles["profiles"]) + "\n"]
    return "".join(out)


def by_size(rows):
    out = {}
    for r in rows:
        out.setdefault(r["bodies"], {})[r["engine"]] = r
    return out


def ratio(ours, other):
    """How many times faster the other engine is (> 1: this engine is behind)."""
    if not ours or not other or "error" in ours or "error" in other:
        return None
    return other["steps_per_second"] / ours["steps_per_second"]


def fastest_peer_ratio(per):
    """This engine's steps/s over the fastest peer's at one size (None: no peer ran)."""
    ours = per.get("physics_core")
    peers = [r["steps_per_second"] for e, r in per.items()
             if e != "physics_core" and r and "error" not in r]
    if not ours or "error" in ours or not peers:
        return None
    return ours["steps_per_second"] / max(peers)


def _ratio_text(x):
    if x is None:
        return "—"
    return f"{x:.3g}× faster" if x >= 1 else f"{1 / x:.3g}× slower"


def pyramid_table(rows):
    head = ["boxes"]
    for e in engines.ENGINES:
        head += [f"{e} steps/s", f"{e} body-steps/s", f"{e} peak MB"]
    head += [f"{engines.LABELS[e]} vs this engine" for e in engines.PEERS]
    head.append("this / fastest peer")
    rounds = any(len(r.get("rounds") or []) > 1 for r in rows)
    if rounds:
        head.append("this / faster peer, each round")
    out = []
    for n, per in sorted(by_size(rows).items()):
        cells = [n]
        for e in engines.ENGINES:
            r = per.get(e)
            if not r or "error" in r:
                cells += ["not installed" if r and r["error"] == "not installed" else "failed",
                          "—", "—"]
            else:
                cells += [md.num(r["steps_per_second"])
                          + (f"* ({r['steps']} steps)" if _ran_short(r) else ""),
                          md.num(r["body_steps_per_second"]), f"{r['peak_rss_mb']:.0f}"]
        ours = per.get("physics_core")
        cells += [_ratio_text(ratio(ours, per.get(e))) for e in engines.PEERS]
        lead = fastest_peer_ratio(per)
        cells.append("—" if lead is None else f"{lead:.2f}")
        if rounds:
            cells.append(", ".join(f"{x:.2f}" for x in round_ratios(per)) or "—")
        out.append(cells)
    return md.table(head, out, align="r" * len(head))


def left_table(rows):
    """Per size and engine: sunk mm / moved mm after its run (measure.left_by)."""
    head = ["boxes"] + [f"{engines.LABELS[e]} sunk / moved, mm" for e in engines.ENGINES]
    out = []
    for n, per in sorted(by_size(rows).items()):
        cells = [n]
        for e in engines.ENGINES:
            r = per.get(e)
            ok = r and "error" not in r and "sink_mm" in r
            cells.append(f"{r['sink_mm']:.1f} / {r['moved_mm']:.1f}" if ok else "—")
        out.append(cells)
    return md.table(head, out, align="r" * len(head))


def stage_table(rows):
    """Where this engine's step time goes, per size: the stage profile."""
    ours = [r for r in rows if r.get("engine") == "physics_core" and r.get("stage_seconds_per_step")]
    if not ours:
        return ""
    stages = []
    for r in ours:
        for k in r["stage_seconds_per_step"]:
            if k not in stages:
                stages.append(k)
    head = ["boxes", "step"] + stages
    out = []
    for r in ours:
        prof = r["stage_seconds_per_step"]
        total = r["seconds"] / r["steps"]
        out.append([r["bodies"], md.seconds(total)]
                   + [f"{100 * prof.get(k, 0.0) / total:.0f}%" for k in stages])
    return md.table(head, out, align="r" * len(head))


def report(data):
    parts = ["# Scale: this engine beside PyBullet and MuJoCo\n",
             f"Run: `physics-bench scale{' --quick' if data['quick'] else ''}`, {data['machine']}. "
             f"Same step for every engine: dt = 1/{round(1 / data['dt'])} s, "
             f"{data['iterations']} solver iterations, sleeping off (every body awake: "
             "the worst case, and one all three engines can be put in), one process per "
             "engine and size. Peak MB: the process's peak resident memory, the engine's "
             "own import included." + _repeat_text(data.get("repeat", 1)) + "\n"]
    if data.get("skipped"):
        parts.append(f"_Skipped: contacts are not available ({data['skipped']})._\n")
        return "\n".join(parts)
    parts += ["## Box pyramid\n",
              "One vertical wall of 20 cm cubes, each row half a cube in from the one below, "
              "started 2 mm apart so that it settles under gravity. Timed over the first "
              f"{FIRST_SECOND_STEPS[data['quick']]} steps (the fall, the first touches and the "
              "wall taking its weight), in wall time of a fresh process per engine and size; "
              f"an engine still short of its steps after {BUDGET:.0f} s of stepping "
              "is reported over the steps it did (an early part, which costs less: marked *).\n",
              "![pyramid](scale_pyramid.png)\n", pyramid_table(data["pyramid"]),
              "\nWhat each engine's run left (sunk: the deepest centre below its resting "
              "height on the ground; moved: the largest sideways move of a centre from where "
              "it started, which in a pyramid is the wall spreading as it gives way):\n",
              left_table(data["pyramid"]),
              "\n### Where this engine's step time goes (box pyramid)\n",
              stage_table(data["pyramid"])]
    if data.get("box_piles"):
        about = (_box_pile_doc().split("\n\n", 1) + [""])[1]
        parts += ["\n## Box piles (benchmarks/box_pile.py)\n",
                  " ".join(about.split()) + f" Timed over the first {FIRST_SECOND_STEPS[data['quick']]} "
                  "steps (the fall, the impacts and the pile forming), in wall time of a fresh "
                  "process per engine and size, as the pyramid is.\n",
                  "![box piles](scale_box_piles.png)\n", pyramid_table(data["box_piles"]),
                  "\nWhat each engine's run left (as for the pyramid; a pile's columns may "
                  "lean and slide, so its sideways moves are no fault):\n",
                  left_table(data["box_piles"]),
                  "\n### Where this engine's step time goes (box piles)\n",
                  stage_table(data["box_piles"])]
    piles = data.get("piles") or {}
    parts.append("\n## Sphere piles (benchmarks/pile_compare.py)\n")
    if "skipped" in piles:
        parts.append(f"_Skipped: {piles['skipped']}._\n")
    else:
        parts.append(" ".join(piles.get("about", "").split()) + " The `this / …` columns are "
                     "this engine's steps/s over the other's (below 1: this engine is slower).\n")
        parts.append(pile_tables(piles))
        parts.append("\nHow many times faster than this engine:\n")
        parts.append(md.table(["spheres"] + [engines.LABELS[e] for e in engines.PEERS],
                              [[n] + [_ratio_text(x.get(e)) for e in engines.PEERS]
                               for n, x in pile_ratios(piles["rows"])],
                              align="r" * (1 + len(engines.PEERS))))
    return "\n".join(parts)


def _repeat_text(repeat):
    if repeat <= 1:
        return ""
    return (f" Every measurement was made {repeat} times (`--repeat {repeat}`) and each "
            "engine's fastest run is the one reported, so a slow phase of the machine during "
            "one run does not count against one engine alone. For the pyramid and the box "
            "piles the engines ran one after the other in each round, and the last column "
            "gives this engine's steps/s over the faster peer's round by round: the spread "
            "that noise leaves. The sphere piles run the engines in turn in each round too, in one process. "
            f"Within one measurement, a run shorter than {MIN_TIMED:g} s (a few bodies' first "
            "second takes about a millisecond) is made again from a freshly built scene until "
            f"its runs reach {MIN_TIMED:g} s in all (at most {MAX_WINDOWS} of them), the fastest "
            "kept, for every engine alike.")


def _box_pile_doc():
    from . import box_pile
    return box_pile.__doc__ or ""


def generic_table(rows):
    """A table of rows produced elsewhere (dicts with the same keys)."""
    if not rows:
        return "_No rows._\n"
    head = list(rows[0].keys())
    fmt = lambda v: md.num(v) if isinstance(v, float) else str(v)
    return md.table(head, [[fmt(r.get(k, "")) for k in head] for r in rows])


def plot_scale(rows, title, path):
    fig, (ax_s, ax_b) = plotting.figure(ncols=2)
    for e in engines.ENGINES:
        mine = sorted((r for r in rows if r.get("engine") == e and "error" not in r),
                      key=lambda r: r["bodies"])
        if not mine:
            continue
        ax_s.plot([r["bodies"] for r in mine], [r["steps_per_second"] for r in mine],
                  marker="o", color=plotting.COLORS[e], label=e)
        ax_b.plot([r["bodies"] for r in mine], [r["body_steps_per_second"] for r in mine],
                  marker="o", color=plotting.COLORS[e], label=e)
    ax_s.set_ylabel("steps per second")
    ax_b.set_ylabel("body-steps per second")
    for ax in (ax_s, ax_b):
        ax.set_xlabel("bodies")
        ax.legend(fontsize=8)
    ax_s.set_title(f"{title}: steps/s")
    ax_b.set_title(f"{title}: body-steps/s")
    plotting.save(fig, path)
