"""physics-sweep without Ray: the --vary grammar and key paths, the designs,
the seeds' perturbations, the measures against closed forms, error rows and
the incremental, resumable Parquet file."""
import copy
import math
import re
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sweep_support import DROP_SCENE, FREE_SCENE

from physics_sweep import SweepError, SweepPlan, run_serial
from physics_sweep.design import Design, Perturb, Range, Vary, get_key, parse_key, parse_values, set_key
from physics_sweep.results import ResultsFile

import pyarrow.parquet as pq   # the `sweep` extra; `make install` installs it
re_literal = re.escape


# ---- key paths and values ----------------------------------------------------
def test_key_path_selects_bodies_by_name_and_components_by_index():
    scene = copy.deepcopy(DROP_SCENE)
    set_key(scene, parse_key("bodies[ball].restitution"), 0.9)
    set_key(scene, parse_key("bodies[probe].position[2]"), 7.5)
    set_key(scene, parse_key("effects.contacts.iterations"), 12)
    set_key(scene, parse_key("effects.drag.model"), "linear")      # mappings on the way are made
    assert scene["bodies"][1]["restitution"] == 0.9
    assert scene["bodies"][2]["position"] == [5.0, 0.0, 7.5]
    assert scene["effects"]["contacts"]["iterations"] == 12
    assert scene["effects"]["drag"] == {"model": "linear"}
    assert DROP_SCENE["bodies"][1]["restitution"] == 0.5
    set_key(scene, parse_key("bodies[*].restitution"), 0.25)
    assert get_key(scene, parse_key("bodies[*].restitution")) == [0.25, 0.25, 0.25]


@pytest.mark.parametrize("key, message", [
    ("bodies[nope].mass", "no item named 'nope'; names are: ground, ball, probe"),
    ("bodies[7].mass", "bodies[7]: index out of range (3 items)"),
    ("bodies[ball].position[5]", "bodies[ball].position[5]: index out of range"),
    ("dt[0]", "dt is float, not a list"),
])
def test_a_key_path_that_selects_nothing_names_where(key, message):
    with pytest.raises(SweepError, match=re_literal(message)):
        set_key(copy.deepcopy(DROP_SCENE), parse_key(key), 1.0)


@pytest.mark.parametrize("spec, message", [
    ("restitution", "expected KEY=VALUES"),
    ("bodies[ball]..mass=1", "is not a key"),
    ("bodies[a-b].mass=1", "selects nothing"),
    ("dt=1:2:0", "count of low:high:count is an integer >= 1"),
    ("dt=a:b:3", "a range is low:high:count"),
    ("dt=1,,2", "an empty value"),
])
def test_bad_vary_specs_name_the_option_and_text(spec, message):
    with pytest.raises(SweepError, match=re_literal(message)) as e:
        Vary.parse(spec)
    assert "--vary" in str(e.value)


def test_values_grammar():
    assert Range(0, 1, 11).grid() == [i / 10 for i in range(11)]
    assert Range(0, 1, 11).grid()[-1] == 1.0 and Range(0, 1, 11).grid()[3] == 0.3
    assert Range(1, 4, 4).grid() == [1, 2, 3, 4] and all(type(v) is int for v in Range(1, 4, 4).grid())
    assert parse_values("1/240,1/480", "dt") == [1 / 240, 1 / 480]
    assert parse_values("rk4,velocity_verlet", "integrator") == ["rk4", "velocity_verlet"]
    assert parse_values("true,false", "x") == [True, False]
    assert parse_values("-1:1", "x") == Range(-1, 1, None)
    assert Vary.parse("substeps=1:4:4").column_type() == "int"
    assert Vary.parse("dt=1/240,1/480").column_type() == "float"


def test_grid_between_integer_ends_with_fractional_steps_is_a_float_column(tmp_path):
    """Regression: `0:1:11` has integer ends but values 0.0, 0.1, ...; its
    column was typed int64 from the ends and the file held 0 and 1."""
    assert Vary.parse("bodies[ball].restitution=0:1:11").column_type() == "float"
    assert Vary.parse("k=0:10:11").column_type() == "int" and Vary.parse("k=0:10").column_type() == "int"
    from physics_sweep import sweep
    out = tmp_path / "r.parquet"
    sweep(copy.deepcopy(DROP_SCENE), ["bodies[ball].restitution=0:1:11"], duration=0.01, out=out,
          serial=True, progress=False)
    values = pq.read_table(out).sort_by("run_id").column("bodies[ball].restitution").to_pylist()
    assert values == [i / 10 for i in range(11)]


