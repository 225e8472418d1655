"""One MCAP file per session, laid out as rosbag2 writes it.

Profile `ros2`; each channel carries its type's full `ros2msg` schema, `cdr`
message encoding and `offered_qos_profiles`. Log and publish times are sim
time in nanoseconds. The MCAP `sequence` field of every message holds the
engine step index it belongs to (for a command: the step that applied it;
for an output: the step that produced it), which is what exact replay keys
on.

Messages are written in zstd chunks. The chunk in progress is closed and the
file flushed at least every `flush_period` seconds of wall time, so a
process killed outright loses at most that last chunk.
"""

import os
import struct
import time

import mcap
import numpy as np
from mcap.opcode import Opcode
from mcap.records import MessageIndex
from mcap.writer import CompressionType, Writer

from msg_adapters.schema import ros2msg_schema, type_name

from .qos import STREAM, offered_qos_yaml

PROFILE = "ros2"
SCHEMA_ENCODING = "ros2msg"
MESSAGE_ENCODING = "cdr"

# Names of the records that make a recording self-contained.
SESSION_METADATA = "physics_node"
SCENE_MEDIA_TYPE = "application/yaml"
# Control events (world resets) travel on this channel, relative to the
# node's fully qualified name, as std_msgs/String.
EVENTS_SUFFIX = "/events"
RESET_EVENT = "reset"


# A Message record up to its data: opcode, record length, channel id,
# sequence, log time, publish time (little endian, unpadded).
_MESSAGE_HEAD = np.dtype(
    [("opcode", "u1"), ("length", "<u8"), ("channel", "<u2"), ("sequence", "<u4"), ("log", "<u8"), ("publish", "<u8")]
)
_MESSAGE_HEAD_STRUCT = struct.Struct("<BQHIQQ")
_MESSAGE_FIELDS_BYTES = _MESSAGE_HEAD.itemsize - 9  # the record length counts what follows opcode and length
_SMALL_BATCH = 8


# Chunk size: 1 MiB, or room for about ten steps of a large scene, so that
# each channel's per-chunk MessageIndex record covers several messages (a
# scene of a thousand bodies writes a thousand odometry channels per step).
CHUNK_SIZE = 1 << 20
MAX_CHUNK_SIZE = 16 << 20
CHUNK_BYTES_PER_BODY = 10 << 10


def chunk_size_for(bodies):
    return int(min(MAX_CHUNK_SIZE, max(CHUNK_SIZE, CHUNK_BYTES_PER_BODY * int(bodies))))


class RecorderError(RuntimeError):
    pass


class _ChunkIndex(MessageIndex):
    """One channel's MessageIndex record for the chunk in progress; its
    entries are kept by the appender for all channels at once and packed
    when mcap's Writer writes the record (after the chunk)."""

    def __init__(self, channel_id, appender):  # the dataclass's fields, without its __init__'s cost
        self.channel_id, self.records, self._appender = channel_id, [], appender

    def write(self, stream):
        stream.write(self._appender.index_record(self.channel_id))


