"""Recorder.write_many (a step's outputs at once) writes what mcap's own
`Writer.add_message` would: same messages, indexes and statistics, and
byte for byte the same file while the batches do not straddle a chunk.
Message by message (`write`), the file is mcap's byte for byte at any chunk
size (with mcap's zstd level)."""

import itertools
import math

import mcap
import pytest
from mcap.reader import make_reader
from mcap.records import Chunk, Message
from mcap.stream_reader import StreamReader, breakup_chunk
from mcap.writer import CompressionType, Writer
from nav_msgs.msg import Odometry
from rclpy.serialization import serialize_message
from rosgraph_msgs.msg import Clock

from msg_adapters import odometry, time_msg
from msg_adapters.schema import ros2msg_schema, type_name
from physics_node import chunk_writer
from physics_node import recorder as recorder_module
from physics_node.qos import LATCHED, STREAM, offered_qos_yaml
from physics_node.recorder import Recorder
from physics_node.recording_reader import Recording

BODIES = ("a", "bb", "ccc")


def _payloads(steps):
    """(time, clock bytes, odometry bytes per body) per step, serialized once
    (rclpy leaves CDR padding uninitialised, so two serializations differ)."""
    out = []
    for k in range(steps):
        t = 4_166_667 * k
        odom = [
            serialize_message(odometry(name, [k, i, 0.0], [1.0, 0, 0, 0], [0, 0, 0], [0, 0, 0], t))
            for i, name in enumerate(BODIES)
        ]
        out.append((t, serialize_message(Clock(clock=time_msg(t))), odom))
    return out


def _session(path, payloads, chunk_size, batched=True):
    """Clock one by one, every body's odometry per step: with write_many or with write."""
    topics = [f"/physics/{name}/odom" for name in BODIES]
    # no time-based flush: it would close a chunk wherever a slow machine happens to be
    with Recorder(path, chunk_size=chunk_size, flush_period=math.inf) as rec:
        rec.add_metadata("physics_node", {"node": "/physics"})
        rec.channel("/clock", Clock, LATCHED)
        channels = [rec.channel(topic, Odometry, STREAM) for topic in topics]
        for k, (t, clock, odom) in enumerate(payloads):
            rec.write("/clock", Clock, clock, t, k, LATCHED)
            if batched:
                rec.write_many(channels, odom, t, k)
            else:
                for topic, data in zip(topics, odom):
                    rec.write(topic, Odometry, data, t, k, STREAM)
        assert rec.message_count == len(payloads) * (1 + len(BODIES))
    return path


class _McapSession:
    """The same session written by mcap's Writer itself, message by message,
    as the recorder lays it out (metadata, then a flush)."""

    def __init__(self, f, chunk_size):
        self.writer = Writer(f, chunk_size=chunk_size, compression=CompressionType.ZSTD)
        self.writer.start(profile="ros2", library=f"physics_node; mcap {mcap.__version__}")
        self.schemas, self.channels = {}, {}

    def channel(self, topic, msg_class, qos):
        if topic not in self.channels:
            name = type_name(msg_class)
            if name not in self.schemas:
                self.schemas[name] = self.writer.register_schema(name, "ros2msg", ros2msg_schema(msg_class).encode())
            self.channels[topic] = self.writer.register_channel(
                topic, "cdr", self.schemas[name], {"offered_qos_profiles": offered_qos_yaml(qos)}
            )
        return self.channels[topic]

    def add(self, channel_id, data, t, k):
        self.writer.add_message(channel_id=channel_id, log_time=t, data=data, publish_time=t, sequence=k)


def _mcap_session(path, payloads, chunk_size):
    topics = [f"/physics/{name}/odom" for name in BODIES]
    with open(path, "wb") as f:
        s = _McapSession(f, chunk_size)
        s.writer.add_metadata("physics_node", {"node": "/physics"})
        s.writer.flush()
        clock = s.channel("/clock", Clock, LATCHED)
        channels = [s.channel(topic, Odometry, STREAM) for topic in topics]
        for k, (t, clock_bytes, odom) in enumerate(payloads):
            s.add(clock, clock_bytes, t, k)
            for channel, data in zip(channels, odom):
                s.add(channel, data, t, k)
        s.writer.finish()
    return path


def _read(path):
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        messages = [(c.topic, m.log_time, m.publish_time, m.sequence, m.data) for _, c, m in reader.iter_messages()]
        one_topic = [m.sequence for _, _, m in reader.iter_messages(topics=["/physics/bb/odom"])]
    stats = summary.statistics
    counts = {summary.channels[c].topic: n for c, n in stats.channel_message_counts.items()}
    return messages, one_topic, counts, (stats.message_count, stats.message_start_time, stats.message_end_time)


