"""One MCAP file per session, laid out as rosbag2 writes it.

Profile `ros2`; each channel carries its type's full `ros2msg` schema, `cdr`
message encoding and `offered_qos_profiles`. Log and publish times are sim
time in nanoseconds. The MCAP `sequence` field of every message holds the
engine step index it belongs to (for a command: the step that applied it;
for an output: the step that produced it), which is what exact replay keys
on.

Messages are written in zstd chunks. The calling thread only appends Message
records to the chunk in progress and keeps its index entries; a chunk that
has grown past `chunk_size` is handed, finished, to one writer thread
(`chunk_writer.py`) that compresses it, writes it with its message indexes
and pushes the file to the OS. So:

- Chunk boundaries depend only on what was written: a chunk closes after the
  `write`/`write_many` call that takes it past `chunk_size` (a batch is not
  split between chunks), and on `flush`, `add_attachment`, `add_metadata`.
  The time-based flush below is the one exception: it closes the chunk in
  progress after `flush_period` seconds of wall time, wherever the session
  is. Nothing depends on how fast the writer thread runs; the file's records
  are in the order a synchronous writer would write them.
- At least every `flush_period` seconds the chunk in progress is closed and
  queued, so a process killed outright loses at most that last chunk (and
  whatever was still queued: at most `QUEUE_JOBS` finished chunks, which
  `flush()` waits for). The file is pushed to the OS after every chunk, not
  fsynced: it survives the process dying, not the machine.
- If the writer falls behind, the queue fills and the calling thread blocks.
- An error while writing (a full disk) is raised, as RecorderError with the
  original as its cause, from the next `write`, `write_many`, `flush` or
  `close`; the writes after it raise too.
"""

import collections
import os
import struct
import time
import weakref

import mcap
import numpy as np
from mcap.data_stream import RecordBuilder
from mcap.opcode import Opcode
from mcap.records import Channel, Schema, Statistics

from msg_adapters.schema import ros2msg_schema, type_name

from . import chunk_writer
from .chunk_writer import ChunkJob, ChunkWriter
from .qos import STREAM, offered_qos_yaml

PROFILE = "ros2"
SCHEMA_ENCODING = "ros2msg"
MESSAGE_ENCODING = "cdr"

# Names of the records that make a recording self-contained.
SESSION_METADATA = "physics_node"
INTEGRATION_METADATA = "physics_integration"   # adaptive integration totals, written at close
SCENE_MEDIA_TYPE = "application/yaml"
# Control events (world resets) travel on this channel, relative to the
# node's fully qualified name, as std_msgs/String.
EVENTS_SUFFIX = "/events"
RESET_EVENT = "reset"
# "isolate a,b": bodies frozen at that step after their state went non-finite.
ISOLATE_EVENT = "isolate"

# Chunks are finished on a writer thread; False finishes them inline on the
# calling thread (same bytes; for comparison).
WRITER_THREAD = True

# A Message record up to its data: opcode, record length, channel id,
# sequence, log time, publish time (little endian, unpadded).
_MESSAGE_HEAD = np.dtype(
    [("opcode", "u1"), ("length", "<u8"), ("channel", "<u2"), ("sequence", "<u4"), ("log", "<u8"), ("publish", "<u8")]
)
_MESSAGE_HEAD_STRUCT = struct.Struct("<BQHIQQ")
_MESSAGE_HEAD_SIZE = _MESSAGE_HEAD.itemsize
_MESSAGE_FIELDS_BYTES = _MESSAGE_HEAD_SIZE - 9  # the record length counts what follows opcode and length
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


class _OpenChunk:
    """The chunk in progress: its records (schemas, channels, messages) and
    what its Chunk and MessageIndex records will need."""

    __slots__ = ("parts", "size", "num_messages", "start_time", "end_time", "log", "channels", "indexed")

    def __init__(self):
        self.parts = []  # the chunk's records, as bytes objects, joined by the writer
        self.size = 0
        self.num_messages = 0
        self.start_time = self.end_time = 0
        self.log = []  # (channel ids array, offsets in the chunk, log time) per batch
        self.channels = {}  # channel id -> None, in order of first message in this chunk
        self.indexed = set()  # batches of channel ids already in `channels`