class _ChunkAppender:
    """Appends Message records to the chunk mcap's Writer is building, a
    step's messages at a time: their headers built with numpy, one write, and
    the chunk's message indexes and the writer's statistics kept as
    `Writer.add_message` keeps them (one record object and about twenty small
    writes per message otherwise). The records are the ones `add_message`
    writes; a batch is not split between chunks, so a chunk may close a few
    messages later than it would one message at a time.

    This relies on how mcap's Writer keeps its chunk; `attach` returns None
    when the installed mcap does not look that way, and the recorder then
    goes through `add_message`."""

    def __init__(self, builder, statistics, maybe_finalize):
        self._builder, self._statistics, self._maybe_finalize = builder, statistics, maybe_finalize
        self._channels = {}  # tuple of channel ids -> the same as an array
        # Messages per channel are counted per batch of channels and added to
        # the statistics in `settle`, before the summary is written.
        self._batches = {}
        self._new_chunk()

    def _new_chunk(self):
        self._log = []  # (channel ids, offsets in the chunk, log time) per batch
        self._indexed = set()  # batches whose channels have an index record in this chunk
        self._index = None  # channel id -> packed MessageIndex record, once the chunk is done

    @classmethod
    def attach(cls, writer):
        builder = getattr(writer, "_Writer__chunk_builder", None)
        statistics = getattr(writer, "_Writer__statistics", None)
        maybe_finalize = getattr(writer, "_Writer__maybe_finalize_chunk", None)
        record_writer = getattr(builder, "record_writer", None)
        chunk_fields = ("message_indices", "num_messages", "message_start_time", "message_end_time")
        statistics_fields = ("channel_message_counts", "message_count", "message_start_time", "message_end_time")
        needed = (
            all(hasattr(builder, a) for a in chunk_fields)
            and hasattr(getattr(record_writer, "_buffer", None), "write")
            and all(hasattr(statistics, a) for a in statistics_fields)
            and callable(maybe_finalize)
        )
        return cls(builder, statistics, maybe_finalize) if needed else None

    def add(self, channel_ids, datas, time_ns, sequence):
        """Message records at one time and sequence number; returns how many."""
        ids = tuple(channel_ids)
        n = len(ids)
        if not n:
            return 0
        builder, stats = self._builder, self._statistics
        if builder.num_messages == 0:  # the writer closed the last chunk (or none yet)
            self._new_chunk()
        channels = self._channels.get(ids)
        if channels is None:
            channels = self._channels[ids] = np.array(ids, dtype=np.uint16)
        buffer = builder.record_writer._buffer
        start = buffer.tell()
        if n < _SMALL_BATCH:  # numpy's fixed cost is more than packing a few headers
            pack, offsets, at, parts = _MESSAGE_HEAD_STRUCT.pack, [], start, []
            for channel_id, data in zip(ids, datas):
                size = len(data)
                offsets.append(at)
                head = pack(Opcode.MESSAGE, _MESSAGE_FIELDS_BYTES + size, channel_id, sequence, time_ns, time_ns)
                parts += (head, data)
                at += _MESSAGE_HEAD.itemsize + size
            offsets = np.array(offsets, dtype=np.int64)
        else:
            sizes = np.fromiter(map(len, datas), dtype=np.int64, count=n)
            heads = np.empty(n, dtype=_MESSAGE_HEAD)
            heads["opcode"] = Opcode.MESSAGE
            heads["length"] = _MESSAGE_FIELDS_BYTES + sizes
            heads["channel"] = channels
            heads["sequence"] = sequence
            heads["log"] = heads["publish"] = time_ns
            head_bytes, step = heads.tobytes(), _MESSAGE_HEAD.itemsize
            parts = [b""] * (2 * n)
            parts[0::2] = [head_bytes[i : i + step] for i in range(0, n * step, step)]
            parts[1::2] = datas
            record_sizes = step + sizes
            offsets = start + np.cumsum(record_sizes) - record_sizes
        buffer.write(b"".join(parts))
        self._log.append((channels, offsets, time_ns))
        if ids not in self._indexed:
            indices = builder.message_indices
            for channel_id in ids:
                if channel_id not in indices:
                    indices[channel_id] = _ChunkIndex(channel_id, self)
            self._indexed.add(ids)
        self._batches[ids] = self._batches.get(ids, 0) + 1
        if builder.num_messages == 0:
            builder.message_start_time = time_ns
        else:
            builder.message_start_time = min(builder.message_start_time, time_ns)
        builder.message_end_time = max(builder.message_end_time, time_ns)
        builder.num_messages += n
        if stats.message_count == 0:
            stats.message_start_time = time_ns
        else:
            stats.message_start_time = min(stats.message_start_time, time_ns)
        stats.message_end_time = max(stats.message_end_time, time_ns)
        stats.message_count += n
        self._maybe_finalize()
        return n

    def index_record(self, channel_id):
        """The MessageIndex record of `channel_id` for the chunk just closed:
        its (log time, offset) entries in the order the messages were added."""
        if self._index is None:
            channels = np.concatenate([c for c, _, _ in self._log])
            entries = np.empty((len(channels), 2), dtype="<u8")
            entries[:, 0] = np.concatenate([np.full(len(c), t, dtype=np.uint64) for c, _, t in self._log])
            entries[:, 1] = np.concatenate([o for _, o, _ in self._log])
            order = np.argsort(channels, kind="stable")
            channels, entries = channels[order], entries[order]
            ids, starts = np.unique(channels, return_index=True)
            ends = np.append(starts[1:], len(channels))
            self._index = {}
            for c, a, b in zip(ids.tolist(), starts.tolist(), ends.tolist()):
                body = entries[a:b].tobytes()
                self._index[c] = struct.pack("<BQHI", Opcode.MESSAGE_INDEX, 6 + len(body), c, len(body)) + body
        return self._index[channel_id]

    def settle(self):
        """Add the per-channel message counts to the writer's statistics."""
        counts = self._statistics.channel_message_counts
        for channel_ids, batches in self._batches.items():
            for channel_id in channel_ids:
                counts[channel_id] += batches
        self._batches.clear()