@pytest.fixture
def mcap_level(monkeypatch):
    """mcap's Writer compresses at zstd's default level; the recorder too, for byte comparisons."""
    monkeypatch.setattr(chunk_writer, "ZSTD_LEVEL", 3)


@pytest.mark.parametrize("chunk_size", [1 << 20, 2000])  # one chunk; a chunk every few steps
def test_batched_writes_read_back_like_add_message(tmp_path, mcap_level, chunk_size):
    steps = 40
    payloads = _payloads(steps)
    batched = _read(_session(tmp_path / "batched.mcap", payloads, chunk_size))
    single = _read(_mcap_session(tmp_path / "single.mcap", payloads, chunk_size))
    assert batched == single
    messages, one_topic, counts, totals = batched
    assert len(messages) == steps * 4 and one_topic == list(range(steps))
    assert counts == {"/clock": steps, **{f"/physics/{n}/odom": steps for n in BODIES}}
    assert totals == (steps * 4, 0, 4_166_667 * (steps - 1))
    assert [m.sequence for m in Recording(tmp_path / "batched.mcap").messages()][:4] == [0, 0, 0, 0]
    if chunk_size > 100_000:  # one chunk: byte for byte the file mcap's Writer writes itself
        assert (tmp_path / "batched.mcap").read_bytes() == (tmp_path / "single.mcap").read_bytes()


@pytest.mark.parametrize("chunk_size", [1 << 20, 2000, 300])  # one chunk; every few steps; every message
def test_message_by_message_is_mcap_writers_file_byte_for_byte(tmp_path, mcap_level, chunk_size):
    payloads = _payloads(40)
    ours = _session(tmp_path / "ours.mcap", payloads, chunk_size, batched=False)
    theirs = _mcap_session(tmp_path / "theirs.mcap", payloads, chunk_size)
    assert Recording(ours).chunk_count == Recording(theirs).chunk_count
    assert ours.read_bytes() == theirs.read_bytes()


def test_a_channel_in_several_batches_of_a_chunk(tmp_path):
    """Index entries stay in the order the messages were added when a channel
    comes in batches of different shapes (a big batch, then alone, ...)."""
    payloads = _payloads(30)
    topics = [f"/physics/{name}/odom" for name in BODIES]

    def session(path):
        with Recorder(path, chunk_size=3000) as rec:
            channels = [rec.channel(topic, Odometry, STREAM) for topic in topics]
            for k, (t, _, odom) in enumerate(payloads):
                rec.write_many(channels, odom, t, k)
                if k % 3 == 0:
                    rec.write_many(channels[1:2], odom[1:2], t + 1, k)
                    rec.write_many(channels[::-1], odom[::-1], t + 2, k)
        return path

    def reference(path):
        with open(path, "wb") as f:
            s = _McapSession(f, 3000)
            channels = [s.channel(topic, Odometry, STREAM) for topic in topics]
            for k, (t, _, odom) in enumerate(payloads):
                batches = [(channels, odom, t)]
                if k % 3 == 0:
                    batches += [(channels[1:2], odom[1:2], t + 1), (channels[::-1], odom[::-1], t + 2)]
                for ids, datas, time_ns in batches:
                    for channel, data in zip(ids, datas):
                        s.add(channel, data, time_ns, k)
            s.writer.finish()
        return path

    batched = _read(session(tmp_path / "batched.mcap"))
    single = _read(reference(tmp_path / "single.mcap"))
    assert batched == single  # a batch is never split between chunks, but reads back the same
    assert batched[1] == [k for k in range(30) for _ in range(3 if k % 3 == 0 else 1)]


def test_large_scenes_get_larger_chunks():
    assert recorder_module.chunk_size_for(4) == recorder_module.CHUNK_SIZE
    assert recorder_module.chunk_size_for(1000) == 1000 * recorder_module.CHUNK_BYTES_PER_BODY
    assert recorder_module.chunk_size_for(10**6) == recorder_module.MAX_CHUNK_SIZE


# ---- a 100-body scene: the numpy packing path (batches of _SMALL_BATCH or more) ----
MANY = tuple(f"b{i}" for i in range(100))  # names of 2 and 3 characters: messages of two sizes


def _many_payloads(steps, names=MANY):
    out = []
    for k in range(steps):
        t = 4_166_667 * k
        odom = [serialize_message(odometry(name, [k, i, 0.5 * i], [1.0, 0, 0, 0], [0.1 * i, 0, 0], [0, 0, 0], t))
                for i, name in enumerate(names)]
        out.append((t, serialize_message(Clock(clock=time_msg(t))), odom))
    return out


