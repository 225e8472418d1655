"""An `integrator: adaptive` session through the node: recorded, re-simulated
bit for bit, with the integration statistics in the recording's metadata and
in /diagnostics."""
import json

import pytest
from test_node_support import NodeProcess, run_cli

from physics_core import load_scene
from physics_node.diagnostics import DiagnosticsWindow
from physics_node.recorder import INTEGRATION_METADATA, SESSION_METADATA
from physics_node.recording_reader import Recording

# A ball on a stiff spring (ω = 1000 rad/s, several internal steps per 1/240 s
# step) that falls onto the ground and bounces: error control and contacts.
ADAPTIVE_SCENE = """\
dt: 0.004166666666666667
integrator: adaptive
accuracy: {relative: 1.0e-6, method: dormand_prince}
gravity: earth
effects: {contacts: {}}
bodies:
  - name: ground
    shape: {type: plane}
    static: true
    material: steel
  - name: ball
    shape: {type: sphere, radius: 0.1}
    mass: 1.0
    material: steel
    position: [0, 0, 0.5]
    velocity: [0.2, 0, 0]
  - name: bob
    shape: {type: sphere, radius: 0.05}
    mass: 1.0
    material: steel
    position: [1.01, 0, 1.0]
springs:
  - {a: bob, b: world, stiffness: 1.0e+6, point_b: [1.0, 0, 1.0]}
"""


def test_adaptive_session_resimulates_exactly_and_records_its_statistics(tmp_path):
    scene = tmp_path / "adaptive.yaml"
    scene.write_text(ADAPTIVE_SCENE)
    path = tmp_path / "adaptive.mcap"
    with NodeProcess(["--scene", scene, "--record", path, "--rtf", "0", "--duration", "1.0"], tmp_path,
                     isolated=True) as node:
        assert node.wait(60.0) == 0, node.log()
    result = run_cli("physics_node.replay", [path, "--resimulate"])
    assert result.returncode == 0, result.stdout + result.stderr

    recording = Recording(path)
    session = recording.metadata[SESSION_METADATA]
    assert session["integrator"] == "adaptive"
    assert json.loads(session["accuracy"])["relative"] == 1e-6
    stats = recording.metadata[INTEGRATION_METADATA]
    # the same scene stepped here gives the same totals (240 steps of 1/240 s)
    world = load_scene(scene)
    world.step(240)
    expected = world.integration_stats
    assert int(stats["internal_steps"]) == expected["internal_steps"] > 240
    assert int(stats["rejected_steps"]) == expected["rejected_steps"]
    assert float(stats["smallest_step_s"]) == expected["smallest_step_s"]


def test_diagnostics_report_the_integration_statistics():
    world = load_scene({"dt": 1 / 240, "accuracy": 1e-6,
                        "bodies": [{"name": "bob", "shape": {"type": "sphere", "radius": 0.05},
                                    "mass": 1.0, "position": [0.01, 0, 0]}],
                        "springs": [{"a": "bob", "b": "world", "stiffness": 1e6}]})
    world.step(5)                           # before the window: not counted per step
    before = world.integration_stats["internal_steps"]
    window = DiagnosticsWindow(world, ("rejected",))
    for _ in range(10):
        world.step()
        window.stepped(0, 1e-4)
    msg = window.report(0, "test", paused=False, target_rtf=1.0, recording=False)
    values = {kv.key: kv.value for kv in msg.status[0].values}
    total = world.integration_stats
    assert float(values["integration_internal_steps_total"]) == total["internal_steps"]
    per_step = float(values["integration_internal_steps_per_step"])
    assert per_step == pytest.approx((total["internal_steps"] - before) / 10, rel=1e-5)
    assert per_step >= 2.0
    assert 0.0 < float(values["integration_smallest_step_s"]) <= 1 / 240
    assert 0.0 < float(values["integration_max_local_error"]) <= 1.0
    assert float(values["integration_steps_at_min_step_total"]) == 0
