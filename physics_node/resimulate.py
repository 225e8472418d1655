"""Exact replay: rebuild the world from a recording and check every pose.

The world is loaded from the scene attached to the recording; each recorded
command is submitted at the step index it was applied at (the message's
`sequence`), through the same `Stepper` the node uses. Every recorded
PoseArray is then compared with the recomputed state bit for bit.

A recording started mid-session (`record` set while the node ran) carries
the node's history since its last reset as an attached MCAP
(session_history.py); that is re-applied first, so the world reaches the
recording's first step exactly as the node had it.
"""

import json
import os
import re
import tempfile
import warnings
from dataclasses import dataclass, field

import numpy as np
from geometry_msgs.msg import PoseArray, WrenchStamped
from rclpy.serialization import deserialize_message
from std_msgs.msg import String

from msg_adapters import arrays_from_pose_array, wrench_arrays
from physics_core import CommandError, SceneError, load_scene
from physics_core.scene_limits import MAX_BODIES

from .commands import Command
from .recorder import EVENTS_SUFFIX, ISOLATE_EVENT, RESET_EVENT, SCENE_MEDIA_TYPE, SESSION_METADATA
from .resimulate_requests import ReplayedRequests
from .recording_reader import Recording
from .session_history import HISTORY_MEDIA_TYPE, HISTORY_NAME, HISTORY_STATE, STARTED_AT_STEP
from .stepping import Stepper

MATCH, DIVERGE, ERROR = 0, 1, 2  # also the exit status of `physics-replay --resimulate`


class ResimulationError(RuntimeError):
    pass


@dataclass
class Divergence:
    step: int
    time_ns: int
    body: str
    index: int
    recorded_position: np.ndarray
    recorded_orientation: np.ndarray  # w, x, y, z
    recomputed_position: np.ndarray
    recomputed_orientation: np.ndarray


@dataclass
class Result:
    status: int  # MATCH, DIVERGE or ERROR
    compared: int = 0  # pose messages compared
    last_step: int = 0
    commands: int = 0
    resets: int = 0
    requests: int = 0  # simulator-standard requests re-applied (spawn, delete, set state, reset, ...)
    complete_file: bool = True
    divergence: Divergence = None
    error: str = ""
    notes: list = field(default_factory=list)

    def report(self):
        tail = "" if self.complete_file else " (file not closed cleanly: checked up to its last complete chunk)"
        if self.status == ERROR:
            return f"error: {self.error}"
        if self.status == MATCH:
            return (
                f"match: all {self.compared} recorded pose sets up to step {self.last_step} are bit-identical "
                f"to the recomputed ones ({self.commands} commands, {self.requests} simulator requests re-applied, "
                f"{self.resets} resets){tail}"
            )
        d = self.divergence
        with np.printoptions(precision=17):
            return (
                f"diverge: first difference at step {d.step} (t = {d.time_ns / 1e9:.9f} s), "
                f"body {d.body!r} (index {d.index})\n"
                f"  recorded   position {d.recorded_position} orientation (w,x,y,z) {d.recorded_orientation}\n"
                f"  recomputed position {d.recomputed_position} orientation (w,x,y,z) {d.recomputed_orientation}\n"
                f"  {self.compared - 1} earlier pose sets matched{tail}"
            )


def _same_bits(a, b):
    a = np.ascontiguousarray(a, dtype=np.float64)
    b = np.ascontiguousarray(b, dtype=np.float64)
    return a.shape == b.shape and np.array_equal(a.view(np.uint64), b.view(np.uint64))


def _load_world(recording, max_bodies=MAX_BODIES):
    scene = recording.attachment(media_type=SCENE_MEDIA_TYPE)
    if scene is None:
        raise ResimulationError("the recording has no scene attachment")
    # Loaded from a file of the same name, as the node loaded it, so the same
    # loader path runs; what the loader warns about was logged when recording.
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, os.path.basename(scene.name) or "scene.yaml")
        with open(path, "wb") as f:
            f.write(scene.data)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return load_scene(path, max_bodies=max_bodies)


def resimulate(path):
    """Re-run a recording; returns a Result (never raises for bad files)."""
    try:
        return _resimulate(Recording(path))
    except (ResimulationError, SceneError, OSError, ValueError) as exc:
        return Result(ERROR, error=f"{path}: {exc}")


def _resimulate(recording):
    session = recording.metadata.get(SESSION_METADATA)
    if session is None or "node" not in session:
        raise ResimulationError(f"no {SESSION_METADATA!r} metadata: not a physics_node recording")
    # The body limit the node ran with (older recordings: the default).
    max_bodies = int(json.loads(session.get("param.max_bodies", str(MAX_BODIES))))
    history = _history(recording, session)
    replay = _Replay(recording, session["node"], max_bodies, history)
    if history is not None:
        # the world up to the step the recording started at (no poses in it)
        for m in history.messages():
            replay.take(m)
        replay.result.notes.append(
            f"re-applied the node's history since its last reset up to step {session[STARTED_AT_STEP]}, "
            "where the recording started"
        )
    for m in recording.messages():
        if not replay.take(m):
            break
    result = replay.result
    result.complete_file = recording.complete
    if result.status == MATCH and result.compared == 0:
        raise ResimulationError("no poses recorded on " + replay.poses_topic)
    return result