def test_grid_design_is_the_product_in_order_with_seeds_innermost():
    d = Design((Vary.parse("a=0:1:3"), Vary.parse("b=x,y")), seeds=2)
    runs = list(d.runs())
    assert len(d) == len(runs) == 12
    assert [r.run_id for r in runs] == list(range(12))
    assert runs[0].params == (("a", 0.0), ("b", "x")) and runs[0].seed == 0
    assert runs[1].seed == 1 and runs[2].params == (("a", 0.0), ("b", "y"))
    assert runs[-1].params == (("a", 1.0), ("b", "y"))


@settings(max_examples=40, deadline=None)
@given(low=st.floats(-1e3, 1e3), span=st.floats(1e-6, 1e3), n=st.integers(1, 50), seed=st.integers(0, 2**31))
def test_random_design_draws_inside_the_ranges_and_repeats_with_its_seed(low, span, n, seed):
    vary = (Vary("x", parse_key("x"), Range(low, low + span)), Vary("k", parse_key("k"), Range(2, 5)),
            Vary("w", parse_key("w"), ["a", "b"]))
    runs = list(Design(vary, samples=n, design_seed=seed).runs())
    again = list(Design(vary, samples=n, design_seed=seed).runs())
    assert runs == again and len(runs) == n
    for r in runs:
        x, k, w = (v for _, v in r.params)
        assert low <= x <= low + span and k in (2, 3, 4, 5) and type(k) is int and w in ("a", "b")


# ---- perturbations --------------------------------------------------------------
def _plan(scene=DROP_SCENE, vary=(), **kw):
    kw.setdefault("duration", 0.25)
    return SweepPlan.make(copy.deepcopy(scene), vary, **kw)


def test_seeds_perturb_dynamic_bodies_reproducibly_and_leave_static_ones():
    plan = _plan(seeds=400, perturbs=["position=0.01", "bodies[probe].orientation=0.1"])
    runs = list(plan.design.runs())
    scenes = [plan.scene_for(r) for r in runs]
    assert plan.scene_for(runs[5]) == scenes[5]                       # same seed, same scene
    assert scenes[0] != scenes[1]
    assert all(s["bodies"][0] == DROP_SCENE["bodies"][0] for s in scenes)    # the ground stays
    dz = np.array([s["bodies"][1]["position"] for s in scenes]) - [0.0, 0.0, 1.0]
    # 1,200 normal draws of σ = 0.01: the sample std is within 10 % (about 5 standard errors)
    assert abs(dz.std() - 0.01) < 0.001 and abs(dz.mean()) < 0.002
    q = np.array([s["bodies"][2]["orientation"] for s in scenes])
    assert np.allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-12)
    assert "orientation" not in scenes[0]["bodies"][1]                   # only the probe's


def test_seeds_default_to_one_millimetre_of_position_noise():
    plan = _plan(seeds=2)
    assert [p.key for p in plan.perturbs] == ["position"] and plan.perturbs[0].sigma == 0.001
    with pytest.raises(SweepError, match="QUANTITY one of"):
        Perturb.parse("mass=0.1")
    with pytest.raises(SweepError, match="no body named 'nobody'"):
        _plan(seeds=2, perturbs=["bodies[nobody].position=0.1"])


# ---- measures against closed forms ----------------------------------------------
def test_free_flight_measures_match_semi_implicit_euler_closed_form():
    """Semi-implicit Euler under constant g: v_n = v0 - g h n,
    z_n = z0 + n h v0 - g h² n(n+1)/2 (COURSE.md 3); duration 1 s = 100 steps."""
    m = ["ball.position.z:end", "ball.position.z:max", "ball.velocity.z:end", "ball.velocity.x:mean",
         "kinetic_energy:initial", "ball.speed:min", "time:end", "momentum.z:end",
         "sweep_support:ball_height", "sweep_support:ball_height:max"]
    (row,) = run_serial(_plan(FREE_SCENE, duration=1.0, measures=m))
    h, g, n, z0, v0 = 0.01, 9.81, 100, 1.0, 4.0
    z = [z0 + k * h * v0 - g * h * h * k * (k + 1) / 2 for k in range(n + 1)]
    assert row["error"] is None and row["steps"] == n
    assert row["ball.position.z:end"] == pytest.approx(z[-1], rel=1e-12, abs=1e-12)
    assert row["ball.position.z:max"] == pytest.approx(max(z), rel=1e-12)
    assert row["ball.velocity.z:end"] == pytest.approx(v0 - g * h * n, rel=1e-12)
    assert row["ball.velocity.x:mean"] == pytest.approx(1.0, rel=1e-12)
    assert row["kinetic_energy:initial"] == pytest.approx(0.5 * 2.0 * (1.0 + 16.0), rel=1e-12)
    speeds = [math.hypot(1.0, v0 - g * h * k) for k in range(n + 1)]
    assert row["ball.speed:min"] == pytest.approx(min(speeds), rel=1e-12)
    assert row["time:end"] == pytest.approx(1.0, rel=1e-12)
    assert row["momentum.z:end"] == pytest.approx(2.0 * (v0 - g * h * n), rel=1e-12)
    assert row["sweep_support:ball_height"] == pytest.approx(z[-1] - 0.1, rel=1e-12)
    assert row["sweep_support:ball_height:max"] == pytest.approx(max(z) - 0.1, rel=1e-12)


