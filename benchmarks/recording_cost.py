"""What recording costs the node per step: `Recorder.write_many` of one
step's /clock, PoseArray and contact PointCloud2 (real CDR bytes from the
`msg_adapters.cdr` builders), for 100 and 1000 bodies, with the chunk size
the node uses for that many bodies.

Each size runs twice: steps back to back (what the recorder can sustain),
and with one dt of the node's own work between steps (1 ms for 100 bodies,
4.167 ms for 1000: a busy loop holding the GIL, as the node's Python code
does). Columns, per step, averaged over every step of the run (chunk
boundaries included; `close()` is shown separately):

- calling thread: wall time spent inside `write_many` (what the step pays,
  including any wait on a full chunk queue) and CPU time of that thread;
- total CPU: CPU time of the whole process over the run and `close()`,
  less the simulated node work (so: the calling thread's recording plus
  the chunk writer thread), i.e. the work recording does, wherever it runs.

On a shared machine the wall times after a busy loop include cold caches
(a trivial call can take 20 µs instead of 1 µs there); compare the CPU
columns across versions as well.

A second table compresses one chunk of the 1000-body stream with each zstd
level: ratio and speed.

Run: `python -m benchmarks.recording_cost [--steps SCALE]`.
"""

import argparse
import os
import tempfile
import time

import numpy as np
import zstandard
from geometry_msgs.msg import PoseArray
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import PointCloud2

from msg_adapters.cdr import ContactCloudCdr, PoseArrayCdr, clock_cdr
from msg_adapters.contacts import ContactArrays
from physics_node import chunk_writer
from physics_node.qos import LATCHED, STREAM
from physics_node.recorder import Recorder, chunk_size_for

from .markdown import table

DT_NS = 4_166_667  # 240 Hz
CONTACTS_PER_BODY = 0.6  # 64-byte points: about 40 bytes of cloud per body


def scene_stream(bodies, steps, seed=0):
    """Per step: (time ns, [clock, poses, contacts] CDR bytes), from bodies
    moving smoothly and resting on one another, as a running scene gives."""
    rng = np.random.default_rng(seed)
    poses, cloud = PoseArrayCdr(bodies), ContactCloudCdr()
    pos = rng.uniform(-5, 5, size=(bodies, 3))
    vel = rng.normal(scale=0.5, size=(bodies, 3))
    quat = rng.normal(size=(bodies, 4))
    quat /= np.linalg.norm(quat, axis=1, keepdims=True)
    spin = rng.normal(scale=0.01, size=(bodies, 4))
    k = int(CONTACTS_PER_BODY * bodies)
    body_a = rng.integers(0, bodies, size=k)
    body_b = rng.integers(0, bodies, size=k)
    normal = np.tile([0.0, 0.0, 1.0], (k, 1))
    dt = DT_NS * 1e-9
    out = []
    for step in range(steps):
        t = step * DT_NS
        vel[:, 2] -= 9.81 * dt
        pos += vel * dt
        quat += spin * dt
        quat /= np.linalg.norm(quat, axis=1, keepdims=True)
        contacts = ContactArrays(
            point=pos[body_a] + np.array([0.0, 0.0, -0.1]),
            normal=normal,
            impulse=9.81 * dt * (1.0 + 0.01 * rng.standard_normal(k)),
            friction_impulse=0.1 * dt * rng.random(k),
            normal_speed=0.001 * rng.standard_normal(k),
            body_a=body_a,
            body_b=body_b,
            event=np.ones(k, dtype=np.int64),
        )
        out.append((t, [clock_cdr(t), poses.build(pos, quat, t), cloud.build(contacts, t)]))
    return out


def busy(seconds):
    """The node's own work between two steps' recording, holding the GIL as
    its Python code does."""
    end = time.perf_counter() + seconds
    while time.perf_counter() < end:
        pass


