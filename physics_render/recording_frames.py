"""Frames from a physics_node recording: `~/poses` for where the bodies are,
`~/contacts` for the contact events, `~/bodies` (or the attached scene) for
what they look like. Reads what `physics-replay` reads, a file cut short by
a crash included (up to its last complete chunk).

After a world reset sim time starts again at 0; the frames run on in file
order, so playback time keeps counting from where the part before ended.
"""

from geometry_msgs.msg import PoseArray
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import PointCloud2
from visualization_msgs.msg import MarkerArray

from msg_adapters import arrays_from_pose_array, contacts_from_cloud
from physics_node.recorder import SESSION_METADATA
from physics_node.recording_reader import Recording
from physics_node.resimulate import ResimulationError
from physics_node.resimulate import _load_world as load_attached_scene

from .shapes import Shapes
from .timeline import NS_PER_S, Frame, _ContactWindow


class RecordingError(ValueError):
    pass


def open_recording(path):
    """(Recording, node name) of a physics_node recording, or RecordingError saying why not."""
    try:
        recording = Recording(path)
    except (OSError, ValueError) as exc:
        raise RecordingError(str(exc)) from exc
    session = recording.metadata.get(SESSION_METADATA)
    if session is None or "node" not in session:
        raise RecordingError(f"{path}: no {SESSION_METADATA!r} metadata: not a physics_node recording")
    return recording, session["node"]


def scene_shapes(recording):
    """Shapes of the scene attached to the recording (loaded as `--resimulate`
    loads it), or None if it has none."""
    try:
        return Shapes.from_model(load_attached_scene(recording).model)
    except ResimulationError:
        return None


class _Playhead:
    """The latest recorded state, with the playback time it was reached at."""

    def __init__(self, shapes):
        self.shapes = shapes
        self.pose = None  # (playback ns, sim ns, step, pos, quat)
        self.offset = 0  # playback ns at the start of the current part (after resets)
        self.part = 0

    def playback_of(self, sim_ns):
        """Playback time of a pose recorded at `sim_ns`: after a reset (sim time
        going back) the new part starts where the last one ended."""
        if self.pose is not None and sim_ns < self.pose[1]:
            return self.pose[0] + sim_ns
        return self.offset + sim_ns

    def move(self, sim_ns, step, pos, quat):
        playback = self.playback_of(sim_ns)
        if self.pose is not None and sim_ns < self.pose[1]:
            self.part += 1
        self.offset = playback - sim_ns
        self.pose = (playback, sim_ns, step, pos, quat)

    def frame(self, t, window):
        _, sim_ns, step, pos, quat = self.pose
        shapes = self.shapes
        if shapes is None or len(shapes) != len(pos):
            known = 0 if shapes is None else len(shapes)
            raise RecordingError(f"step {step}: {len(pos)} poses but the shapes of {known} bodies are known")
        point, normal, event = window.take()
        return Frame(t / NS_PER_S, sim_ns / NS_PER_S, step, pos, quat, point, normal, event, shapes, self.part)


def recording_frames(recording, node, times_ns, span_ns=0):
    """Frames at the given playback times (ns, increasing) until the recording
    ends; `span_ns` as in timeline.scene_frames."""
    poses_topic, contacts_topic, bodies_topic = f"{node}/poses", f"{node}/contacts", f"{node}/bodies"
    scene = scene_shapes(recording)
    head = _Playhead(scene)
    window = _ContactWindow()
    times = iter(times_ns)
    t = next(times, None)
    for m in recording.messages():
        if t is None:
            return
        if m.topic == bodies_topic:
            # The scene's own shapes (exact planes, springs) while it describes
            # every body; the node's markers once bodies were added or removed.
            marked = Shapes.from_markers(deserialize_message(m.data, MarkerArray))
            head.shapes = scene if scene is not None and len(scene) == len(marked) else marked
        elif m.topic == contacts_topic and head.pose is not None:
            c = contacts_from_cloud(deserialize_message(m.data, PointCloud2))
            window.add(c.point, c.normal, c.event, in_span=t is not None and head.pose[0] > t - span_ns)
        elif m.topic == poses_topic:
            # Every frame before this pose shows the one before it.
            arrival = head.playback_of(m.log_time)
            while head.pose is not None and t is not None and t < arrival:
                yield head.frame(t, window)
                t = next(times, None)
            head.move(m.log_time, m.sequence, *arrays_from_pose_array(deserialize_message(m.data, PoseArray)))
    # The recording ended: frames up to its last state are shown, later ones do not exist.
    while t is not None and head.pose is not None and t <= head.pose[0]:
        yield head.frame(t, window)
        t = next(times, None)
