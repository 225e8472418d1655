"""`physics-bench effects`: the per-effect cost table of benchmarks/core_speed.py
(`run(quick) -> rows`), written as `effects.md` and `effects.json`.

The table shows what each declared effect costs per step, and that an
effect a scene does not declare costs nothing (it is not in the pipeline).
"""
import importlib
import re

from .progress import Progress
from .results_io import machine, write_json, write_text
from .scale import generic_table


def run(quick=False, out=None):
    try:
        core_speed = importlib.import_module("benchmarks.core_speed")
    except ImportError as e:
        why = f"benchmarks/core_speed.py not available ({e})"
        Progress("effects", 1).note(f"skipped: {why}")
        data = {"quick": quick, "skipped": why}
        text = f"# Cost of each effect\n\n_Skipped: {why}._\n"
    else:
        rows = core_speed.run(quick)
        data = {"quick": quick, "machine": machine(), "rows": rows}
        text = report(data, getattr(core_speed, "__doc__", "") or "", tables(rows, level=2))
    if out:
        write_json(out, "effects.json", data)
        write_text(out, "effects.md", text)
    return data


def tables(rows, level):
    """core_speed's own Markdown, its headings moved to `level`; a plain table otherwise."""
    try:
        from .core_speed import markdown
    except ImportError:
        return generic_table(rows)
    return re.sub(r"^#+ ", "#" * level + " ", markdown(rows), flags=re.M)


def report(data, doc, body):
    intro = doc.strip().split("\n\n")[0] if doc else ""
    return "\n".join([
        "# Cost of each effect\n",
        f"Run: `physics-bench effects{' --quick' if data['quick'] else ''}`, {data['machine']}.\n",
        (intro + "\n") if intro else "",
        body,
    ])
