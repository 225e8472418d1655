"""Numba's reference counts are inlinable in the compiled step
(physics_core/refcounts.py), and inlined they still free every array.

Each check runs in a fresh process: whether the counters are inlinable is
decided once, when numba first compiles its runtime."""
import os

import pytest

from fresh_process import printed_value


def test_importing_the_engine_makes_the_runtime_counters_inlinable():
    """The runtime numba compiles after `import physics_core` defines
    NRT_incref and NRT_decref without the noinline attribute."""
    got = printed_value(
        "import physics_core\n"
        "from numba.core.runtime import nrt\n"
        "import numpy as np\n"
        "physics_core.load_scene(physics_core.default_scene_path()).step(1)\n"
        "ir = nrt.rtsys.library.get_llvm_str()\n"
        "heads = [l for l in ir.splitlines() if l.startswith('define') and "
        "('@NRT_incref' in l or '@NRT_decref' in l)]\n"
        "groups = {l.split('=')[0].replace('attributes', '').strip(): l for l in ir.splitlines() if l.startswith('attributes #')}\n"
        "attrs = [groups.get(h.rsplit(' ', 2)[-2], '') + h for h in heads]\n"
        "print({'n': len(heads), 'noinline': any('noinline' in a for a in attrs)})")
    assert got == {"n": 2, "noinline": False}


def test_a_runtime_compiled_before_the_engine_keeps_its_counters_and_steps_the_same():
    """If numba's runtime was compiled before `import physics_core`, the
    counters stay as numba made them: inline_reference_counts says so, and
    the step still gives the same bits as with inlined counters."""
    code = (
        "import hashlib{pre}\n"
        "import physics_core\n"
        "from physics_core.refcounts import inline_reference_counts\n"
        "w = physics_core.load_scene('scenes/pyramid_10.yaml')\n"
        "w.step(120)\n"
        "h = hashlib.sha1(w.state.pos.tobytes() + w.state.quat.tobytes() + w.state.vel.tobytes()"
        " + w.state.omega.tobytes()).hexdigest()\n"
        "print({{'inlinable': inline_reference_counts(), 'digest': h}})")
    early = "\nfrom numba import njit\nnjit(lambda x: x + 1)(1)"
    inlined = printed_value(code.format(pre=""))
    counted = printed_value(code.format(pre=early))
    assert inlined["inlinable"] is True and counted["inlinable"] is False
    assert inlined["digest"] == counted["digest"]


@pytest.mark.parametrize("scene", ["scenes/pyramid_10.yaml", "scenes/bullet_wall.yaml"])
def test_inlined_reference_counts_free_every_array_a_step_allocates(scene):
    """With NUMBA_NRT_STATS on: the arrays alive after 60 more steps are the
    arrays alive before them (a missed decref would leave one per step, a
    missed incref would free one still in use and crash or corrupt)."""
    got = printed_value(
        "import physics_core\n"
        "from numba.core.runtime import rtsys\n"
        f"w = physics_core.load_scene({scene!r})\n"
        "w.step(30)\n"
        "def live():\n"
        "    s = rtsys.get_allocation_stats()\n"
        "    return s.alloc - s.free, s.mi_alloc - s.mi_free\n"
        "a = live()\n"
        "w.step(60)\n"
        "b = live()\n"
        "w.step(60)\n"
        "c = live()\n"
        "print({'a': a, 'b': b, 'c': c, 'allocs': rtsys.get_allocation_stats().alloc})",
        env=dict(os.environ, NUMBA_NRT_STATS="1"))
    assert got["allocs"] > 0            # the stats are on and the step allocates
    assert got["b"] == got["a"] and got["c"] == got["a"], got
