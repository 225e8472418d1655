"""`physics-bench node` runs every row it lists, as a user runs it: a
separate process, here for a fraction of a second per row.

Its `odometry all` row of 1,000 bodies is past the node's
topics_on_demand_above bound, where the node makes per-body topics on
demand and refuses `odometry: all`; the benchmark stopped there with that
error and wrote no results at all.
"""
import json

from test_node_support import run_cli

from benchmarks.node_realtime import CASES
from physics_node.body_topics import ON_DEMAND_ABOVE

CASE = "1000 @ 240 Hz, free, odometry all"


def test_node_benchmark_runs_its_odometry_all_row_past_the_on_demand_bound(tmp_path):
    case = next(c for c in CASES if c.name == CASE)
    assert case.odometry == "all" and case.bodies > ON_DEMAND_ABOVE
    done = run_cli("benchmarks.node_realtime",
                   ["--only", CASE, "--seconds", "0.3", "--no-listener", "--out", tmp_path],
                   timeout=180.0)
    assert done.returncode == 0, done.stderr[-3000:]
    rows = json.loads((tmp_path / "node_realtime.json").read_text())["rows"]
    ran = [r for r in rows if r["case"] == CASE]
    assert [r["record"] for r in ran] == [False, True]
    for row in ran:
        assert row["steps"] > 0
        # every body's odometry is published each step, besides the poses
        assert row["messages_per_step"] >= case.bodies
