"""Everything the node sends: publishers, and the recording of what they send.

With a recording open, each message is serialized once; the same CDR bytes
are published and written to the file, so the file holds exactly what
subscribers received.
"""

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseArray, WrenchStamped
from nav_msgs.msg import Odometry
from rclpy.serialization import serialize_message
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import PointCloud2
from std_msgs.msg import String
from visualization_msgs.msg import MarkerArray

from msg_adapters import BodyOdometry, SceneMarkers, body_markers, contact_cloud, pose_array, time_msg

from .qos import COMMANDS, LATCHED, STREAM
from .recorder import EVENTS_SUFFIX, RESET_EVENT


class Outputs:
    def __init__(self, node, model, recorder=None):
        self.model = model
        self.recorder = recorder
        self._node = node
        pub = node.create_publisher
        self.clock = pub(Clock, "/clock", LATCHED)
        self.poses = pub(PoseArray, "~/poses", STREAM)
        self.contacts = pub(PointCloud2, "~/contacts", STREAM)
        self.markers = pub(MarkerArray, "~/markers", STREAM)
        self.bodies = pub(MarkerArray, "~/bodies", LATCHED)
        self.diagnostics = pub(DiagnosticArray, "/diagnostics", STREAM)
        self.odom = [pub(Odometry, f"~/{name}/odom", STREAM) for name in model.names]
        self._qos = {p.topic_name: q for p, q in self._all_publishers()}
        self.events_topic = node.get_fully_qualified_name() + EVENTS_SUFFIX
        # Messages are published (serialized) before the next step changes
        # them, so one set per body can be reused.
        self._odometry = BodyOdometry(model.names)
        self._markers = SceneMarkers(model)

    def _all_publishers(self):
        yield self.clock, LATCHED
        yield self.bodies, LATCHED
        for p in (self.poses, self.contacts, self.markers, self.diagnostics, *self.odom):
            yield p, STREAM

    def _send(self, publisher, msg, time_ns, step):
        if self.recorder is None:
            publisher.publish(msg)
            return
        data = serialize_message(msg)
        publisher.publish(data)
        topic = publisher.topic_name
        self.recorder.write(topic, type(msg), data, time_ns, step, self._qos[topic])

    # -- per step ----------------------------------------------------------
    def send_clock(self, time_ns, step):
        self._send(self.clock, Clock(clock=time_msg(time_ns)), time_ns, step)

    def send_state(self, world, time_ns, step):
        s = world.state
        self._send(self.poses, pose_array(s.pos, s.quat, time_ns), time_ns, step)
        for publisher, msg in zip(self.odom, self._odometry.build(s.pos, s.quat, s.vel, s.omega, time_ns)):
            self._send(publisher, msg, time_ns, step)
        contacts = world.contacts
        self._send(self.contacts, contact_cloud(contacts, time_ns), time_ns, step)
        self._send(self.markers, self._markers.build(s.pos, s.quat, contacts, time_ns), time_ns, step)

    def send_bodies(self, world, time_ns, step):
        msg = body_markers(self.model, world.state.pos, world.state.quat, time_ns)
        self._send(self.bodies, msg, time_ns, step)

    def send_diagnostics(self, msg, time_ns, step):
        self._send(self.diagnostics, msg, time_ns, step)

    # -- recording only ----------------------------------------------------
    def record_command(self, command, time_ns, step):
        """An applied command, at the sim time and index of the step that
        applied it. Commands the node made itself (a wrench timing out) are
        recorded as the zero WrenchStamped they amount to."""
        if self.recorder is None:
            return
        data = command.raw
        if not data:
            msg = WrenchStamped()
            msg.header.stamp = time_msg(time_ns)
            msg.header.frame_id = command.frame
            data = serialize_message(msg)
        topic = command.topic or f"{self._node.get_fully_qualified_name()}/{command.body}/wrench"
        self.recorder.write(topic, WrenchStamped, data, time_ns, step, COMMANDS)

    def record_reset(self, time_ns, step):
        if self.recorder is None:
            return
        data = serialize_message(String(data=RESET_EVENT))
        self.recorder.write(self.events_topic, String, data, time_ns, step, STREAM)
