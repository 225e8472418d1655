"""The recorder's chunk writer thread: the same bytes as writing inline
whatever the thread's timing, `close()` drains and joins it, its errors
reach the caller, a full queue blocks the caller, and a process killed
outright keeps every chunk the thread had written."""

import errno
import os
import random
import signal
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import pytest
from geometry_msgs.msg import PoseArray
from mcap.exceptions import EndOfFile, McapError
from mcap.reader import make_reader
from mcap.records import Message
from mcap.stream_reader import StreamReader
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import PointCloud2

from msg_adapters.cdr import PoseArrayCdr, clock_cdr
from physics_node import chunk_writer
from physics_node import recorder as recorder_module
from physics_node.qos import LATCHED, STREAM
from physics_node.recorder import Recorder, RecorderError
from physics_node.recording_reader import Recording

rosbags = pytest.importorskip("rosbags")
from rosbags.rosbag2 import Reader  # noqa: E402

import numpy as np  # noqa: E402


def _steps(count, bodies=5):
    rng = np.random.default_rng(7)
    poses = PoseArrayCdr(bodies)
    out = []
    for k in range(count):
        t = 1_000_000 * k
        pos, quat = rng.normal(size=(bodies, 3)), np.tile([1.0, 0, 0, 0], (bodies, 1))
        cloud = bytes(rng.integers(0, 4, size=8 * (k % 7), dtype=np.uint8))
        out.append((t, [clock_cdr(t), poses.build(pos, quat, t), cloud]))
    return out


class SlowFile:
    """A file whose writes take a random while (the writer thread falls
    behind by varying amounts); optionally blocked until `gate` is set."""

    def __init__(self, path, seed=None, gate=None):
        self._f = open(path, "wb")
        self._rng = random.Random(seed)
        self.gate = gate
        self.writes = 0

    def write(self, data):
        if self.gate is not None:
            self.gate.wait()
        if self._rng is not None and self._rng.random() < 0.3:
            time.sleep(self._rng.random() * 0.004)
        self.writes += 1
        return self._f.write(data)

    def flush(self):
        self._f.flush()

    def close(self):
        self._f.close()


class FullDisk(SlowFile):
    """Raises ENOSPC once `limit` bytes have been written."""

    def __init__(self, path, limit):
        super().__init__(path)
        self._rng = None
        self.limit, self.written = limit, 0

    def write(self, data):
        if self.written + len(data) > self.limit:
            raise OSError(errno.ENOSPC, "No space left on device")
        self.written += len(data)
        return self._f.write(data)


def _session(path, steps, chunk_size=3000, file_factory=None, monkeypatch=None):
    rec = Recorder(path, chunk_size=chunk_size, flush_period=float("inf"))
    if file_factory is not None:
        rec._open_file = lambda: file_factory(path)
    with rec:
        rec.add_metadata("physics_node", {"node": "/physics"})
        clock = rec.channel("/clock", Clock, LATCHED)
        ids = [clock, rec.channel("/physics/poses", PoseArray, STREAM), rec.channel("/physics/contacts", PointCloud2)]
        for k, (t, datas) in enumerate(steps):
            rec.write_many(ids, datas, t, k)
            if k % 5 == 0:
                rec.write("/physics/events", Clock, datas[0], t, k)
            if k == len(steps) // 2:
                rec.add_attachment("scene.yaml", b"dt: 0.001\n", "application/yaml", t)
            if k % 17 == 0:
                rec.write_many(ids[1:2], datas[1:2], t, k)
    return path


