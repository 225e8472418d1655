"""The peers of `physics-bench scale`: MuJoCo runs with its default Newton
solver and with CG, and every "ahead of" figure is over the fastest peer
that ran, never over one chosen solver (benchmarks/engines.py)."""
import re

from benchmarks import engines, pile_compare, scale


def test_mujoco_is_two_peers_newton_and_cg_from_one_module():
    assert engines.PEERS == ("pybullet", "mujoco", "mujoco-cg")
    assert engines.module_of("mujoco") == engines.module_of("mujoco-cg") == "mujoco"
    assert engines.module_of("pybullet") == "pybullet"
    bodies = pile_compare.pile(3)
    for solver in ("Newton", "CG"):
        xml = engines.mujoco_xml(bodies, 1 / 240, 8, solver)
        assert re.search(r'<option timestep="0.00416667" iterations="8" solver="%s"/>' % solver, xml)
        assert xml.count("<freejoint/>") == 3


def test_fastest_peer_ratio_is_over_the_fastest_peer_that_ran():
    per = {"physics_core": {"steps_per_second": 300.0},
           "pybullet": {"steps_per_second": 50.0},
           "mujoco": {"steps_per_second": 20.0},
           "mujoco-cg": {"steps_per_second": 150.0}}
    assert scale.fastest_peer_ratio(per) == 2.0
    per["mujoco-cg"] = {"error": "timed out"}          # a failed peer leaves the others
    assert scale.fastest_peer_ratio(per) == 6.0
    assert scale.fastest_peer_ratio({"physics_core": {"steps_per_second": 1.0}}) is None


def test_the_pile_table_gives_this_engine_over_the_fastest_peer(monkeypatch):
    cpu = {"physics_core": 1.0, "pybullet": 4.0, "mujoco": 40.0, "mujoco-cg": 2.5}
    monkeypatch.setattr(pile_compare, "installed", lambda engine: True)
    monkeypatch.setattr(pile_compare, "time_engine",
                        lambda engine, bodies, steps, budget: (steps, cpu[engine], cpu[engine], None))
    row, = pile_compare.run(sizes=(10,), steps=100, log=lambda m: None)
    assert row["this / mujoco"] == "40.00" and row["this / mujoco-cg"] == "2.50"
    assert row["this / fastest peer"] == "2.50"
    (n, ratios), = scale.pile_ratios([row])
    assert n == 10 and ratios == {"pybullet": 0.25, "mujoco": 0.025, "mujoco-cg": 0.4}
