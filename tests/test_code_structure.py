"""The reading rules for physics_core: no function over 60 lines and none above
cyclomatic complexity 10 (radon's measure: 1 + branches, loops, boolean
operators, comprehensions), so each stage's kernels can be followed from the
stage list one short function at a time."""
import ast
import pathlib

from radon.complexity import cc_visit

CORE = pathlib.Path(__file__).resolve().parent.parent / "physics_core"
MAX_LINES = 60
MAX_COMPLEXITY = 10


def _sources():
    files = sorted(CORE.rglob("*.py"))
    assert len(files) > 30          # the walk found the package
    return [(f.relative_to(CORE.parent), f.read_text()) for f in files]


def _functions(tree):
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            yield node


def test_no_function_in_physics_core_is_over_60_lines():
    long = [f"{path}:{fn.lineno} {fn.name} ({fn.end_lineno - fn.lineno + 1} lines)"
            for path, text in _sources() for fn in _functions(ast.parse(text))
            if fn.end_lineno - fn.lineno + 1 > MAX_LINES]
    assert long == []


def _blocks(text):
    """Every function and method radon measures (a class's methods are inside it)."""
    for block in cc_visit(text):
        yield from getattr(block, "methods", [])
        if not hasattr(block, "methods"):
            yield block


def test_no_function_in_physics_core_is_above_complexity_10():
    complex_ = [f"{path}:{b.lineno} {b.fullname} (complexity {b.complexity})"
                for path, text in _sources() for b in _blocks(text)
                if b.complexity > MAX_COMPLEXITY]
    assert complex_ == []