def measure(bodies, steps, directory, work_us=0.0):
    """One recorded run, with `work_us` of the node's own work between
    steps; returns a row dict (µs per step unless named otherwise)."""
    stream = scene_stream(bodies, steps)
    path = os.path.join(directory, f"cost-{bodies}.mcap")
    rec = Recorder(path, chunk_size=chunk_size_for(bodies)).open()
    ids = [
        rec.channel("/clock", Clock, LATCHED),
        rec.channel("/physics/poses", PoseArray, STREAM),
        rec.channel("/physics/contacts", PointCloud2, STREAM),
    ]
    write_many, clock, thread_clock = rec.write_many, time.perf_counter, time.thread_time
    wall = call_cpu = worst = 0.0
    work = work_us * 1e-6
    cpu0, thread0 = time.process_time(), thread_clock()
    for step, (t, datas) in enumerate(stream):
        c, a = thread_clock(), clock()
        write_many(ids, datas, t, step)
        b = clock() - a
        call_cpu += thread_clock() - c
        wall += b
        worst = max(worst, b)
        if work:
            busy(work)
    work_cpu = thread_clock() - thread0 - call_cpu
    a = clock()
    rec.close()
    close_s = clock() - a
    total_cpu = time.process_time() - cpu0 - work_cpu
    raw = sum(len(d) for _, datas in stream for d in datas)
    size = os.path.getsize(path)
    os.remove(path)
    return {
        "bodies": bodies,
        "work_us": work_us,
        "steps": steps,
        "bytes_per_step": raw / steps,
        "call_wall_us": 1e6 * wall / steps,
        "call_max_us": 1e6 * worst,
        "call_cpu_us": 1e6 * call_cpu / steps,
        "total_cpu_us": 1e6 * total_cpu / steps,
        "close_ms": 1e3 * close_s,
        "ratio": raw / size,
    }


def zstd_levels(bodies=1000, levels=(-3, -1, 1, 2, 3, 5)):
    """Compress one chunk's worth of the stream at each level."""
    chunk = chunk_size_for(bodies)
    steps = 1 + chunk // sum(len(d) for d in scene_stream(bodies, 1)[0][1])
    stream = scene_stream(bodies, steps, seed=1)
    data = b"".join(d for _, datas in stream for d in datas)[:chunk]
    rows = []
    for level in levels:
        compressor = zstandard.ZstdCompressor(level=level)
        best = float("inf")
        for _ in range(3):
            a = time.perf_counter()
            out = compressor.compress(data)
            best = min(best, time.perf_counter() - a)
        rows.append({"level": level, "ratio": len(data) / len(out), "mb_per_s": len(data) / best / 1e6, "ms": 1e3 * best})
    return rows


def markdown(rows, levels):
    level = chunk_writer.ZSTD_LEVEL
    head = ["bodies", "node work µs/step", "bytes/step", "calling thread µs/step", "worst call µs", "calling thread CPU µs/step",
            "total CPU µs/step", "close ms", "ratio"]
    body = [
        [r["bodies"], f"{r['work_us']:.0f}", f"{r['bytes_per_step']:.0f}", f"{r['call_wall_us']:.1f}", f"{r['call_max_us']:.0f}",
         f"{r['call_cpu_us']:.1f}", f"{r['total_cpu_us']:.1f}", f"{r['close_ms']:.1f}", f"{r['ratio']:.2f}"]
        for r in rows
    ]
    text = f"## Recording cost per step (zstd level {level})\n\n" + table(head, body)
    text += "\n## zstd levels on one 1000-body chunk\n\n"
    text += table(["level", "ratio", "MB/s", "ms per chunk"],
                  [[r["level"], f"{r['ratio']:.2f}", f"{r['mb_per_s']:.0f}", f"{r['ms']:.1f}"] for r in levels])
    return text


# (bodies, steps, node work per step in µs): back to back, and with a step
# of one dt of the node's targets (1 kHz for 100 bodies, 240 Hz for 1000).
CASES = ((100, 3000, 0.0), (100, 3000, 1000.0), (1000, 600, 0.0), (1000, 600, 4167.0))


def run(cases=CASES):
    with tempfile.TemporaryDirectory() as directory:
        rows = [measure(bodies, steps, directory, work) for bodies, steps, work in cases]
    return rows, zstd_levels()


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=float, default=1.0, help="scale the number of steps of every case")
    args = parser.parse_args(argv)
    rows, levels = run([(b, max(10, int(n * args.steps)), w) for b, n, w in CASES])
    print(markdown(rows, levels))


if __name__ == "__main__":
    main()
