"""Mutation check: does the test suite catch plausible physics bugs?

    physics-bench mutations [--only WORD ...] [--list] [--timeout S] [--out DIR]
    python -m benchmarks.mutations ...

Copies the repository (the files git tracks or would track) into a scratch
folder, runs the tests the mutations name there once unchanged (they must
pass), then for each mutation of benchmarks/mutation_list.py: changes that
one line in the copy, runs its test files (`pytest -x`, so it stops at the
first failure), and puts the line back. A mutant is *caught* when pytest
reports a failing test (exit code 1), *survived* when its tests pass; a
collection error, a timeout or a line that is no longer in the file is
reported as such and is not counted as caught.

Numba's cache: a cached kernel does not notice that a kernel it calls from
another file changed. Each mutant runs on a fresh copy of this checkout's
own compiled kernels (`make install` / `python -m physics_core.warm_up`
made them; the copy reads them through benchmarks/mutant_pytest.py) with
every entry of the mutated file, and of every file that imports it directly
or through others (the import graph, `dependents`), removed: everything
that can reach the changed line is compiled anew, nothing else is. A stale
entry could only hide a mutation (the unchanged code would run), never fake
a catch; `--recheck` runs a survivor again on an empty cache. `--cold` gives
every mutant an empty cache (a full compile each: several minutes on two
shared cores). Mutants run one after the other under `nice`.

Writes DIR/mutations.md and DIR/mutations.json (default benchmarks/results).
Not part of `make test` or `physics-bench all`: it takes about an hour.
"""
import argparse
import ast
import hashlib
import itertools
import json
import os
import shutil
import subprocess
import sys
import tempfile
from dataclasses import asdict
from time import perf_counter

from .mutation_list import MUTATIONS
from .repo import REPO
from .results_io import DEFAULT_OUT, ensure

CAUGHT, SURVIVED = "caught", "survived"


def tracked_files(repo=REPO):
    out = subprocess.run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
                         cwd=repo, check=True, capture_output=True).stdout
    return [p for p in out.decode().split("\0") if p and os.path.isfile(os.path.join(repo, p))]


def copy_repo(dest, repo=REPO):
    for rel in tracked_files(repo):
        target = os.path.join(dest, rel)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        shutil.copy2(os.path.join(repo, rel), target)
    return dest


def _module_files(root):
    for folder, dirs, files in os.walk(root):
        dirs[:] = [d for d in dirs if d not in ("__pycache__", ".git", ".venv", "build")]
        for name in files:
            if name.endswith(".py"):
                yield os.path.join(folder, name)


def _resolve(bases, name):
    """Files `name` (dotted, may be empty: the base package) can be, under any base."""
    out = []
    for base in bases:
        stem = os.path.join(base, *name.split(".")) if name else base
        for cand in (stem + ".py", os.path.join(stem, "__init__.py")):
            if os.path.isfile(cand):
                out.append(os.path.normpath(cand))
    return out


def _candidates(root, path, node):
    """Files an import statement binds names from: the module itself, or for
    `from pkg import x` the submodule pkg/x.py when there is one, else pkg's
    __init__ (a name it defines or re-exports). Absolute names are looked up
    from the repository root and from tests/ (pytest puts it on the path)."""
    tops = [root, os.path.join(root, "tests")]
    if isinstance(node, ast.Import):
        return [f for a in node.names for f in _resolve(tops, a.name)]
    if node.level:
        base = os.path.dirname(path)
        for _ in range(node.level - 1):
            base = os.path.dirname(base)
        bases = [base]
    else:
        bases = tops
    head = node.module or ""
    out = []
    for a in node.names:
        sub = _resolve(bases, f"{head}.{a.name}" if head else a.name)
        out += sub or _resolve(bases, head)
    return out


