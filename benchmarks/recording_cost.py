"""What recording costs the node per step: `Recorder.write_many` of one
step's /clock, PoseArray and contact PointCloud2 (real CDR bytes from the
`msg_adapters.cdr` builders), for 100 and 1000 bodies, with the chunk size
the node uses for that many bodies.

Columns, per step, averaged over every step of the run (chunk boundaries
included; `close()` is shown separately):

- calling thread: wall time spent inside `write_many` (what the step pays,
  including any wait on a full chunk queue) and CPU time of that thread;
- total CPU: CPU time of the whole process over the run and `close()`
  (calling thread plus the chunk writer thread), i.e. the work recording
  does, wherever it runs.

A second table compresses one chunk of the 1000-body stream with each zstd
level: ratio and speed.

Run: `python -m benchmarks.recording_cost [--steps-100 N] [--steps-1000 N]`.
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
from physics_node import recorder as recorder_module
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


def measure(bodies, steps, directory):
    """One recorded run; returns a row dict (µs per step unless named otherwise)."""
    stream = scene_stream(bodies, steps)
    path = os.path.join(directory, f"cost-{bodies}.mcap")
    rec = Recorder(path, chunk_size=chunk_size_for(bodies)).open()
    ids = [
        rec.channel("/clock", Clock, LATCHED),
        rec.channel("/physics/poses", PoseArray, STREAM),
        rec.channel("/physics/contacts", PointCloud2, STREAM),
    ]
    write_many = rec.write_many
    wall = 0.0
    worst = 0.0
    cpu0, thread0 = time.process_time(), time.thread_time()
    for step, (t, datas) in enumerate(stream):
        a = time.perf_counter()
        write_many(ids, datas, t, step)
        b = time.perf_counter() - a
        wall += b
        worst = max(worst, b)
    thread_cpu = time.thread_time() - thread0
    a = time.perf_counter()
    rec.close()
    close_s = time.perf_counter() - a
    total_cpu = time.process_time() - cpu0
    raw = sum(len(d) for _, datas in stream for d in datas)
    size = os.path.getsize(path)
    os.remove(path)
    return {
        "bodies": bodies,
        "steps": steps,
        "bytes_per_step": raw / steps,
        "call_wall_us": 1e6 * wall / steps,
        "call_max_us": 1e6 * worst,
        "call_cpu_us": 1e6 * thread_cpu / steps,
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
    level = getattr(recorder_module, "ZSTD_LEVEL", 3)
    head = ["bodies", "bytes/step", "calling thread µs/step", "worst call µs", "calling thread CPU µs/step",
            "total CPU µs/step", "close ms", "ratio"]
    body = [
        [r["bodies"], f"{r['bytes_per_step']:.0f}", f"{r['call_wall_us']:.1f}", f"{r['call_max_us']:.0f}",
         f"{r['call_cpu_us']:.1f}", f"{r['total_cpu_us']:.1f}", f"{r['close_ms']:.1f}", f"{r['ratio']:.2f}"]
        for r in rows
    ]
    text = f"## Recording cost per step (zstd level {level})\n\n" + table(head, body)
    text += "\n## zstd levels on one 1000-body chunk\n\n"
    text += table(["level", "ratio", "MB/s", "ms per chunk"],
                  [[r["level"], f"{r['ratio']:.2f}", f"{r['mb_per_s']:.0f}", f"{r['ms']:.1f}"] for r in levels])
    return text


def run(steps_100=3000, steps_1000=600):
    with tempfile.TemporaryDirectory() as directory:
        rows = [measure(100, steps_100, directory), measure(1000, steps_1000, directory)]
    return rows, zstd_levels()


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps-100", type=int, default=3000)
    parser.add_argument("--steps-1000", type=int, default=600)
    args = parser.parse_args(argv)
    rows, levels = run(args.steps_100, args.steps_1000)
    print(markdown(rows, levels))


if __name__ == "__main__":
    main()
