"""`physics-sweep --resimulate 'recordings/*.mcap'`: re-run every recording of
a corpus (as `physics-replay --resimulate` does for one) and report which
diverge: the first step and body, bit for bit.

A report is a plain dict (it travels back from Ray workers): path, status
('match', 'diverge' or 'error'), step and body of the first difference (None
on a match), poses compared, and the one-recording report text.
"""
import glob
import os

from .design import SweepError

STATUS = {0: "match", 1: "diverge", 2: "error"}


def expand(patterns):
    """The recordings named by glob patterns (or plain paths), sorted, each once."""
    paths = []
    for pattern in patterns:
        found = sorted(glob.glob(os.path.expanduser(pattern), recursive=True))
        if not found and not glob.has_magic(pattern):
            found = [pattern]          # a plain path that is missing: reported as an error
        paths += [p for p in found if p not in paths]
    if not paths:
        raise SweepError(f"--resimulate {' '.join(patterns)}: no recording matches")
    return paths


def check_recording(path):
    from physics_node.resimulate import resimulate
    result = resimulate(path)
    d = result.divergence
    return {"path": str(path), "status": STATUS[result.status], "step": None if d is None else int(d.step),
            "body": None if d is None else d.body, "compared": int(result.compared),
            "report": result.report()}


def error_report(path, text):
    return {"path": str(path), "status": "error", "step": None, "body": None, "compared": 0,
            "report": f"error: {path}: {text}"}


def resimulate_serial(paths, sink):
    for p in paths:
        sink(check_recording(p))


def summary_line(reports):
    counts = {s: sum(r["status"] == s for r in reports) for s in STATUS.values()}
    return (f"{len(reports)} recordings: {counts['match']} match, {counts['diverge']} diverge, "
            f"{counts['error']} error")


def exit_status(reports):
    """0 all match, 1 some diverge (and none failed to read), 2 any error."""
    if any(r["status"] == "error" for r in reports):
        return 2
    return 1 if any(r["status"] == "diverge" for r in reports) else 0