@pytest.mark.parametrize("seed", [1, 2])
def test_threaded_file_is_the_inline_file_byte_for_byte(tmp_path, monkeypatch, seed):
    """Chunk boundaries and record order depend on the inputs only: a writer
    thread that lags by random amounts writes exactly what writing every
    chunk inline on the calling thread writes."""
    steps = _steps(300)
    threaded = _session(tmp_path / "threaded.mcap", steps, file_factory=lambda p: SlowFile(p, seed))
    monkeypatch.setattr(recorder_module, "WRITER_THREAD", False)
    inline = _session(tmp_path / "inline.mcap", steps)
    assert threaded.read_bytes() == inline.read_bytes()
    rec = Recording(threaded)
    assert rec.complete and rec.chunk_count > 20
    with open(threaded, "rb") as f:
        reader = make_reader(f)
        seqs = [m.sequence for _, c, m in reader.iter_messages() if c.topic == "/physics/poses"]
        stats = reader.get_summary().statistics
    assert seqs == sorted(list(range(300)) + list(range(0, 300, 17)))
    assert stats.chunk_count == rec.chunk_count and stats.attachment_count == 1
    with Reader(threaded) as reader:
        assert {c.topic: c.msgcount for c in reader.connections}["/clock"] == 300


def test_close_drains_the_queue_joins_the_thread_and_is_idempotent(tmp_path):
    gate = threading.Event()
    path = tmp_path / "drain.mcap"
    rec = Recorder(path, chunk_size=2000, flush_period=float("inf"))
    rec._open_file = lambda: SlowFile(path, seed=None, gate=gate)
    rec.open()
    sink = rec._sink
    ids = [rec.channel("/clock", Clock, LATCHED)]
    for k, (t, datas) in enumerate(_steps(60)):  # queued while the file is held up
        rec.write_many(ids, datas[:1], t, k)
    assert sink._thread.is_alive() and sink._queue.qsize() > 0
    threading.Timer(0.2, gate.set).start()
    rec.close()
    assert not sink._thread.is_alive() and sink._queue.qsize() == 0
    assert not rec.is_open
    rec.close()  # again: nothing to do
    assert Recording(path).complete
    with Reader(path) as reader:
        assert reader.message_count == 60


def test_flush_returns_once_the_chunks_are_in_the_file(tmp_path):
    path = tmp_path / "flush.mcap"
    rec = Recorder(path, chunk_size=1 << 20, flush_period=float("inf"))
    rec._open_file = lambda: SlowFile(path, seed=3)
    with rec:
        ids = [rec.channel("/clock", Clock, LATCHED)]
        for k, (t, datas) in enumerate(_steps(40)):
            rec.write_many(ids, datas[:1], t, k)
        rec.flush()
        assert sum(1 for _ in Recording(path).messages()) == 40


def test_a_writer_error_reaches_the_caller(tmp_path):
    path = tmp_path / "full.mcap"
    rec = Recorder(path, chunk_size=2000, flush_period=float("inf"))
    rec._open_file = lambda: FullDisk(path, limit=6000)
    rec.open()
    ids = [rec.channel("/clock", Clock, LATCHED), rec.channel("/physics/poses", PoseArray)]
    with pytest.raises(RecorderError, match="No space left") as raised:
        for k, (t, datas) in enumerate(_steps(2000)):
            rec.write_many(ids, datas[:2], t, k)
            time.sleep(0.0005)
    assert isinstance(raised.value.__cause__, OSError) and raised.value.__cause__.errno == errno.ENOSPC
    with pytest.raises(RecorderError):  # the recording cannot go on
        rec.write("/clock", Clock, clock_cdr(0), 0, 0)
    with pytest.raises(RecorderError):
        rec.flush()
    sink = rec._sink
    rec.close()  # already reported: closes quietly
    assert not sink._thread.is_alive() and not rec.is_open
    assert Recording(path).chunk_count >= 1  # what was written before the disk filled


def _poses_on_a_small_disk(path):
    """A recorder whose disk fills at 4000 bytes, holding 100 steps of poses
    in one open chunk (so nothing has been written yet)."""
    rec = Recorder(path, chunk_size=1 << 20, flush_period=float("inf"))
    rec._open_file = lambda: FullDisk(path, limit=4000)
    rec.open()
    ids = [rec.channel("/physics/poses", PoseArray)]
    for k, (t, datas) in enumerate(_steps(100)):
        rec.write_many(ids, datas[1:2], t, k)
    return rec


