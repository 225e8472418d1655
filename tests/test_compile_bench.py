"""`physics-bench compile` (benchmarks/compile_time.py): its per-kernel
timing of numba's compile events, its switch back to numba's own inliner,
and its table. The study itself compiles every kernel twice (about 18
minutes on a 2 GHz pair) and is not run here."""
from time import perf_counter

from numba import njit

from benchmarks.compile_time import markdown, own_times
from fresh_process import printed_value


def test_each_kernel_is_charged_its_own_compile_and_the_times_add_up_to_the_whole():
    """A chain top → middle → leaf compiled inside the timer: each of the three
    gets a positive own time, and their sum is the compile's wall time less
    what ran outside any compile event (the call itself, microseconds)."""
    @njit
    def leaf(x):
        return x * 2.0 + 1.0

    @njit
    def middle(x):
        s = 0.0
        for i in range(3):
            s += leaf(x + i)
        return s

    @njit
    def top(x):
        return middle(x) - leaf(x)

    t0 = perf_counter()
    with own_times() as own:
        assert top(1.0) == 15.0 - 3.0
    elapsed = perf_counter() - t0
    names = {n.rsplit(".", 1)[-1]: t for n, t in own.items() if "<locals>" in n}
    assert set(names) == {"top", "middle", "leaf"}
    assert all(t > 0.0 for t in names.values())
    assert 0.9 * elapsed <= sum(own.values()) <= elapsed


def test_the_timer_stops_listening_when_its_block_ends():
    with own_times() as own:
        pass

    @njit
    def later(x):
        return x + 1

    later(1)
    assert own == {}


def test_numbas_own_inliner_can_be_put_back_and_shared_copies_set_again():
    code = ("import copy, physics_core\n"
            "from numba.core import inline_closurecall as ic\n"
            "from physics_core.inline_copies import restore_inline_copies, share_inline_copies\n"
            "shared = lambda: getattr(ic.InlineWorker.inline_ir, 'shares_copies', False)\n"
            "out = [shared(), restore_inline_copies(), shared(), ic.copy is copy,"
            " restore_inline_copies(), share_inline_copies(), shared(), ic.copy is copy]\n"
            "print(out)")
    assert printed_value(code) == [True, True, False, True, False, True, True, False]


def test_the_table_lists_the_kernels_by_their_own_compile_under_numbas_inliner():
    runs = {"shared": {"seconds": 364.2, "own": {"physics_core.a": 73.0, "physics_core.b": 31.0,
                                                  "physics_core.c": 27.0}},
            "numba": {"seconds": 741.0, "own": {"physics_core.a": 248.0, "physics_core.b": 87.0,
                                                 "physics_core.c": 128.0}}}
    text = markdown(runs)
    rows = [line for line in text.splitlines() if line.startswith("| ")]
    assert rows[0] == "| | shared inliner, s | numba inliner, s |"
    assert rows[1] == "| **all kernels** | **364** | **741** |"
    assert [r.split("`")[1] for r in rows[2:]] == ["a", "c", "b"]
    assert rows[3] == "| `c` (own) | 27.0 | 128.0 |"
    quick = markdown({"shared": runs["shared"]})
    assert "| **all kernels** | **364** |" in quick
