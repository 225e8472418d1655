"""`physics-bench crosscheck --quick`, this engine's part, against each row's closed form.

The bench itself is benchmarks/crosscheck.py; the peers (PyBullet, MuJoCo) are
not needed here. Tolerances, row by row (COURSE.md sections in the scenes):

- slide to stop, v0²/(2 μ_k g): a dt² / 2 with a = μ_k g (9 µm at dt = 1/240 s).
  Friction at its kinetic bound moves the box by ½ a h² a substep, the
  exact motion under a constant force, so it stops short only by what its
  last, partial step would have slid, at most a dt² / 2
  (test_collisions_friction: the box launched sliding).
- bounce apex, C_R² h0: 2 % of the apex.
- roll at 5/7 v0: rounding only, 4 ε per step over the run's steps
  (friction at the contact point keeps the angular momentum about it;
  test_collisions_friction: the ball rolls on its radius).
- incline 1° below the friction angle: under 1 mm in 3 s (static friction holds).
- incline 1° above: g (sin θ − μ_k cos θ) within 1 %.
- 20-box stack, top box: within 5 mm (issue 10: "the 20-stack's top within 5 mm").
- 1000:1 pair, heavy cube's sink: within the slop + 2 mm (issue 10).
"""
import sys

import pytest

from benchmarks import crosscheck
from benchmarks import crosscheck_scenes as cs
from physics_core.contact_params import ContactParams

pytestmark = pytest.mark.filterwarnings("ignore:.*fallback")

ROLL_STEPS = round(next(r for r in cs.rows(True) if r.key == "roll").spec.duration / cs.DT)
TOLERANCE = {   # row -> (absolute tolerance, in the row's unit)
    "slide": cs.MU_K * cs.G * cs.DT ** 2 / 2,
    "bounce": 0.02 * cs.C_R ** 2 * cs.DROP_H0,
    "roll": ROLL_STEPS * 4 * sys.float_info.epsilon * 5.0 / 7.0 * cs.V_ROLL,
    "incline_hold": 1e-3,
    "incline_slide": 0.01 * 1.864,
    "stack": 5e-3,
    "mass_ratio": ContactParams().slop + 2e-3,
}


@pytest.fixture(scope="module")
def ours():
    data = crosscheck.run(quick=True, engines=("physics_core",))
    return {r["key"]: r for r in data["rows"]}


def test_every_row_has_a_tolerance():
    assert {r.key for r in cs.rows(True)} == set(TOLERANCE)


@pytest.mark.parametrize("key", sorted(TOLERANCE))
def test_this_engine_meets_the_closed_form(ours, key):
    row = ours[key]
    got = row["engines"]["physics_core"]
    assert got["status"] is None, got["status"]
    assert got["value"] == pytest.approx(row["closed_form"], abs=TOLERANCE[key]), row["title"]


def test_missing_peers_are_named_and_the_bench_still_runs(monkeypatch, tmp_path):
    """Only the closed-form rows' bookkeeping: the one row run is the cheapest."""
    monkeypatch.setattr(crosscheck, "installed", lambda e: e == "physics_core")
    roll = [r for r in cs.rows(True) if r.key == "roll"]
    monkeypatch.setattr(crosscheck.cs, "rows", lambda quick: roll)
    data = crosscheck.run(quick=True, out=str(tmp_path))
    assert data["missing"] == ["pybullet", "mujoco"]
    row = data["rows"][0]
    assert row["engines"]["pybullet"]["status"] == "not installed"
    assert row["closest"] == ["physics_core"]
    text = (tmp_path / "crosscheck.md").read_text()
    assert "Not installed: pybullet, mujoco" in text and "not installed" in crosscheck.table(data)