def test_contact_count_counts_the_bounces_of_a_dropped_ball():
    """Dropped from 1 m (0.9 m of fall to contact), e = 0.5: impacts at
    t1 = √(2·0.9/g) = 0.428 s and t1 + 2 e v1 / g = 0.857 s, the third after
    1.07 s; so two contacts begin in the first second, none for the probe."""
    (row,) = run_serial(_plan(duration=1.0, measures=["ball.contacts.begin:sum", "probe.contacts:sum",
                                                       "contacts.begin:sum"]))
    assert row["error"] is None
    assert row["ball.contacts.begin:sum"] == 2.0
    assert row["contacts.begin:sum"] == 2.0
    assert row["probe.contacts:sum"] == 0.0


def test_bad_measures_are_refused_before_the_sweep_naming_the_spec():
    for spec, message in [("ball.mass:max", "not a body quantity"), ("nobody.position.z", "no body 'nobody'"),
                          ("ball.position.q:max", "takes a component .x, .y, .z or .norm"),
                          ("no_such_module_xyz:f", "cannot import 'f'")]:
        with pytest.raises(SweepError, match=re_literal(message)) as e:
            _plan(measures=[spec])
        assert spec in str(e.value)


# ---- errors in rows ---------------------------------------------------------------
def test_a_run_that_raises_records_its_error_and_the_others_go_on():
    plan = _plan(vary=["bodies[ball].restitution=0.5,1.5,0.8"], measures=["ball.position.z:max",
                                                                      "sweep_support:not_a_number"])
    rows = list(run_serial(plan))
    assert [r["run_id"] for r in rows] == [0, 1, 2]
    assert "SceneError" in rows[1]["error"] and "bodies[1].restitution" in rows[1]["error"]
    assert rows[1]["ball.position.z:max"] is None
    assert all("returned str, expected a number" in r["error"] for r in (rows[0], rows[2]))
    plan = _plan(vary=["bodies[ball].restitution=0.5,1.5,0.8"], measures=["ball.position.z:max"])
    rows = list(run_serial(plan))
    assert rows[0]["error"] is None and rows[2]["error"] is None and rows[1]["error"]
    assert rows[0]["ball.position.z:max"] == pytest.approx(1.0, abs=1e-12)


def test_a_grid_range_without_a_count_is_refused_before_the_sweep():
    with pytest.raises(SweepError, match=re_literal("a grid needs a count (low:high:count)")):
        _plan(vary=["bodies[ball].restitution=0:1"])
    plan = _plan(vary=["bodies[ball].restitution=0:1"], samples=5)     # random: LOW:HIGH is enough
    assert len(plan.design) == 5


def test_a_typo_in_a_varied_key_fails_the_sweep_at_once():
    with pytest.raises(SweepError, match="no such key.*restitutoin"):
        _plan(vary=["bodies[ball].restitutoin=0:1:3"])


def test_varied_dt_changes_the_step_count():
    rows = list(run_serial(_plan(vary=["dt=1/240,1/480"], duration=0.5)))
    assert [r["steps"] for r in rows] == [120, 240]