def test_a_writer_error_during_close_is_raised_by_close(tmp_path):
    rec = _poses_on_a_small_disk(tmp_path / "full-at-close.mcap")  # one chunk, written by close
    with pytest.raises(RecorderError) as raised:
        rec.close()
    assert isinstance(raised.value.__cause__, OSError)
    rec.close()
    assert not rec.is_open


def test_a_writer_error_is_raised_by_flush(tmp_path):
    rec = _poses_on_a_small_disk(tmp_path / "full-at-flush.mcap")
    with pytest.raises(RecorderError):
        rec.flush()
    rec.close()


def test_a_full_queue_blocks_the_caller(tmp_path, monkeypatch):
    monkeypatch.setattr(chunk_writer, "QUEUE_JOBS", 2)
    gate = threading.Event()
    path = tmp_path / "backpressure.mcap"
    rec = Recorder(path, chunk_size=500, flush_period=float("inf"))
    rec._open_file = lambda: SlowFile(path, seed=None, gate=gate)
    rec.open()
    ids = [rec.channel("/physics/poses", PoseArray)]
    steps = _steps(50)
    done = []

    def produce():
        for k, (t, datas) in enumerate(steps):
            rec.write_many(ids, datas[1:2], t, k)
            done.append(k)

    producer = threading.Thread(target=produce)
    producer.start()
    producer.join(0.5)
    assert producer.is_alive(), "the caller should wait for the writer"
    assert len(done) < 10 and rec._sink._queue.qsize() <= 2  # nothing dropped, nothing piled up
    gate.set()
    producer.join(10.0)
    assert not producer.is_alive() and len(done) == 50
    rec.close()
    with Reader(path) as reader:
        assert reader.message_count == 50


def test_a_dropped_recorder_still_writes_its_queued_chunks(tmp_path):
    path = tmp_path / "dropped.mcap"
    rec = Recorder(path, chunk_size=500, flush_period=float("inf")).open()
    sink = rec._sink
    ids = [rec.channel("/physics/poses", PoseArray)]
    for k, (t, datas) in enumerate(_steps(30)):
        rec.write_many(ids, datas[1:2], t, k)
    del rec  # never closed: the finalizer drains the queue and closes the file
    assert not sink._thread.is_alive()
    assert len([m for m in Recording(path).messages()]) >= 28


KILLED = textwrap.dedent(
    """
    import sys, time
    from geometry_msgs.msg import PoseArray
    from msg_adapters.cdr import PoseArrayCdr
    import numpy as np
    from physics_node.recorder import Recorder

    rec = Recorder(sys.argv[1], chunk_size=4000, flush_period=float("inf")).open()
    poses = PoseArrayCdr(10)
    channel = rec.channel("/physics/poses", PoseArray)
    for k in range(400):
        rec.write_many([channel], [poses.build(np.full((10, 3), k), np.tile([1.0, 0, 0, 0], (10, 1)), k)], k, k)
    rec.flush()
    print("flushed", flush=True)
    for k in range(400, 405):  # in the open chunk: lost
        rec.write_many([channel], [poses.build(np.full((10, 3), k), np.tile([1.0, 0, 0, 0], (10, 1)), k)], k, k)
    time.sleep(60)
    """
)


def test_kill_9_keeps_every_chunk_the_writer_had_written(tmp_path):
    path = tmp_path / "killed.mcap"
    root = str(Path(__file__).resolve().parents[1])
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([root, os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.Popen([sys.executable, "-c", KILLED, str(path)], stdout=subprocess.PIPE, text=True, env=env)
    try:
        assert proc.stdout.readline().strip() == "flushed"
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait(10)
    assert proc.returncode == -signal.SIGKILL
    rec = Recording(path)
    assert not rec.complete and rec.chunk_count > 10
    assert [m.sequence for m in rec.messages()] == list(range(400))
    with open(path, "rb") as f:  # mcap's own stream reader, up to the torn end
        messages = 0
        try:
            for record in StreamReader(f, skip_magic=False).records:
                messages += isinstance(record, Message)
        except (McapError, EndOfFile):
            pass  # the torn end
    assert messages == 400