def import_graph(root):
    """{file: set of files it imports} over every .py file under root."""
    graph = {}
    for path in _module_files(root):
        with open(path, encoding="utf-8") as f:
            try:
                tree = ast.parse(f.read(), path)
            except SyntaxError:
                continue
        deps = set()
        for node in ast.walk(tree):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                deps.update(_candidates(root, path, node))
        graph[os.path.normpath(path)] = deps
    return graph


def dependents(root, path, graph=None):
    """`path` and every file that imports it, directly or through others."""
    graph = import_graph(root) if graph is None else graph
    out, todo = {os.path.normpath(path)}, [os.path.normpath(path)]
    while todo:
        target = todo.pop()
        for module, deps in graph.items():
            if target in deps and module not in out:
                out.add(module)
                todo.append(module)
    return out


def _cache_folder(py_file):
    """The folder under NUMBA_CACHE_DIR where Numba keeps py_file's kernels
    (numba.core.caching._CacheLocator.get_suitable_cache_subpath)."""
    subpath = os.path.dirname(os.path.abspath(py_file))
    return "_".join([os.path.split(subpath)[-1], hashlib.sha1(subpath.encode()).hexdigest()])


def warm_cache(repo=REPO):
    """This checkout's compiled kernels (physics_core/kernel_cache.py's folder
    for the current source), compiling them first if there are none."""
    sys.path.insert(0, repo)
    try:
        from physics_core.kernel_cache import PREFIX, source_hash
    finally:
        sys.path.pop(0)
    folder = os.path.join(repo, "physics_core", "__pycache__", PREFIX + source_hash(os.path.join(repo, "physics_core")))
    if not os.path.isdir(folder):
        sys.stderr.write("[mutations] compiling this checkout's kernels first (physics_core.warm_up)\n")
        env = dict(os.environ, PYTHONPATH=repo)
        env.pop("NUMBA_CACHE_DIR", None)
        subprocess.run(["nice", "-n", "10", sys.executable, "-m", "physics_core.warm_up"], cwd=repo, env=env,
                       check=True)
    return folder


def prune_cache(cache, files, copy=None, repo=REPO):
    """Remove the cached kernels of `files` (paths in `copy`, filed under their
    originals in `repo`) from a Numba cache folder; returns how many."""
    removed = 0
    for py_file in files:
        if copy is not None:
            py_file = os.path.join(repo, os.path.relpath(py_file, copy))
        folder = os.path.join(cache, _cache_folder(py_file))
        prefix = os.path.splitext(os.path.basename(py_file))[0] + "."
        if not os.path.isdir(folder):
            continue
        for name in os.listdir(folder):
            if name.startswith(prefix) and name.endswith((".nbi", ".nbc")):
                os.remove(os.path.join(folder, name))
                removed += 1
    return removed


def locate(text, mutation):
    """Index of the mutation's `old` text in `text` (its `occurrence`-th), or
    a reason it cannot be applied."""
    count = text.count(mutation.old)
    if count == 0:
        return None, "line not found (the source changed: update the mutation)"
    if mutation.occurrence == 0 and count > 1:
        return None, f"line occurs {count} times: give `occurrence`"
    if mutation.occurrence > count:
        return None, f"only {count} occurrences"
    at = -1
    for _ in range(max(mutation.occurrence, 1)):
        at = text.index(mutation.old, at + 1)
    return at, None


def check(mutation, repo=REPO):
    """None if the mutation applies to `repo` as written, else the reason."""
    if mutation.old == mutation.new:
        return "old and new are the same"
    changed = [a != b for a, b in zip(mutation.old.split("\n"), mutation.new.split("\n"))]
    if len(mutation.old.split("\n")) != len(mutation.new.split("\n")) or sum(changed) != 1:
        return "a mutation changes exactly one line"
    path = os.path.join(repo, mutation.path)
    if not os.path.isfile(path):
        return f"{mutation.path} does not exist"
    with open(path, encoding="utf-8") as f:
        return locate(f.read(), mutation)[1]


