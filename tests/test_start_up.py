"""What a start of the node spends before its first step, beyond the kernels."""
import ast
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# Imports what `physics-node` imports, with Python writing no bytecode, and
# prints the project's files that Python had to compile from source.
_FROM_SOURCE = f"""
import importlib._bootstrap_external as external
compiled = []
_source_to_code = external.SourceLoader.source_to_code
def _record(self, data, path, *args, **kwargs):
    compiled.append(path)
    return _source_to_code(self, data, path, *args, **kwargs)
external.SourceLoader.source_to_code = _record
import physics_node.main
print(sorted(p for p in compiled if p.startswith({ROOT!r})))
"""


def test_every_start_compiled_the_sources_where_python_writes_no_bytecode():
    """Regression: with PYTHONDONTWRITEBYTECODE set (this machine's image
    sets it, as many containers do) Python never kept the bytecode of the
    project's 110 modules, so every start of the node compiled them from
    source again: about 0.25 s of a 1.9 s start to the first step. `make
    install` writes that bytecode (and again for any file changed since);
    a start then reads it and compiles none of the project's files."""
    env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1")
    out = subprocess.run([sys.executable, "-c", _FROM_SOURCE], capture_output=True, text=True,
                         timeout=300, check=True, env=env, cwd=ROOT).stdout
    from_source = ast.literal_eval(out.strip().splitlines()[-1])
    assert from_source == [], f"compiled from source at start (run `make install`): {from_source}"