class Recorder:
    """Writes one session. Use as a context manager; `close()` is idempotent
    and is what makes the file complete (summary, statistics, indexes).
    One thread calls it (the chunk writer thread is its own)."""

    def __init__(self, path, *, chunk_size=CHUNK_SIZE, flush_period=1.0, library="physics_node"):
        self.path = os.fspath(path)
        self._chunk_size = chunk_size
        self._flush_period = flush_period
        self._library = library
        self._sink = None  # ChunkWriter, while open
        self._stop_sink = None  # finalizer: drains and closes the sink if this object is dropped unclosed
        self._reported = None  # the writer error already raised to the caller
        self._chunk = None
        self._schemas = {}  # type name -> schema id
        self._schema_records = []
        self._channels = {}  # topic -> (channel id, type name)
        self._channel_records = []
        self._channel_ids = {}  # (topic, class) -> channel id, once checked
        self._channel_arrays = {}  # tuple of channel ids -> the same as an array
        self._batches = collections.Counter()  # tuple of channel ids -> batches written
        self._stats = None
        self._last_flush = 0.0
        self.message_count = 0

    # -- lifecycle -------------------------------------------------------
    def _open_file(self):
        return open(self.path, "wb")

    def open(self):
        if self._sink is not None:
            return self
        parent = os.path.dirname(os.path.abspath(self.path))
        os.makedirs(parent, exist_ok=True)
        sink = ChunkWriter(
            self._open_file(),
            threaded=WRITER_THREAD,
            level=chunk_writer.ZSTD_LEVEL,
            queue_jobs=chunk_writer.QUEUE_JOBS,
        )
        self._sink = sink
        self._stop_sink = weakref.finalize(self, sink.close)
        self._reported = None
        self._chunk = _OpenChunk()
        self._stats = Statistics(
            attachment_count=0,
            channel_count=0,
            channel_message_counts=collections.defaultdict(int),
            chunk_count=0,
            message_count=0,
            metadata_count=0,
            message_start_time=0,
            message_end_time=0,
            schema_count=0,
        )
        sink.submit("start", PROFILE, f"{self._library}; mcap {mcap.__version__}")
        self._last_flush = time.monotonic()
        return self

    def close(self):
        """Finish the file (summary and statistics) and close it, after the
        writer thread has written every queued chunk. Safe to call twice and
        from exit paths. Raises a writer error not yet raised elsewhere."""
        sink = self._sink
        if sink is None:
            return
        try:
            if sink.error is None:
                self._finish_chunk()
                self._settle_counts()
                sink.submit("finish", list(self._schema_records), list(self._channel_records), self._stats)
        finally:
            self._sink = self._chunk = None
            self._stop_sink()  # sink.close(): drain, join the thread, close the file
            self._writer_cpu = sink.cpu_seconds
        if sink.error is not None and sink.error is not self._reported:
            self._raise(sink)

    @property
    def is_open(self):
        return self._sink is not None

    @property
    def writer_cpu_seconds(self):
        """CPU time the writer thread has spent compressing and writing chunks."""
        sink = self._sink
        return sink.cpu_seconds if sink is not None else getattr(self, "_writer_cpu", 0.0)

    def __enter__(self):
        return self.open()

    def __exit__(self, *exc):
        self.close()
        return False

    # -- content ---------------------------------------------------------
    def add_attachment(self, name, data, media_type, time_ns=0):
        sink = self._require_open()
        sink.submit("attachment", name, media_type, bytes(data), time_ns, time_ns)
        self._stats.attachment_count += 1
        self._flush_async()

    def add_metadata(self, name, values):
        """Key-value strings, e.g. the session's parameters."""
        sink = self._require_open()
        sink.submit("metadata", name, {str(k): str(v) for k, v in values.items()})
        self._stats.metadata_count += 1
        self._flush_async()

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
            schema_id = len(self._schema_records) + 1
            schema = Schema(id=schema_id, data=ros2msg_schema(msg_class).encode(), encoding=SCHEMA_ENCODING, name=name)
            self._schema_records.append(schema)
            self._stats.schema_count += 1
            self._add_to_chunk(schema)
            self._schemas[name] = schema_id
        channel_id = len(self._channel_records) + 1
        channel = Channel(
            id=channel_id,
            topic=topic,
            message_encoding=MESSAGE_ENCODING,
            schema_id=schema_id,
            metadata={"offered_qos_profiles": offered_qos_yaml(qos)},
        )
        self._channel_records.append(channel)
        self._stats.channel_count += 1
        self._add_to_chunk(channel)
        self._channels[topic] = (channel_id, name)
        return channel_id

    def _add_to_chunk(self, record):
        """A Schema or Channel record, in the chunk in progress (as mcap's
        Writer places them)."""
        builder = RecordBuilder()
        record.write(builder)
        data = builder.end()
        chunk = self._chunk
        chunk.parts.append(data)
        chunk.size += len(data)
        if chunk.size > self._chunk_size:
            self._finish_chunk()

    def write(self, topic, msg_class, data, time_ns, step=0, qos=STREAM):
        """One CDR-serialized message at sim time `time_ns` of step `step`."""
        self.write_many((self.channel(topic, msg_class, qos),), (data,), time_ns, step)

    def write_many(self, channel_ids, datas, time_ns, step=0):
        """CDR-serialized messages that share a sim time and step (the
        outputs of one step), on channels from `channel`, in order."""
        sink = self._sink
        if sink is None or sink.error is not None:
            self._require_open()
        n = len(channel_ids)
        if n != len(datas):
            raise ValueError(f"{n} channels but {len(datas)} messages")
        time_ns, step = int(time_ns), int(step)
        if n:
            self._append(channel_ids, datas, n, time_ns, step)
            self.message_count += n
        if time.monotonic() - self._last_flush >= self._flush_period:
            self._flush_async()

    def _append(self, channel_ids, datas, n, time_ns, sequence):
        """Message records at one time and sequence number, written as
        `Writer.add_message` would write them one by one."""
        ids = channel_ids if type(channel_ids) is tuple else tuple(channel_ids)
        chunk = self._chunk
        channels = self._channel_arrays.get(ids)
        if channels is None:
            channels = self._channel_arrays[ids] = np.array(ids, dtype=np.uint16)
        parts = chunk.parts
        start = chunk.size
        if n < _SMALL_BATCH:  # numpy's fixed cost is more than packing a few headers
            pack, offsets, at = _MESSAGE_HEAD_STRUCT.pack, [], start
            for channel_id, data in zip(ids, datas):
                if type(data) is not bytes:  # kept until the writer joins the chunk: take a copy
                    data = bytes(data)
                size = len(data)
                offsets.append(at)
                parts.append(pack(Opcode.MESSAGE, _MESSAGE_FIELDS_BYTES + size, channel_id, sequence, time_ns, time_ns))
                parts.append(data)
                at += _MESSAGE_HEAD_SIZE + size
            chunk.size = at
        else:
            sizes = np.fromiter(map(len, datas), dtype=np.int64, count=n)
            heads = np.empty(n, dtype=_MESSAGE_HEAD)
            heads["opcode"] = Opcode.MESSAGE
            heads["length"] = _MESSAGE_FIELDS_BYTES + sizes
            heads["channel"] = channels
            heads["sequence"] = sequence
            heads["log"] = heads["publish"] = time_ns
            head_bytes, step = heads.tobytes(), _MESSAGE_HEAD_SIZE
            batch = [b""] * (2 * n)
            batch[0::2] = [head_bytes[i : i + step] for i in range(0, n * step, step)]
            batch[1::2] = [d if type(d) is bytes else bytes(d) for d in datas]
            parts += batch
            record_sizes = step + sizes
            offsets = start + np.cumsum(record_sizes) - record_sizes
            chunk.size = int(offsets[-1] + record_sizes[-1])
        chunk.log.append((channels, offsets, time_ns))
        if ids not in chunk.indexed:
            for channel_id in ids:
                chunk.channels.setdefault(channel_id)
            chunk.indexed.add(ids)
        self._batches[ids] += 1
        chunk.start_time, chunk.end_time = _widen(chunk.start_time, chunk.end_time, chunk.num_messages, time_ns)
        chunk.num_messages += n
        stats = self._stats
        stats.message_start_time, stats.message_end_time = _widen(
            stats.message_start_time, stats.message_end_time, stats.message_count, time_ns
        )
        stats.message_count += n
        if chunk.size > self._chunk_size:
            self._finish_chunk()

    def _finish_chunk(self):
        """Hand the chunk in progress, if it holds messages, to the writer."""
        chunk = self._chunk
        if chunk is None or chunk.num_messages == 0:
            return
        self._stats.chunk_count += 1
        self._chunk = _OpenChunk()
        job = ChunkJob(chunk.parts, chunk.start_time, chunk.end_time, chunk.log, list(chunk.channels))
        self._sink.submit("chunk", job)

    def _settle_counts(self):
        """Add the per-channel message counts to the statistics (in order of
        each channel's first message, as `Writer.add_message` counts)."""
        counts = self._stats.channel_message_counts
        for channel_ids, batches in self._batches.items():
            for channel_id in channel_ids:
                counts[channel_id] += batches
        self._batches.clear()

    def _flush_async(self):
        """Close the chunk in progress and have the writer push the file to
        the OS, without waiting for it."""
        self._finish_chunk()
        self._sink.submit("flush")
        self._last_flush = time.monotonic()

    def flush(self):
        """Close the chunk in progress and push everything to the OS: returns
        once the writer thread has written every chunk so far."""
        if self._sink is None:
            return
        self._require_open()
        self._flush_async()
        self._sink.wait()
        self._require_open()

    def _require_open(self):
        sink = self._sink
        if sink is None:
            raise RecorderError(f"recording {self.path} is not open")
        if sink.error is not None:
            self._raise(sink)
        return sink

    def _raise(self, sink):
        self._reported = sink.error
        raise RecorderError(f"recording {self.path}: writing failed: {sink.error!r}") from sink.error


def _widen(start, end, count, time_ns):
    """A (start, end) log-time range of `count` messages widened to hold
    `time_ns`; with no messages yet the range starts there."""
    if count == 0 or time_ns < start:
        start = time_ns
    return start, (time_ns if time_ns > end else end)
