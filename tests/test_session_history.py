"""The node's history for recordings started mid-session (physics_node/session_history.py):
what goes in comes out of its MCAP unchanged, a full reset clears it, and
past its bound it is dropped and said to be incomplete until the next reset,
which `--resimulate` then gives as its reason."""

import types

from geometry_msgs.msg import WrenchStamped
from rclpy.serialization import serialize_message
from std_msgs.msg import String

from msg_adapters import wrench_stamped
from physics_node.qos import COMMANDS, STREAM
from physics_node.recording_reader import Recording
from physics_node.resimulate import ERROR, resimulate
from physics_node.session_history import HISTORY_STATE, STARTED_AT_STEP, SessionHistory

WRENCH = serialize_message(wrench_stamped((1.0, 2.0, 3.0)))
RESET = serialize_message(String(data="reset"))


def _stepper():
    return types.SimpleNamespace(resets=0)


def test_what_goes_in_comes_out_of_its_mcap_in_order():
    history = SessionHistory(_stepper())
    assert history.empty
    history.add("/physics/ball/wrench", WrenchStamped, WRENCH, 10_000_000, 1, COMMANDS)
    history.add_attachment("spawn:/tmp/b.yaml", b"name: b\n", "application/yaml", 20_000_000)
    history.add("/physics/events", String, RESET, 30_000_000, 3, STREAM)
    read = Recording(history.mcap())
    assert read.complete
    assert [(a.name, bytes(a.data)) for a in read.attachments] == [("spawn:/tmp/b.yaml", b"name: b\n")]
    got = [(m.topic, m.type_name, m.log_time, m.sequence, bytes(m.data)) for m in read.messages()]
    assert got == [
        ("/physics/ball/wrench", "geometry_msgs/msg/WrenchStamped", 10_000_000, 1, WRENCH),
        ("/physics/events", "std_msgs/msg/String", 30_000_000, 3, RESET),
    ]


def test_a_full_reset_clears_it():
    stepper = _stepper()
    history = SessionHistory(stepper)
    history.add("/physics/ball/wrench", WrenchStamped, WRENCH, 0, 0, COMMANDS)
    stepper.resets += 1
    assert history.empty
    history.add("/physics/ball/wrench", WrenchStamped, WRENCH, 0, 0, COMMANDS)
    assert sum(1 for _ in Recording(history.mcap()).messages()) == 1


def test_past_its_bound_it_is_incomplete_until_the_next_reset():
    stepper = _stepper()
    history = SessionHistory(stepper, limit_bytes=10 * (len(WRENCH) + 100))
    for step in range(11):
        history.add("/physics/ball/wrench", WrenchStamped, WRENCH, step * 10_000_000, step, COMMANDS)
    assert history.mcap() is None and "MAX_HISTORY_BYTES" in history.lost
    stepper.resets += 1
    history.add("/physics/ball/wrench", WrenchStamped, WRENCH, 0, 0, COMMANDS)
    assert history.lost == "" and history.mcap() is not None


def test_resimulate_refuses_a_mid_session_recording_without_its_history(tmp_path):
    """Such a file plays back, but nothing rebuilds the world up to its first step."""
    from mcap.writer import Writer

    path = tmp_path / "late.mcap"
    with open(path, "wb") as f:
        writer = Writer(f)
        writer.start(profile="ros2", library="test")
        writer.add_attachment(0, 0, "scene.yaml", "application/yaml", b"bodies: [{name: b, shape: {type: plane}}]\n")
        writer.add_metadata("physics_node", {"node": "/physics", STARTED_AT_STEP: "120",
                                             HISTORY_STATE: "incomplete: it passed 64 MiB"})
        writer.finish()
    result = resimulate(path)
    assert result.status == ERROR
    assert "step 120" in result.error and "passed 64 MiB" in result.error