def pytest_run(copy, tests, timeout, label, cache=None):
    """(status, seconds, last lines of output) of `pytest -x tests` in the copy
    with the Numba cache folder `cache`, read as this checkout's (None: a new,
    empty one); the folder is removed afterwards."""
    aliased = cache is not None
    cache = cache or tempfile.mkdtemp(prefix="numba-", dir=os.path.dirname(copy))
    env = dict(os.environ, PYTHONPATH=copy, NUMBA_CACHE_DIR=cache, PYTHONDONTWRITEBYTECODE="1")
    runner = ["-m", "benchmarks.mutant_pytest", REPO, copy] if aliased else ["-m", "pytest"]
    cmd = ["nice", "-n", "10", sys.executable, *runner, "-x", "-q", "-p", "no:cacheprovider", *tests]
    t0 = perf_counter()
    try:
        proc = subprocess.run(cmd, cwd=copy, env=env, capture_output=True, text=True, timeout=timeout)
        code, output = proc.returncode, proc.stdout + proc.stderr
    except subprocess.TimeoutExpired as e:
        out = e.stdout or ""  # bytes even with text=True
        code, output = None, out.decode(errors="replace") if isinstance(out, bytes) else out
    finally:
        shutil.rmtree(cache, ignore_errors=True)
    seconds = perf_counter() - t0
    status = {0: SURVIVED, 1: CAUGHT, None: "timeout"}.get(code, f"error (pytest exit {code})")
    tail = "\n".join(output.strip().splitlines()[-6:])
    sys.stderr.write(f"[mutations] {label}: {status} in {seconds:.0f} s\n")
    return status, seconds, tail


def run_mutant(copy, mutation, timeout, warm=None, recheck=False):
    """Apply, test, restore. warm: the unchanged run's cache folder, reused
    without the kernels the mutation can reach (None: an empty cache)."""
    path = os.path.join(copy, mutation.path)
    with open(path, encoding="utf-8") as f:
        original = f.read()
    at, reason = locate(original, mutation)
    if reason:
        return {"status": f"not applied: {reason}", "seconds": 0.0, "tail": ""}
    mutated = original[:at] + mutation.new + original[at + len(mutation.old):]
    try:
        with open(path, "w", encoding="utf-8") as f:
            f.write(mutated)
        cache = None
        if warm is not None:
            cache = _cache_copy(warm, copy)
            prune_cache(cache, dependents(copy, path), copy)
        status, seconds, tail = pytest_run(copy, mutation.tests, timeout, mutation.name, cache)
        if status == SURVIVED and warm is not None and recheck:  # make sure no stale kernel hid it
            status, more, tail = pytest_run(copy, mutation.tests, timeout, mutation.name + " (cold)")
            seconds += more
    finally:
        with open(path, "w", encoding="utf-8") as f:
            f.write(original)
    return {"status": status, "seconds": seconds, "tail": tail}


def _cache_copy(warm, copy):
    cache = tempfile.mkdtemp(prefix="numba-", dir=os.path.dirname(copy))
    shutil.copytree(warm, cache, dirs_exist_ok=True)
    return cache


def select(words):
    """The mutations to run, taking the stages in turn (one of each stage, then
    the next of each...), so a run stopped early has still covered every stage."""
    chosen = list(MUTATIONS)
    if words:
        words = [w.lower() for w in words]
        chosen = [m for m in chosen if any(w in m.name.lower() or w == m.stage for w in words)]
    by_stage = {}
    for m in chosen:
        by_stage.setdefault(m.stage, []).append(m)
    return [m for group in itertools.zip_longest(*by_stage.values()) for m in group if m is not None]