def _many_session(path, payloads, chunk_size, wrap=bytes):
    """What the node writes each step: /clock alone (the small path), then
    every body's odometry in one write_many (the numpy path)."""
    assert len(MANY) >= recorder_module._SMALL_BATCH
    with Recorder(path, chunk_size=chunk_size, flush_period=math.inf) as rec:
        clock = rec.channel("/clock", Clock, LATCHED)
        channels = tuple(rec.channel(f"/physics/{name}/odom", Odometry, STREAM) for name in MANY)
        for k, (t, clock_bytes, odom) in enumerate(payloads):
            rec.write_many((clock,), (clock_bytes,), t, k)
            datas = [wrap(d) for d in odom]
            rec.write_many(channels, datas, t, k)
            for d in datas:  # the recorder keeps a copy of what is not bytes: changing ours changes nothing
                if isinstance(d, bytearray):
                    d[-1] ^= 0xFF
    return path


def _messages_per_chunk(path):
    """Message count of every chunk, in file order."""
    counts = []
    with open(path, "rb") as f:
        for record in StreamReader(f, skip_magic=False, emit_chunks=True).records:
            if isinstance(record, Chunk):
                counts.append(sum(isinstance(r, Message) for r in breakup_chunk(record)))
    return counts


def _many_reference(path, payloads, chunk_messages):
    """mcap's Writer, message by message, closing a chunk (`flush`) after the
    same messages as the recorder did (it closes only between batches)."""
    ends = set(itertools.accumulate(chunk_messages))
    written = 0
    with open(path, "wb") as f:
        s = _McapSession(f, 1 << 40)  # its own chunking off: it closes where told
        clock = s.channel("/clock", Clock, LATCHED)
        channels = [s.channel(f"/physics/{name}/odom", Odometry, STREAM) for name in MANY]
        for k, (t, clock_bytes, odom) in enumerate(payloads):
            for channel, data in [(clock, clock_bytes), *zip(channels, odom)]:
                s.add(channel, data, t, k)
                written += 1
                if written in ends:
                    s.writer.flush()
        s.writer.finish()
    return path


@pytest.mark.parametrize("chunk_size", [1 << 24, 20_000, 200_000])  # one chunk; every step; every few steps
def test_hundred_body_batches_are_mcap_writers_file_byte_for_byte(tmp_path, mcap_level, chunk_size):
    steps = 30
    payloads = _many_payloads(steps)
    ours = _many_session(tmp_path / "ours.mcap", payloads, chunk_size)
    chunks = _messages_per_chunk(ours)
    assert sum(chunks) == steps * (1 + len(MANY))
    if chunk_size < 1 << 24:
        # closed between batches only (after a step's /clock or after its odometry)
        assert len(chunks) > 3 and all(n % (1 + len(MANY)) in (0, 1) for n in itertools.accumulate(chunks))
    else:
        assert chunks == [steps * (1 + len(MANY))]
    theirs = _many_reference(tmp_path / "theirs.mcap", payloads, chunks)
    assert ours.read_bytes() == theirs.read_bytes()


def test_hundred_body_batches_read_back_through_mcaps_reader(tmp_path):
    """Whatever the zstd level and chunking, mcap's reader gets every message
    back with its channel, times, step and bytes, and the summary counts them."""
    steps = 12
    payloads = _many_payloads(steps)
    path = _many_session(tmp_path / "ours.mcap", payloads, 30_000, wrap=bytearray)
    with open(path, "rb") as f:
        reader = make_reader(f)
        got = [(c.topic, m.log_time, m.publish_time, m.sequence, m.data) for _, c, m in reader.iter_messages()]
        summary = reader.get_summary()
    want = []
    for k, (t, clock_bytes, odom) in enumerate(payloads):
        want.append(("/clock", t, t, k, clock_bytes))
        want += [(f"/physics/{name}/odom", t, t, k, data) for name, data in zip(MANY, odom)]
    assert got == want
    stats = summary.statistics
    assert stats.message_count == steps * (1 + len(MANY))
    assert set(stats.channel_message_counts.values()) == {steps}
    assert (stats.message_start_time, stats.message_end_time) == (0, payloads[-1][0])
    assert stats.chunk_count == len(summary.chunk_indexes) > 1
    # each chunk's index finds its messages: one body's odometry, read on its own
    with open(path, "rb") as f:
        one = [m.sequence for _, _, m in make_reader(f).iter_messages(topics=["/physics/b57/odom"])]
    assert one == list(range(steps))
