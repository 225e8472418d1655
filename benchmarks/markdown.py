"""Markdown tables and number formats shared by every results file."""


def table(header, rows, align=None):
    """A GitHub Markdown table; `align` is a string of 'l'/'r' per column (default: text left,
    numbers right)."""
    rows = [[str(c) for c in r] for r in rows]
    if align is None:
        align = "".join("r" if rows and _numeric(rows[0][i]) else "l" for i in range(len(header)))
    rule = ["---:" if a == "r" else "---" for a in align]
    lines = ["| " + " | ".join(header) + " |", "| " + " | ".join(rule) + " |"]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines) + "\n"


def _numeric(text):
    t = text.replace("×", "").replace("%", "").replace("−", "-").strip()
    try:
        float(t.split()[0])
        return True
    except (ValueError, IndexError):
        return False


def sci(x, digits=2):
    """1.23e-04 style, '—' for missing."""
    if x is None or x != x:
        return "—"
    return f"{x:.{digits}e}"


def num(x, digits=3):
    """Plain number with `digits` significant figures, '—' for missing."""
    if x is None or x != x:
        return "—"
    return f"{x:.{digits}g}"


def seconds(x):
    """A duration in the unit that reads best (ns … s)."""
    if x is None or x != x:
        return "—"
    for unit, scale in (("s", 1.0), ("ms", 1e-3), ("µs", 1e-6), ("ns", 1e-9)):
        if abs(x) >= scale:
            return f"{x / scale:.3g} {unit}"
    return "< 1 ns"
