"""The Recorder and the tolerant reader, on files written in this process."""

from pathlib import Path

import numpy as np
import pytest

from geometry_msgs.msg import PoseArray
from rclpy.serialization import serialize_message
from rosgraph_msgs.msg import Clock

from msg_adapters import pose_array, time_msg
from physics_node.qos import LATCHED, STREAM
from physics_node.recorder import Recorder
from physics_node.recording_reader import Recording, recover

rosbags = pytest.importorskip("rosbags")
from rosbags.highlevel import AnyReader  # noqa: E402
from rosbags.rosbag2 import Reader  # noqa: E402


def _write(path, steps=20, **kw):
    with Recorder(path, **kw) as rec:
        rec.add_attachment("scene.yaml", b"dt: 0.01\n", "application/yaml")
        rec.add_metadata("physics_node", {"node": "/physics", "dt": 0.01})
        for k in range(steps):
            t = k * 10_000_000
            rec.write("/clock", Clock, serialize_message(Clock(clock=time_msg(t))), t, k, LATCHED)
            poses = pose_array(np.array([[0.0, 0, k]]), np.array([[1.0, 0, 0, 0]]), t)
            rec.write("/physics/poses", PoseArray, serialize_message(poses), t, k, STREAM)
    return path


def test_rosbags_reads_topics_qos_and_times(tmp_path):
    path = _write(tmp_path / "a.mcap")
    with Reader(path) as reader:
        conns = {c.topic: c for c in reader.connections}
        assert conns["/clock"].msgcount == 20
        assert conns["/clock"].ext.offered_qos_profiles[0].durability.name == "TRANSIENT_LOCAL"
        assert conns["/physics/poses"].ext.offered_qos_profiles[0].depth == 10
        assert reader.start_time == 0 and reader.end_time == 19 * 10_000_000 + 1
    with AnyReader([path]) as reader:
        msgs = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages()]
    assert msgs[-1].poses[0].position.z == 19.0


def test_step_index_travels_in_the_sequence_field(tmp_path):
    path = _write(tmp_path / "a.mcap")
    rec = Recording(path)
    assert rec.complete
    seqs = [m.sequence for m in rec.messages() if m.topic == "/physics/poses"]
    assert seqs == list(range(20))
    assert rec.attachment(media_type="application/yaml").data == b"dt: 0.01\n"
    assert rec.metadata["physics_node"] == {"node": "/physics", "dt": "0.01"}


def test_an_exception_inside_the_block_still_finishes_the_file(tmp_path):
    path = tmp_path / "b.mcap"
    with pytest.raises(RuntimeError):
        with Recorder(path) as rec:
            rec.write("/clock", Clock, serialize_message(Clock()), 0, 0)
            raise RuntimeError("boom")
    assert Recording(path).complete
    with Reader(path) as reader:
        assert reader.message_count == 1


def test_close_is_idempotent(tmp_path):
    rec = Recorder(tmp_path / "c.mcap").open()
    rec.close()
    rec.close()
    assert not rec.is_open


def test_a_torn_file_reads_up_to_its_last_chunk_and_recovers(tmp_path):
    path = tmp_path / "d.mcap"
    # Tiny chunks: every few messages close one, as a long session would.
    _write(path, steps=200, chunk_size=2000)
    data = Path(path).read_bytes()
    torn = tmp_path / "torn.mcap"
    torn.write_bytes(data[: len(data) * 2 // 3])
    rec = Recording(torn)
    assert not rec.complete and rec.problem
    poses = [m for m in rec.messages() if m.topic == "/physics/poses"]
    assert 20 < len(poses) < 200
    assert [m.sequence for m in poses] == list(range(len(poses)))

    fixed = tmp_path / "fixed.mcap"
    assert recover(torn, fixed) == sum(1 for _ in rec.messages())
    with AnyReader([fixed]) as reader:
        assert sum(1 for _ in reader.messages()) == recover(torn, tmp_path / "again.mcap")


def test_not_an_mcap_file_is_a_clear_error(tmp_path):
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"hello")
    with pytest.raises(ValueError, match="not an MCAP"):
        Recording(junk)
