"""What a start of the node or the engine compiles before its first step: each
test runs a start in a fresh process that prints a list of what it compiled."""
import os

from fresh_process import ROOT, printed_value


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
    from_source = printed_value(_FROM_SOURCE, 300, dict(os.environ, PYTHONDONTWRITEBYTECODE="1"))
    assert from_source == [], f"compiled from source at start (run `make install`): {from_source}"


_COMPILES_AT_START = """
from numba.core import event

compiled = []


class Compiles(event.Listener):
    def on_start(self, ev):
        compiled.append(str(ev.data["dispatcher"].py_func.__qualname__))

    def on_end(self, ev):
        pass


event.register("numba:compile", Compiles())
import physics_core
world = physics_core.load_scene(physics_core.default_scene_path())
world.step(1)
print(repr(compiled))
"""


def test_typed_lists_made_in_python_compiled_their_methods_at_every_import():
    """Regression: the warm cache's typed lists were made by Python calls
    (typed.List.empty_list, append), whose compiled methods numba does not
    cache: every `import physics_core` compiled them again, about 1 s of a
    2.1–2.7 s import. Once a process has cached what the default scene
    uses (the first run below: nothing to do after `make install`, the
    whole step after an edit of the engine), importing the engine and
    stepping that scene once compiles nothing (numba's "numba:compile"
    event fires only on a cache miss)."""
    printed_value(_COMPILES_AT_START, 3600)
    assert printed_value(_COMPILES_AT_START, 300) == []