# ---- the results file ---------------------------------------------------------------
def test_results_file_resumes_after_a_kill_without_repeating_a_run(tmp_path):
    """A process killed after two flushes leaves parts and no OUT; --resume
    reads the parts, computes only the rest and merges each run once."""
    plan = _plan(vary=["bodies[ball].restitution=0:1:6"], seeds=3, measures=["ball.position.z:max"])
    out = tmp_path / "r.parquet"
    f = ResultsFile(out, plan, flush_rows=4)
    f.add(run_serial(plan, [r for r in plan.design.runs() if r.run_id < 9]))   # two parts of 4; 1 row unflushed
    assert not out.exists() and len(list((tmp_path / "r.parquet.parts").glob("part-*.parquet"))) == 2
    del f                                                                       # killed: nothing closes it
    with pytest.raises(SweepError, match="--resume continues"):
        ResultsFile(out, plan)
    f = ResultsFile(out, plan, resume=True)
    assert f.done == set(range(8))
    todo = [r for r in plan.design.runs() if r.run_id not in f.done]
    f.add(run_serial(plan, todo))
    assert f.close() == 18
    table = pq.read_table(out)
    ids = sorted(table.column("run_id").to_pylist())
    assert ids == list(range(18)) and not (tmp_path / "r.parquet.parts").exists()
    serial = {r["run_id"]: r for r in run_serial(plan)}
    for row in table.to_pylist():
        assert row["ball.position.z:max"] == serial[row["run_id"]]["ball.position.z:max"]
    other = _plan(vary=["bodies[ball].restitution=0:1:5"], seeds=3, measures=["ball.position.z:max"])
    with pytest.raises(SweepError, match="holds a different sweep"):
        ResultsFile(out, other, resume=True)


def test_serial_sweep_through_the_api_writes_one_row_per_run(tmp_path):
    from physics_sweep import sweep
    out = tmp_path / "s.parquet"
    summary = sweep(copy.deepcopy(DROP_SCENE), ["bodies[ball].restitution=0:1:3", "dt=1/240,1/480"],
                    duration=0.2, measures=["ball.position.z:min"], out=out, serial=True, progress=False)
    assert (summary.rows, summary.total, summary.computed, summary.failed) == (6, 6, 6, 0)
    table = pq.read_table(out)
    assert table.column_names[:4] == ["run_id", "seed", "bodies[ball].restitution", "dt"]
    assert set(table.column("engine_version").to_pylist()) == {"0.1.0"}
    assert all(t > 0 for t in table.column("cpu_s").to_pylist())
    again = sweep(copy.deepcopy(DROP_SCENE), ["bodies[ball].restitution=0:1:3", "dt=1/240,1/480"],
                  duration=0.2, measures=["ball.position.z:min"], out=out, serial=True, progress=False,
                  resume=True)
    assert (again.rows, again.computed) == (6, 0)


def test_cli_reports_bad_arguments_with_status_2(tmp_path):
    base = [sys.executable, "-m", "physics_sweep", "--serial", "--out", str(tmp_path / "x.parquet")]
    r = subprocess.run(base + ["default", "--vary", "bodies[nope].mass=1,2"], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 2 and "physics-sweep: error:" in r.stderr and "nope" in r.stderr
    r = subprocess.run(base + ["default", "--resimulate", "x.mcap"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "not a scene" in r.stderr


def test_unreachable_cluster_is_an_error_in_seconds_and_leaves_no_file(tmp_path):
    """Regression: ray.init retried an address where nothing listens for minutes."""
    import socket
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]          # free, and closed again: nothing listens there
    out = tmp_path / "x.parquet"
    r = subprocess.run([sys.executable, "-m", "physics_sweep", "default", "--vary", "dt=1/240,1/480", "--quiet",
                        "--out", str(out), "--address", f"127.0.0.1:{port}"], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 2 and f"cannot reach the Ray cluster at '127.0.0.1:{port}'" in r.stderr, r.stderr
    assert list(tmp_path.iterdir()) == []


def test_cli_resimulate_prints_each_recording_and_exits_1_on_a_divergence(tmp_path):
    from sweep_support import SPIN_SCENE, write_recording
    write_recording(tmp_path / "a.mcap", SPIN_SCENE, 40, impulse_at=10)
    write_recording(tmp_path / "b.mcap", SPIN_SCENE, 40, impulse_at=10, tamper_step=25)
    (tmp_path / "c.mcap").write_bytes(b"not an mcap file")
    cmd = [sys.executable, "-m", "physics_sweep", "--serial", "--resimulate", str(tmp_path / "[ab].mcap")]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert r.returncode == 1, r.stdout + r.stderr
    lines = r.stdout.splitlines()
    assert lines[0] == f"{tmp_path / 'a.mcap'}: match"
    assert lines[1] == f"{tmp_path / 'b.mcap'}: diverge at step 25, body 'box'"
    assert lines[-1] == "2 recordings: 1 match, 1 diverge, 0 error"
    r = subprocess.run(cmd[:-1] + [str(tmp_path / "*.mcap")], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and r.stdout.splitlines()[-1] == "3 recordings: 1 match, 1 diverge, 1 error"