class Recorder:
    """Writes one session. Use as a context manager; `close()` is idempotent
    and is what makes the file complete (summary, statistics, indexes)."""

    def __init__(self, path, *, chunk_size=CHUNK_SIZE, flush_period=1.0, library="physics_node"):
        self.path = os.fspath(path)
        self._chunk_size = chunk_size
        self._flush_period = flush_period
        self._library = library
        self._file = None
        self._writer = None
        self._schemas = {}  # type name -> schema id
        self._channels = {}  # topic -> (channel id, type name)
        self._channel_ids = {}  # (topic, class) -> channel id, once checked
        self._appender = None
        self._last_flush = 0.0
        self.message_count = 0

    # -- lifecycle -------------------------------------------------------
    def open(self):
        if self._writer is not None:
            return self
        parent = os.path.dirname(os.path.abspath(self.path))
        os.makedirs(parent, exist_ok=True)
        self._file = open(self.path, "wb")
        self._writer = Writer(self._file, chunk_size=self._chunk_size, compression=CompressionType.ZSTD)
        self._writer.start(profile=PROFILE, library=f"{self._library}; mcap {mcap.__version__}")
        self._appender = _ChunkAppender.attach(self._writer)
        self._file.flush()
        self._last_flush = time.monotonic()
        return self

    def close(self):
        """Finish the file (summary and statistics) and close it. Safe to call
        twice and from exit paths."""
        writer, f, appender = self._writer, self._file, self._appender
        self._writer = self._file = self._appender = None
        if writer is None:
            return
        try:
            if appender is not None:
                appender.settle()
            writer.finish()
        finally:
            f.close()

    @property
    def is_open(self):
        return self._writer is not None

    def __enter__(self):
        return self.open()

    def __exit__(self, *exc):
        self.close()
        return False

    # -- content ---------------------------------------------------------
    def add_attachment(self, name, data, media_type, time_ns=0):
        self._require_open()
        self._writer.add_attachment(create_time=time_ns, log_time=time_ns, name=name, media_type=media_type, data=data)
        self.flush()

    def add_metadata(self, name, values):
        """Key-value strings, e.g. the session's parameters."""
        self._require_open()
        self._writer.add_metadata(name, {str(k): str(v) for k, v in values.items()})
        self.flush()

    def channel(self, topic, msg_class, qos=STREAM):
        """Channel id for `topic`, registering schema and channel the first
        time the topic is seen."""
        known_id = self._channel_ids.get((topic, msg_class))
        if known_id is not None:
            return known_id
        channel_id = self._register(topic, msg_class, qos)
        self._channel_ids[(topic, msg_class)] = channel_id
        return channel_id

    def _register(self, topic, msg_class, qos):
        known = self._channels.get(topic)
        name = type_name(msg_class)
        if known is not None:
            if known[1] != name:
                raise RecorderError(f"topic {topic} already recorded as {known[1]}, not {name}")
            return known[0]
        self._require_open()
        schema_id = self._schemas.get(name)
        if schema_id is None:
            schema_id = self._writer.register_schema(
                name=name, encoding=SCHEMA_ENCODING, data=ros2msg_schema(msg_class).encode()
            )
            self._schemas[name] = schema_id
        channel_id = self._writer.register_channel(
            topic=topic,
            message_encoding=MESSAGE_ENCODING,
            schema_id=schema_id,
            metadata={"offered_qos_profiles": offered_qos_yaml(qos)},
        )
        self._channels[topic] = (channel_id, name)
        return channel_id

    def write(self, topic, msg_class, data, time_ns, step=0, qos=STREAM):
        """One CDR-serialized message at sim time `time_ns` of step `step`."""
        self.write_many((self.channel(topic, msg_class, qos),), (data,), time_ns, step)

    def write_many(self, channel_ids, datas, time_ns, step=0):
        """CDR-serialized messages that share a sim time and step (the
        outputs of one step), on channels from `channel`, in order."""
        self._require_open()
        if len(channel_ids) != len(datas):
            raise ValueError(f"{len(channel_ids)} channels but {len(datas)} messages")
        time_ns, step = int(time_ns), int(step)
        if self._appender is not None:
            self.message_count += self._appender.add(channel_ids, datas, time_ns, step)
        else:
            for channel_id, data in zip(channel_ids, datas):
                self._writer.add_message(
                    channel_id=channel_id, log_time=time_ns, publish_time=time_ns, data=data, sequence=step
                )
                self.message_count += 1
        if time.monotonic() - self._last_flush >= self._flush_period:
            self.flush()

    def flush(self):
        """Close the chunk in progress and push everything to the OS."""
        if self._writer is None:
            return
        self._writer.flush()
        self._last_flush = time.monotonic()

    def _require_open(self):
        if self._writer is None:
            raise RecorderError(f"recording {self.path} is not open")