def _history(recording, session):
    """The history attached to a recording started mid-session
    (session_history.py), as a Recording; None for one started with the node."""
    if STARTED_AT_STEP not in session:
        return None
    state = session.get(HISTORY_STATE, "")
    attached = recording.attachment(media_type=HISTORY_MEDIA_TYPE, name=HISTORY_NAME)
    if state != "complete" or attached is None:
        raise ResimulationError(
            f"the recording started at step {session[STARTED_AT_STEP]}, mid-session, without the history that "
            f"rebuilds the world up to there ({state or 'none attached'}): physics-replay plays it back, "
            "but it cannot be re-simulated"
        )
    return Recording(attached.data)


class _Replay:
    """The recorded messages of one session, taken in file order."""

    def __init__(self, recording, node, max_bodies=MAX_BODIES, history=None):
        self.world = _load_world(recording, max_bodies)
        self.stepper = Stepper(self.world, command_timeout=0.0, error_types=(CommandError, ValueError))
        self.poses_topic = f"{node}/poses"
        self.events_topic = node + EVENTS_SUFFIX
        # a spawned body's topics may sit under its entity namespace: ~/<ns>/<body>/wrench
        self.command_topic = re.compile(rf"^{re.escape(node)}/(?:.+/)?([^/]+)/(wrench|impulse)$")
        # spawn files read before the recording started come first, in the order read
        attachments = (history.attachments if history is not None else []) + recording.attachments
        self.requests = ReplayedRequests(self.stepper, node, attachments, max_bodies)
        self.result = Result(MATCH)

    def take(self, m):
        """Act on one message; False once the poses diverged."""
        if m.topic == self.poses_topic:
            return self._compare(m)
        if m.topic == self.events_topic:
            self._event(m)
        elif self.requests.takes(m.topic):
            self.advance_to(m.sequence, "request")
            self.result.requests += self.requests.apply(m.topic, m.data)
        else:
            self._command(m)
        return True

    def _event(self, m):
        event = deserialize_message(m.data, String).data
        if event == RESET_EVENT:
            self.requests.reset_all()
            self.result.resets += 1
        elif event.startswith(ISOLATE_EVENT + " "):
            # Bodies the node froze when the step from m.sequence went
            # non-finite: the re-run must have frozen the same ones.
            self.advance_to(m.sequence + 1, "isolation event")
            names = event[len(ISOLATE_EVENT) + 1 :].split(",")
            missing = [n for n in names if n not in self.stepper.isolated]
            if missing:
                raise ResimulationError(f"the recording froze {', '.join(missing)} at step {m.sequence}; the re-run did not")
            self.result.notes.append(f"froze {', '.join(names)} at step {m.sequence}, as recorded")

    def _compare(self, m):
        world, result = self.world, self.result
        self.advance_to(m.sequence, "poses")
        pos, quat = arrays_from_pose_array(deserialize_message(m.data, PoseArray))
        result.compared += 1
        result.last_step = m.sequence
        if _same_bits(pos, world.state.pos) and _same_bits(quat, world.state.quat):
            return True
        result.status = DIVERGE
        result.divergence = _first_difference(world, m, pos, quat)
        return False

    def _command(self, m):
        match = self.command_topic.match(m.topic)
        if not match:
            return
        self.advance_to(m.sequence, "command")
        frame, force, torque = wrench_arrays(deserialize_message(m.data, WrenchStamped))
        self.stepper.submit(Command(match.group(2), match.group(1), frame, force, torque, topic=m.topic, raw=m.data))
        self.result.commands += 1

    def advance_to(self, step, what):
        world = self.world
        if world.step_index > step:
            raise ResimulationError(
                f"{what} at step {step} comes after step {world.step_index} in the file; steps must not go back "
                "without a reset event"
            )
        while world.step_index < step:
            boundary = self.stepper.advance()
            if boundary.rejected:
                command, error = boundary.rejected[0]
                raise ResimulationError(f"recorded command on {command.topic} was refused on re-apply: {error}")
            if boundary.failure is not None:
                raise ResimulationError(f"the engine failed at step {boundary.step}: {boundary.failure}")
            self.requests.stepped()


def _first_difference(world, message, pos, quat):
    n = min(len(pos), len(world.state.pos))
    for i in range(n):
        if not (_same_bits(pos[i], world.state.pos[i]) and _same_bits(quat[i], world.state.quat[i])):
            break
    else:
        i = n  # the body counts differ
    name = world.model.names[i] if i < len(world.model.names) else f"#{i}"
    pick = (lambda a: a[i].copy() if i < len(a) else np.full(a.shape[1:], np.nan))  # noqa: E731
    return Divergence(
        step=message.sequence,
        time_ns=message.log_time,
        body=name,
        index=i,
        recorded_position=pick(pos),
        recorded_orientation=pick(quat),
        recomputed_position=pick(world.state.pos),
        recomputed_orientation=pick(world.state.quat),
    )
