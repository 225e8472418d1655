"""The file side of a recording: everything that reaches the disk, written
in the order it was submitted, on one writer thread.

The recorder builds each chunk's records in memory on the calling thread and
hands the finished chunk over; this thread compresses it (zstd), computes its
CRC, writes the Chunk record and its MessageIndex records, keeps the offsets
the summary needs, and pushes the file to the OS after every chunk. zstd and
zlib.crc32 release the GIL on large buffers, so this runs alongside the
caller's own work.

The queue between them is bounded: when the disk or the compressor falls
behind, `submit` blocks (back-pressure) rather than dropping data or growing
without bound. An exception raised while writing is kept in `error`; later
jobs are skipped (the file can no longer be completed), and the recorder
raises the error to its caller.

`McapFile` holds the byte layout; it writes the records mcap's own `Writer`
writes, in the same order, so given the same sequence of calls a threaded
and an inline `ChunkWriter` write the same bytes.
"""

import queue
import struct
import threading
import time
import zlib

import numpy as np
import zstandard
from mcap.data_stream import RecordBuilder
from mcap.opcode import Opcode
from mcap.records import (
    Attachment,
    AttachmentIndex,
    ChunkIndex,
    DataEnd,
    Footer,
    Header,
    Metadata,
    MetadataIndex,
    SummaryOffset,
)
from mcap.writer import MCAP0_MAGIC

# zstd level 1: on the node's pose and contact streams it compresses as well
# as mcap's default level 3 (ratio 1.28 for both on a 1000-body chunk) at
# about 1.5x the speed; see benchmarks/recording_cost.py.
ZSTD_LEVEL = 1
# Finished chunks (and other jobs) waiting for the writer thread.
QUEUE_JOBS = 4

_CHUNK_HEAD = struct.Struct("<BQQQQI")  # opcode, length, start, end, uncompressed size, crc
_ZSTD = b"zstd"


class ChunkJob:
    """A finished chunk as the calling thread built it: its records (a list
    of bytes objects, in order, no longer appended to), its time range, and per batch of messages
    (channel ids, their offsets in the chunk, log time), plus the channels in
    the order they first appear in the chunk."""

    __slots__ = ("parts", "start_time", "end_time", "log", "channels")

    def __init__(self, parts, start_time, end_time, log, channels):
        self.parts, self.start_time, self.end_time = parts, start_time, end_time
        self.log, self.channels = log, channels


def message_index_records(job):
    """channel id -> packed MessageIndex record: its (log time, offset)
    entries in the order the messages were added."""
    log = job.log
    channels = np.concatenate([c for c, _, _ in log])
    entries = np.empty((len(channels), 2), dtype="<u8")
    entries[:, 0] = np.concatenate([np.full(len(c), t, dtype=np.uint64) for c, _, t in log])
    entries[:, 1] = np.concatenate([np.asarray(o, dtype=np.int64) for _, o, _ in log])
    order = np.argsort(channels, kind="stable")
    channels, entries = channels[order], entries[order]
    ids, starts = np.unique(channels, return_index=True)
    ends = np.append(starts[1:], len(channels))
    records = {}
    for c, a, b in zip(ids.tolist(), starts.tolist(), ends.tolist()):
        body = entries[a:b].tobytes()
        records[c] = struct.pack("<BQHI", Opcode.MESSAGE_INDEX, 6 + len(body), c, len(body)) + body
    return records


