"""Reading a session's MCAP back, including one cut short by a crash.

A file that was never closed has no footer or summary, so it is read as a
stream from the start: every record up to the last complete one is used and
the torn tail is ignored. `recover()` writes such a file out again complete,
for tools that need the summary (rosbags, Foxglove, `ros2 bag`).
"""

import io
import struct
from dataclasses import dataclass

from mcap.exceptions import McapError
from mcap.records import Attachment, Channel, Chunk, Footer, Header, Message, Metadata, Schema
from mcap.stream_reader import StreamReader
from mcap.writer import CompressionType, Writer

# What a torn tail can raise while being parsed or decompressed.
_TORN_TAIL = (McapError, struct.error, ValueError, EOFError, IndexError, RuntimeError)


@dataclass(frozen=True)
class RecordedMessage:
    topic: str
    type_name: str
    log_time: int  # sim time, ns
    sequence: int  # engine step index (see recorder.py)
    data: bytes  # CDR


class Recording:
    """A recording on disk (a path), or in memory (bytes: an MCAP attached to
    another, session_history.py). Construction reads its header, attachments
    and metadata; `messages()` streams the messages in file order."""

    def __init__(self, path):
        self._data = bytes(path) if isinstance(path, (bytes, bytearray, memoryview)) else None
        self.path = "<attached MCAP>" if self._data is not None else str(path)
        self.profile = None
        self.library = None
        self.attachments = []
        self.metadata = {}
        self.complete = False
        self.problem = None  # why reading stopped early, if it did
        self.chunk_count = 0
        self.channels = {}  # topic -> mcap Channel record, filled while messages() runs
        self._scan()

    def _records(self, emit_chunks):
        with io.BytesIO(self._data) if self._data is not None else open(self.path, "rb") as f:
            reader = StreamReader(f, emit_chunks=emit_chunks, validate_crcs=not emit_chunks)
            try:
                for record in reader.records:
                    yield record
            except _TORN_TAIL as exc:
                self.problem = f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__

    def _scan(self):
        for record in self._records(emit_chunks=True):
            if isinstance(record, Header):
                self.profile, self.library = record.profile, record.library
            elif isinstance(record, Attachment):
                self.attachments.append(record)
            elif isinstance(record, Metadata):
                self.metadata[record.name] = dict(record.metadata)
            elif isinstance(record, Chunk):
                self.chunk_count += 1
            elif isinstance(record, Footer):
                self.complete = True
        if self.profile is None:
            raise ValueError(f"{self.path}: not an MCAP file ({self.problem or 'no header'})")

    def attachment(self, media_type=None, name=None):
        """The first attachment matching the given media type and/or name."""
        for a in self.attachments:
            if (media_type is None or a.media_type == media_type) and (name is None or a.name == name):
                return a
        return None

    def raw_records(self):
        """Schemas, channels and messages as MCAP records, in file order."""
        for record in self._records(emit_chunks=False):
            if isinstance(record, (Schema, Channel, Message)):
                yield record

    def messages(self):
        """Every complete message, in the order it was written."""
        schemas, channels = {}, {}
        for record in self.raw_records():
            if isinstance(record, Schema):
                schemas[record.id] = record.name
            elif isinstance(record, Channel):
                channels[record.id] = (record.topic, schemas.get(record.schema_id, ""))
                self.channels.setdefault(record.topic, record)
            else:
                topic, type_name = channels[record.channel_id]
                yield RecordedMessage(topic, type_name, record.log_time, record.sequence, record.data)

    def topics(self):
        """{topic: type name} of every channel with at least one readable message."""
        found = {}
        for m in self.messages():
            found.setdefault(m.topic, m.type_name)
        return found


def recover(src, dst):
    """Write the readable part of `src` to `dst` as a complete MCAP file.
    Returns the number of messages copied."""
    rec = Recording(src)
    count = 0
    with open(dst, "wb") as f:
        writer = Writer(f, compression=CompressionType.ZSTD)
        writer.start(profile=rec.profile, library=rec.library or "")
        for a in rec.attachments:
            writer.add_attachment(a.create_time, a.log_time, a.name, a.media_type, a.data)
        for name, values in rec.metadata.items():
            writer.add_metadata(name, values)
        schema_ids, channel_ids = {}, {}
        for record in rec.raw_records():
            if isinstance(record, Schema):
                if record.id not in schema_ids:
                    schema_ids[record.id] = writer.register_schema(record.name, record.encoding, record.data)
            elif isinstance(record, Channel):
                if record.id not in channel_ids:
                    channel_ids[record.id] = writer.register_channel(
                        record.topic, record.message_encoding, schema_ids.get(record.schema_id, 0), record.metadata
                    )
            else:
                writer.add_message(
                    channel_ids[record.channel_id], record.log_time, record.data, record.publish_time, record.sequence
                )
                count += 1
        writer.finish()
    return count