def report(rows, baseline, out):
    caught = sum(r["status"] == CAUGHT for r in rows)
    lines = ["# Mutation check", "",
             f"{caught} of {len(rows)} mutations caught ({100.0 * caught / max(len(rows), 1):.0f} %); "
             f"unchanged source: {baseline['status'] if baseline else 'not run'}.", "",
             "| stage | mutation | file | tests run | result | s |", "|---|---|---|---|---|---|"]
    for r in rows:
        tests = ", ".join(os.path.basename(t) for t in r["tests"])
        name = r["name"].replace("|", "\\|")  # a table cell
        lines.append(f"| {r['stage']} | {name} | {os.path.basename(r['path'])} | {tests} | "
                     f"{r['status']} | {r['seconds']:.0f} |")
    lines += ["", "Rerun: `physics-bench mutations` (all, about an hour on two cores) or "
              "`physics-bench mutations --only WORD` (mutations whose name has WORD, or a stage)."]
    with open(os.path.join(out, "mutations.md"), "w", encoding="utf-8") as f:
        f.write("\n".join(lines) + "\n")
    with open(os.path.join(out, "mutations.json"), "w", encoding="utf-8") as f:
        json.dump({"baseline": baseline, "mutations": rows}, f, indent=1)
    return caught


def _baseline(copy, chosen, timeout, warm):
    """Every test file the mutations name, on the unchanged copy: they must pass."""
    tests = sorted({t for m in chosen for t in m.tests})
    status, seconds, tail = pytest_run(copy, tests, timeout * 3, "unchanged source",
                                       None if warm is None else _cache_copy(warm, copy))
    return {"status": "pass" if status == SURVIVED else status, "seconds": seconds, "tail": tail}


def run(only=None, out=DEFAULT_OUT, timeout=900.0, baseline=True, cold=False, recheck=False):
    chosen = select(only)
    bad = [(m.name, check(m)) for m in chosen if check(m)]
    for name, reason in bad:
        sys.stderr.write(f"[mutations] cannot apply {name!r}: {reason}\n")
    scratch = tempfile.mkdtemp(prefix="physics-mutations-")
    try:
        copy = copy_repo(os.path.join(scratch, "repo"))
        # a snapshot: the checkout's own folder goes when its source changes
        base, warm = None, (None if cold else _cache_copy(warm_cache(), copy))
        if baseline:
            base = _baseline(copy, chosen, timeout, warm)
            if base["status"] != "pass":
                sys.stderr.write(f"[mutations] the unchanged tests do not pass:\n{base['tail']}\n")
                report([], base, ensure(out))
                return 2
        rows = []
        for m in chosen:
            rows.append({**asdict(m), **run_mutant(copy, m, timeout, warm, recheck)})
            report(rows, base, ensure(out))          # progress on disk after every mutant
        caught = report(rows, base, ensure(out))
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    sys.stderr.write(f"[mutations] {caught} of {len(rows)} caught; see {os.path.join(out, 'mutations.md')}\n")
    return 0 if caught == len(rows) else 1


def parser():
    p = argparse.ArgumentParser(prog="physics-bench mutations", description=__doc__.split("\n\n")[0])
    p.add_argument("--only", nargs="+", metavar="WORD", help="mutations whose name contains WORD, or a stage")
    p.add_argument("--list", action="store_true", help="list the mutations and check they apply; run nothing")
    p.add_argument("--timeout", type=float, default=900.0, help="seconds per mutant (default %(default)s)")
    p.add_argument("--no-baseline", action="store_true", help="skip the run on the unchanged source")
    p.add_argument("--cold", action="store_true", help="an empty Numba cache for every mutant")
    p.add_argument("--recheck", action="store_true", help="run a survivor again on an empty Numba cache")
    p.add_argument("--out", default=DEFAULT_OUT, help="output folder (default: %(default)s)")
    return p


def main(argv=None):
    args = parser().parse_args(argv)
    if args.list:
        chosen = select(args.only)
        for m in chosen:
            problem = check(m)
            print(f"{m.stage:12s} {m.name}" + (f"  [CANNOT APPLY: {problem}]" if problem else ""))
        print(f"{len(chosen)} mutations over {len({m.stage for m in chosen})} stages")
        return 1 if any(check(m) for m in chosen) else 0
    return run(args.only, os.path.abspath(args.out), args.timeout, not args.no_baseline, args.cold, args.recheck)


if __name__ == "__main__":
    sys.exit(main())
