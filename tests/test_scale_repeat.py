"""`physics-bench scale --repeat R` (benchmarks/scale.py): each engine's
fastest run is kept, every round's figure is kept beside it, a failed run
never wins, and the per-round ratios pair runs of the same round."""
from benchmarks import scale


def _run(engine, rate, marker):
    return {"engine": engine, "bodies": 10, "steps_per_second": rate, "marker": marker}


def test_the_fastest_run_of_each_engine_is_kept_with_every_round():
    kept = {}
    for k, rate in enumerate([100.0, 140.0, 120.0]):
        scale._keep_fastest(kept, "physics_core", _run("physics_core", rate, k))
    assert kept["physics_core"]["marker"] == 1
    assert kept["physics_core"]["steps_per_second"] == 140.0
    assert kept["physics_core"]["rounds"] == [100.0, 140.0, 120.0]


def test_a_failed_run_is_recorded_but_never_kept_over_a_measured_one():
    kept = {}
    scale._keep_fastest(kept, "mujoco", _run("mujoco", 50.0, 0))
    scale._keep_fastest(kept, "mujoco", {"engine": "mujoco", "bodies": 10, "error": "timeout"})
    assert kept["mujoco"]["marker"] == 0 and kept["mujoco"]["rounds"] == [50.0, None]


def test_round_ratios_compare_runs_of_the_same_round_with_the_faster_peer():
    per = {"physics_core": {"rounds": [200.0, 150.0]},
           "pybullet": {"rounds": [100.0, 50.0]},
           "mujoco": {"rounds": [80.0, 75.0]}}
    assert scale.round_ratios(per) == [2.0, 2.0]
    per["mujoco"]["rounds"][1] = None            # a failed peer run leaves the other peer
    assert scale.round_ratios(per) == [2.0, 3.0]
