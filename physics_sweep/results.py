"""Results written as they arrive, to Parquet, so an interrupted sweep keeps
what it finished and `--resume` goes on from there.

While a sweep runs, rows collect in memory up to `flush_rows` (or
`flush_seconds`) and are then written as one complete small Parquet file in
``OUT.parts/`` (a file lands whole: written to a temporary name, then
renamed). When the sweep ends — or stops on Ctrl-C — the rows of OUT (when
resuming) and of every part are streamed, one part at a time, into a new OUT
(again via a temporary name) and the parts are removed. A process killed
outright loses at most the rows not yet flushed; `--resume` then reads OUT
and the parts left behind, skips every run_id in them, and merges them all.
So memory holds at most one part's rows, never the whole sweep.

The file's schema metadata `physics_sweep` holds the plan's fingerprint; a
resume of a different sweep is refused.
"""
import glob
import json
import os
import time

import pyarrow as pa
import pyarrow.parquet as pq

from .design import SweepError

META_KEY = b"physics_sweep"
_TYPES = {"bool": pa.bool_(), "int": pa.int64(), "float": pa.float64(), "str": pa.string()}


def schema_for(plan):
    fields = [pa.field("run_id", pa.int64(), nullable=False), pa.field("seed", pa.int64())]
    fields += [pa.field(v.key, _TYPES[v.column_type()]) for v in plan.design.vary]
    fields += [pa.field(m, pa.float64()) for m in plan.measures]
    fields += [pa.field("steps", pa.int64()), pa.field("wall_s", pa.float64()),
               pa.field("cpu_s", pa.float64()), pa.field("engine_version", pa.string()),
               pa.field("worker", pa.string()), pa.field("error", pa.string())]
    meta = {META_KEY: json.dumps(plan.fingerprint(), sort_keys=True).encode()}
    return pa.schema(fields, metadata=meta)


class ResultsFile:
    """Rows in, Parquet out; `done` holds the run_ids already written (resume)."""

    def __init__(self, path, plan, *, resume=False, overwrite=False, flush_rows=256, flush_seconds=5.0):
        self.path = os.path.abspath(path)
        self.parts_dir = self.path + ".parts"
        self.schema = schema_for(plan)
        self.flush_rows, self.flush_seconds = flush_rows, flush_seconds
        self._rows, self._last_flush, self._part = [], time.monotonic(), 0
        self.done = set()
        self.failed = 0
        existing = self._existing_files()
        if existing and not (resume or overwrite):
            raise SweepError(f"--out {path}: results are already there ({', '.join(existing[:2])}); "
                             "--resume continues that sweep, --overwrite starts again")
        if overwrite and not resume:
            for f in existing:
                os.remove(f)
            existing = []
        for f in existing:
            self._read_done(f)
        os.makedirs(self.parts_dir, exist_ok=True)
        self._part = len(glob.glob(os.path.join(self.parts_dir, "part-*.parquet")))

    def _existing_files(self):
        parts = sorted(glob.glob(os.path.join(self.parts_dir, "part-*.parquet")))
        return ([self.path] if os.path.exists(self.path) else []) + parts

    def _read_done(self, f):
        try:
            pf = pq.ParquetFile(f)
        except (OSError, pa.ArrowInvalid) as e:
            raise SweepError(f"--resume: {f} is not a readable Parquet file ({e})") from None
        theirs = (pf.schema_arrow.metadata or {}).get(META_KEY)
        if theirs != self.schema.metadata[META_KEY]:
            raise SweepError(f"--resume: {f} holds a different sweep (scene, --vary, --seeds, --perturb, "
                             "--samples, --design-seed, --duration or --measure differ); use another --out")
        table = pf.read(columns=["run_id", "error"])
        self.done.update(table.column("run_id").to_pylist())
        self.failed += table.num_rows - table.column("error").null_count

    def add(self, rows):
        """Rows of runs not written yet are kept (a run returned twice counts once)."""
        added = 0
        for row in rows:
            if row["run_id"] in self.done:
                continue
            self.done.add(row["run_id"])
            self.failed += row["error"] is not None
            self._rows.append(row)
            added += 1
            if len(self._rows) >= self.flush_rows or time.monotonic() - self._last_flush > self.flush_seconds:
                self.flush()
        return added

    def flush(self):
        self._last_flush = time.monotonic()
        if not self._rows:
            return
        table = pa.Table.from_pylist(self._rows, schema=self.schema)
        name = os.path.join(self.parts_dir, f"part-{self._part:06d}.parquet")
        pq.write_table(table, name + ".tmp")
        os.replace(name + ".tmp", name)
        self._part += 1
        self._rows = []

    def close(self):
        """Flush, then stream OUT and the parts into a new OUT; returns its row count."""
        self.flush()
        sources = self._existing_files()
        if not sources:                # nothing ran (Ray unreachable, Ctrl-C at once): no empty file
            self._remove_parts_dir()
            return 0
        tmp = self.path + ".tmp"
        seen = set()      # a merge cut short after its rename leaves parts already in OUT
        with pq.ParquetWriter(tmp, self.schema) as writer:
            for f in sources:
                pf = pq.ParquetFile(f)
                for i in range(pf.num_row_groups):
                    table = pf.read_row_group(i).cast(self.schema)
                    ids = table.column("run_id").to_pylist()
                    keep = pa.array([r not in seen for r in ids])
                    seen.update(ids)
                    writer.write_table(table.filter(keep))
        os.replace(tmp, self.path)
        for f in sources[1 if sources and sources[0] == self.path else 0:]:
            os.remove(f)
        self._remove_parts_dir()
        return len(seen)

    def _remove_parts_dir(self):
        for f in glob.glob(os.path.join(self.parts_dir, "*.tmp")):
            os.remove(f)       # a part cut short by a kill
        if os.path.isdir(self.parts_dir) and not os.listdir(self.parts_dir):
            os.rmdir(self.parts_dir)
