"""Running a world for a simulated duration while timing its steps.

CPU time per simulated second is the best per-step time over the run's
chunks (perf_counter around world.step), divided by dt: as with `timeit`,
the minimum is the reproducible figure, since other load on the machine only
ever adds time. A run too short to time well is repeated from its initial
state until MIN_TIMED seconds have been timed.
"""
from dataclasses import dataclass
from time import perf_counter

MIN_TIMED = 0.2       # s of stepping timed at least, per measurement
CHUNKS = 20


@dataclass
class TimedRun:
    steps: int
    seconds_per_step: float
    seconds_per_sim_second: float
    wall: float


def run_for(world, duration, chunks=CHUNKS, min_timed=MIN_TIMED):
    """Step `world` to `duration` (s) and time it; returns (world at the end, TimedRun).

    The world is left at the end state of its last full run, so its error can
    be read after."""
    n = max(1, round(duration / world.dt))
    per_step, wall, timed = [], 0.0, 0.0
    while True:
        world.reset()
        done = 0
        size = max(1, n // chunks)
        while done < n:
            k = min(size, n - done)
            t0 = perf_counter()
            world.step(k)
            elapsed = perf_counter() - t0
            per_step.append(elapsed / k)
            done += k
            timed += elapsed
        wall += timed
        if timed >= min_timed:
            break
    sps = min(per_step)
    return world, TimedRun(steps=n, seconds_per_step=sps,
                           seconds_per_sim_second=sps / world.dt, wall=timed)
