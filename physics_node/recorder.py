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
import time

import mcap
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


class RecorderError(RuntimeError):
    pass


class Recorder:
    """Writes one session. Use as a context manager; `close()` is idempotent
    and is what makes the file complete (summary, statistics, indexes)."""

    def __init__(self, path, *, chunk_size=1 << 20, flush_period=1.0, library="physics_node"):
        self.path = os.fspath(path)
        self._chunk_size = chunk_size
        self._flush_period = flush_period
        self._library = library
        self._file = None
        self._writer = None
        self._schemas = {}  # type name -> schema id
        self._channels = {}  # topic -> (channel id, type name)
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
        self._file.flush()
        self._last_flush = time.monotonic()
        return self

    def close(self):
        """Finish the file (summary and statistics) and close it. Safe to call
        twice and from exit paths."""
        writer, f = self._writer, self._file
        self._writer = self._file = None
        if writer is None:
            return
        try:
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
        channel_id = self.channel(topic, msg_class, qos)
        self._require_open()
        self._writer.add_message(
            channel_id=channel_id, log_time=int(time_ns), publish_time=int(time_ns), data=data, sequence=int(step)
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
