"""The moments a render shows, taken from a scene stepped by the engine or
from a recording read back.

A frame at time τ shows the last state at or before τ, as a player would:
the step `floor(τ / dt)` of a scene, the last recorded `~/poses` of a
recording. Contact events between two frames are not lost: a frame shows
every `begin` and `end` event since the previous frame, and the `persist`
events of its own step.
"""

from dataclasses import dataclass

import numpy as np

from physics_core.contact_events import PERSIST

from .shapes import Shapes

NS_PER_S = 1_000_000_000


@dataclass
class Frame:
    time: float  # s, the moment asked for (playback time: after a reset, it counts on)
    sim_time: float  # s, the sim time of the state shown
    step: int  # engine step index of the state shown
    pos: np.ndarray  # (n, 3) m
    quat: np.ndarray  # (n, 4) w, x, y, z
    contact_point: np.ndarray  # (k, 3) m
    contact_normal: np.ndarray  # (k, 3) unit
    contact_event: np.ndarray  # (k,) 0 begin, 1 persist, 2 end
    shapes: Shapes
    part: int = 0  # resets before this frame (a recording's; 0 for a scene)


def frame_times(fps, duration=None, at=None, start=0.0):
    """Frame times in ns: one at `at`, or every 1/fps from `start` over
    `duration` seconds, both ends included (3 s at 25 fps: 76 frames).
    With neither, an endless sequence (a recording stops it)."""
    if at is not None:
        if not (np.isfinite(at) and at >= 0):
            raise ValueError(f"--at must be a time >= 0 s, got {at}")
        yield int(round(at * NS_PER_S))
        return
    if not (np.isfinite(fps) and fps > 0):
        raise ValueError(f"--fps must be > 0, got {fps}")
    count = None
    if duration is not None:
        if not (np.isfinite(duration) and duration >= 0):
            raise ValueError(f"--duration must be a time >= 0 s, got {duration}")
        count = int(np.floor(duration * fps + 1e-9)) + 1
    k = 0
    while count is None or k < count:
        yield int(round((start + k / fps) * NS_PER_S))
        k += 1


def step_at(time_ns, dt):
    """The last step at or before `time_ns` (a nanosecond of slack: frame times are rounded to ns)."""
    return int(np.floor((time_ns + 1) / NS_PER_S / dt))


class _ContactWindow:
    """Contact events a frame shows: every event of the step it shows, and the
    begins and ends of the earlier steps within its span (the time since the
    previous frame; none for a still), each shown once."""

    def __init__(self):
        self._earlier = []
        self._latest = None  # (point, normal, event) of the last step added
        self._latest_counts = False  # within the next frame's span and not yet shown

    def add(self, point, normal, event, in_span=True):
        if self._latest is not None and self._latest_counts:
            p, n, e = self._latest
            keep = e != PERSIST
            if keep.any():
                self._earlier.append((p[keep], n[keep], e[keep]))
        self._latest = (np.asarray(point), np.asarray(normal), np.asarray(event, dtype=np.uint8))
        self._latest_counts = bool(in_span)

    def take(self):
        parts = list(self._earlier)
        if self._latest is not None:
            parts.append(self._latest)
        self._earlier, self._latest_counts = [], False
        if not parts:
            return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, dtype=np.uint8)
        return tuple(np.concatenate([p[i] for p in parts]) for i in range(3))


def scene_frames(world, times_ns, span_ns=0):
    """Frames of `world` stepped from its current state, one per time;
    `span_ns` is how far back a frame's begin and end events reach (the
    frame period; 0 for a still)."""
    shapes = Shapes.from_model(world.model)
    window = _ContactWindow()
    for t in times_ns:
        target = step_at(t, world.model.dt)
        if target < world.step_index:
            raise ValueError(f"frame times must not go back ({t / NS_PER_S:g} s is before step {world.step_index})")
        while world.step_index < target:
            world.step()
            c = world.contacts
            window.add(c.point, c.normal, c.event, in_span=round(world.time * NS_PER_S) > t - span_ns)
        if world.model is not None and len(world.model.names) != len(shapes):
            shapes = Shapes.from_model(world.model)
        point, normal, event = window.take()
        yield Frame(
            t / NS_PER_S, world.time, world.step_index, world.state.pos.copy(), world.state.quat.copy(),
            point, normal, event, shapes,
        )