class McapFile:
    """Writes MCAP records to a binary file object in the order its methods
    are called, and the summary at `finish`. Not thread-safe: one caller."""

    def __init__(self, f, level=ZSTD_LEVEL):
        self._f = f
        self._compressor = zstandard.ZstdCompressor(level=level)
        self._records = RecordBuilder()
        self._offset = 0
        self._chunk_indexes = []
        self._attachment_indexes = []
        self._metadata_indexes = []

    def _emit(self, data):
        self._f.write(data)
        self._offset += len(data)

    def _emit_records(self):
        self._emit(self._records.end())

    def start(self, profile, library):
        self._emit(MCAP0_MAGIC)
        Header(profile, library).write(self._records)
        self._emit_records()
        self._f.flush()

    def attachment(self, name, media_type, data, create_time, log_time):
        offset = self._offset
        Attachment(create_time=create_time, log_time=log_time, name=name, media_type=media_type, data=data).write(
            self._records
        )
        length = self._records.count
        self._emit_records()
        self._attachment_indexes.append(
            AttachmentIndex(
                offset=offset,
                length=length,
                create_time=create_time,
                log_time=log_time,
                data_size=len(data),
                name=name,
                media_type=media_type,
            )
        )

    def metadata(self, name, values):
        offset = self._offset
        Metadata(name=name, metadata=values).write(self._records)
        length = self._records.count
        self._emit_records()
        self._metadata_indexes.append(MetadataIndex(offset=offset, length=length, name=name))

    def chunk(self, job):
        """The Chunk record, then its MessageIndex records; then the file is
        pushed to the OS, so a process killed after this keeps the chunk."""
        data = b"".join(job.parts)  # releases the GIL when large, as do zstd and crc32
        job.parts = None
        size = len(data)
        compressed = self._compressor.compress(data)
        crc = zlib.crc32(data)
        del data
        body = 8 + 8 + 8 + 4 + 4 + len(_ZSTD) + 8 + len(compressed)
        head = _CHUNK_HEAD.pack(Opcode.CHUNK, body, job.start_time, job.end_time, size, crc)
        head += struct.pack("<I", len(_ZSTD)) + _ZSTD + struct.pack("<Q", len(compressed))
        chunk_start = self._offset
        self._emit(head)
        self._emit(compressed)
        index_start = self._offset
        records = message_index_records(job)
        offsets, at, parts = {}, index_start, []
        for channel_id in job.channels:
            record = records[channel_id]
            offsets[channel_id] = at
            at += len(record)
            parts.append(record)
        self._emit(b"".join(parts))
        self._chunk_indexes.append(
            ChunkIndex(
                message_start_time=job.start_time,
                message_end_time=job.end_time,
                chunk_start_offset=chunk_start,
                chunk_length=len(head) + len(compressed),
                message_index_offsets=offsets,
                message_index_length=at - index_start,
                compression="zstd",
                compressed_size=len(compressed),
                uncompressed_size=size,
            )
        )
        self._f.flush()

    def flush(self):
        self._f.flush()

    def finish(self, schemas, channels, statistics):
        """DataEnd, the summary (schemas, channels, statistics, chunk,
        attachment and metadata indexes, summary offsets), footer, magic."""
        DataEnd(0).write(self._records)
        self._emit_records()
        summary_start = self._offset
        summary = RecordBuilder()
        offsets = []

        def group(opcode, records):
            start = summary.count
            for record in records:
                record.write(summary)
            offsets.append(
                SummaryOffset(group_opcode=opcode, group_start=summary_start + start, group_length=summary.count - start)
            )

        group(Opcode.SCHEMA, schemas)
        group(Opcode.CHANNEL, channels)
        group(Opcode.STATISTICS, [statistics])
        group(Opcode.CHUNK_INDEX, self._chunk_indexes)
        group(Opcode.ATTACHMENT_INDEX, self._attachment_indexes)
        group(Opcode.METADATA_INDEX, self._metadata_indexes)
        summary_offset_start = summary_start + summary.count
        for offset in offsets:
            offset.write(summary)
        summary_data = summary.end()
        summary_crc = zlib.crc32(summary_data)
        footer_start = 0 if not summary_data else summary_start
        summary_crc = zlib.crc32(
            struct.pack("<BQQQ", Opcode.FOOTER, 8 + 8 + 4, footer_start, summary_offset_start), summary_crc
        )
        self._emit(summary_data)
        Footer(summary_start=footer_start, summary_offset_start=summary_offset_start, summary_crc=summary_crc).write(
            self._records
        )
        self._emit_records()
        self._emit(MCAP0_MAGIC)
        self._f.flush()


class ChunkWriter:
    """Runs an `McapFile`'s methods, in submission order, on one writer
    thread (or inline, with `threaded=False`, which writes the same bytes).
    Owns the file object and closes it in `close`."""

    def __init__(self, f, *, level=ZSTD_LEVEL, threaded=True, queue_jobs=QUEUE_JOBS):
        self._file_object = f
        self._file = McapFile(f, level)
        self.error = None  # the first exception raised while writing
        self.cpu_seconds = 0.0  # CPU time spent writing (thread CPU time when threaded)
        self._closed = False
        self._queue = self._thread = None
        if threaded:
            self._queue = queue.Queue(maxsize=queue_jobs)
            self._thread = threading.Thread(target=self._run, name="mcap-chunk-writer", daemon=True)
            self._thread.start()

    def submit(self, method, *args):
        """Run `McapFile.<method>(*args)` after everything submitted before;
        blocks while the queue is full."""
        if self._queue is None:
            self._call(method, args)
        else:
            self._queue.put((method, args))

    def _call(self, method, args):
        if self.error is not None:
            return  # the file is broken; what follows cannot be placed in it
        start = time.thread_time()
        try:
            getattr(self._file, method)(*args)
        except BaseException as exc:  # reported to the caller by the recorder
            self.error = exc
        finally:
            self.cpu_seconds += time.thread_time() - start

    def _run(self):
        q = self._queue
        while True:
            job = q.get()
            try:
                if job is None:
                    return
                self._call(*job)
            finally:
                q.task_done()

    def wait(self):
        """Block until every job submitted so far has been written."""
        if self._queue is not None:
            self._queue.join()

    def close(self):
        """Write what is queued, stop the thread, close the file. Idempotent."""
        if self._closed:
            return
        self._closed = True
        try:
            if self._thread is not None:
                self._queue.put(None)
                self._thread.join()
        finally:
            try:
                self._file_object.close()
            except BaseException as exc:
                if self.error is None:
                    self.error = exc
