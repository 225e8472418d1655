"""Everything the node sends: publishers, and the recording of what they send.

Each message is serialized once; the same CDR bytes are published and, with
a recording open, written to the file, so the file holds exactly what
subscribers received. The per-step messages (poses, odometry, contacts,
markers, clock) are built as CDR directly (msg_adapters.cdr), all bodies at
once; the rest go through rclpy's serializer.
"""

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseArray, WrenchStamped
from nav_msgs.msg import Odometry
from rclpy.serialization import serialize_message
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import PointCloud2
from std_msgs.msg import String
from tf2_msgs.msg import TFMessage
from visualization_msgs.msg import MarkerArray

from msg_adapters import BodyOdometry, SceneMarkers, contact_cloud, pose_array, sim_time_ns, time_msg
from msg_adapters.cdr import (
    CdrLayoutError,
    ContactCloudCdr,
    OdometryCdr,
    PoseArrayCdr,
    SceneMarkersCdr,
    body_markers_cdr,
    clock_cdr,
)

from .qos import COMMANDS, LATCHED, STREAM, TF, TF_STATIC, per_body_events
from .recorder import EVENTS_SUFFIX, ISOLATE_EVENT, RESET_EVENT, RecorderError
from .tf_output import TfOutput


class Outputs:
    def __init__(self, node, model, recorder=None, odometry="subscribed", on_demand=False, history=None,
                 on_record_error=None):
        """`recorder`: a Recorder, the Foxglove tap (which records into one
        it is given), or None. `on_demand`: no odometry publisher is made
        until `add_odometry` (body_topics.py makes them when a subscriber
        appears). `history` (session_history.py) keeps every command, request
        and event, recorded or not; `on_record_error(exc)` is told of a
        write error (recording_control.py)."""
        self.model = model
        self.on_demand = on_demand
        self.recorder = recorder
        self._tap = recorder if hasattr(recorder, "set_recorder") else None
        self.history = history
        self._on_record_error = on_record_error
        self._latched_sent = {}  # latched publisher -> (msg class, CDR) last sent, for a recording started later
        self._node = node
        pub = node.create_publisher
        self.clock = pub(Clock, "/clock", LATCHED)
        self.poses = pub(PoseArray, "~/poses", STREAM)
        self.contacts = pub(PointCloud2, "~/contacts", STREAM)
        self.markers = pub(MarkerArray, "~/markers", STREAM)
        self.bodies = pub(MarkerArray, "~/bodies", LATCHED)
        self.diagnostics = pub(DiagnosticArray, "/diagnostics", STREAM)
        self.tf = TfOutput(pub(TFMessage, "/tf", TF), pub(TFMessage, "/tf_static", TF_STATIC), model)
        self.prefix = {}  # body -> its topics' path under the node when not its name (an entity namespace)
        self.odom = [None if on_demand else self._odom_publisher(name) for name in model.names]
        self._qos, self._topic = {}, {}
        self._index_publishers()
        self._channels = {}  # publisher -> recording channel id, made on its first message
        self._bodies_sent, self._body_ns = 0, {}  # markers in the last ~/bodies, and their ns
        self.events_topic = node.get_fully_qualified_name() + EVENTS_SUFFIX
        self._build = _state_builder(model, node.get_logger())
        # On-demand outputs (see refresh_subscribers): which bodies' odometry
        # topics have a reader, the rows published, and whether markers are.
        self.odometry = odometry
        self._odom_read = [False] * len(self.odom)
        self._odom_rows = []
        self._markers_on = False
        self._poll_at = 0
        self.refresh_subscribers()

    def _odom_publisher(self, name):
        odom_events, _ = per_body_events()
        path = self.prefix.get(name, name)
        return self._node.create_publisher(Odometry, f"~/{path}/odom", STREAM, event_callbacks=odom_events)

    def _index_publishers(self):
        self._qos.update({p.topic_name: q for p, q in self._all_publishers()})
        self._topic.update({p: p.topic_name for p, _ in self._all_publishers()})

    def add_odometry(self, name):
        """The odometry publisher of body `name`, made now if it has none
        (on demand: someone subscribed); served once a poll sees the reader."""
        i = self.model.index[name]
        if self.odom[i] is None:
            self.odom[i] = publisher = self._odom_publisher(name)
            self._qos[publisher.topic_name] = STREAM
            self._topic[publisher] = publisher.topic_name
        return self.odom[i]

    @property
    def odometry_publishers(self):
        return sum(1 for p in self.odom if p is not None)

    def bodies_changed(self, model):
        """Bodies were spawned or deleted: each body keeps its odometry
        publisher, a new one gets one, a deleted one's is destroyed; the
        per-step builders are made for the new body list."""
        by_name = dict(zip(self.model.names, self.odom))
        for name in set(by_name) - set(model.names):
            publisher = by_name.pop(name)
            if publisher is None:
                continue
            self._topic.pop(publisher, None)
            self._channels.pop(publisher, None)
            self._node.destroy_publisher(publisher)
        self.model = model
        keep = by_name.get if self.on_demand else lambda name: by_name.get(name) or self._odom_publisher(name)
        self.odom = [keep(name) for name in model.names]
        self._index_publishers()
        self._build = _state_builder(model, self._node.get_logger())
        self.tf.bodies_changed(model)
        self._odom_read = [False] * len(self.odom)
        self.refresh_subscribers()

    def refresh_subscribers(self):
        """Which on-demand outputs are sent: a body's odometry while its
        topic has a subscriber (every body's with `odometry` 'all'), the
        markers while someone (RViz, Foxglove) listens. Poses, contacts and
        /clock are always sent. A publish costs 5-10 us even with no reader,
        so a thousand unread odometry topics would cost more than the step."""
        self._poll_at = 0
        self.poll_subscribers(1)

    def poll_subscribers(self, parts):
        """`refresh_subscribers` spread over `parts` calls: each asks the next
        slice of odometry publishers (about 3 us each), so a thousand bodies
        never cost one long pause between two steps."""
        n = len(self.odom)
        size = -(-n // max(int(parts), 1))
        start = self._poll_at
        read = self._odom_read
        odom = self.odom
        for i in range(start, min(start + size, n)):
            read[i] = odom[i] is not None and odom[i].get_subscription_count() > 0
        self._poll_at = start + size if start + size < n else 0
        self._markers_on = self.markers.get_subscription_count() > 0
        self._update_rows()

    def _update_rows(self):
        if self.odometry == "all":
            self._odom_rows = [i for i, p in enumerate(self.odom) if p is not None]
        else:
            self._odom_rows = [i for i, r in enumerate(self._odom_read) if r]

    @property
    def state_messages(self):
        """Messages `send_state` sends now: poses, contacts, odometry, markers, /tf."""
        return 2 + len(self._odom_rows) + int(self._markers_on) + int(self.tf.has_dynamic)

    def set_odometry(self, mode):
        self.odometry = mode
        self.refresh_subscribers()

    def _all_publishers(self):
        yield self.clock, LATCHED
        yield self.bodies, LATCHED
        yield self.tf.static, TF_STATIC
        yield self.tf.dynamic, TF
        for p in (self.poses, self.contacts, self.markers, self.diagnostics, *self.odom):
            if p is not None:
                yield p, STREAM

    def _send(self, publisher, msg, time_ns, step):
        if self.recorder is None:
            publisher.publish(msg)
            return
        self._send_cdr(publisher, type(msg), serialize_message(msg), time_ns, step)

    def _send_cdr(self, publisher, msg_class, data, time_ns, step):
        """Publish (and record) a message already serialized."""
        publisher.publish(data)
        if publisher is self.clock or publisher is self.bodies or publisher is self.tf.static:
            self._latched_sent[publisher] = (msg_class, data)
        if self.recorder is not None:
            topic = self._topic[publisher]
            self._record(self.recorder.write, topic, msg_class, data, time_ns, step, self._qos[topic])

    def _record(self, write, *args):
        """`write(*args)` on the recorder; a write error (disk full, file
        removed, no permission) stops the recording, never the simulation."""
        try:
            write(*args)
        except (RecorderError, OSError) as exc:
            if self._on_record_error is None:
                raise
            self._on_record_error(exc)

    def set_recorder(self, recorder):
        """Record into `recorder` from now on (None: stop recording); the
        Foxglove tap, if any, keeps serving."""
        if self._tap is not None:
            self._tap.set_recorder(recorder)
        else:
            self.recorder = recorder
        self._channels = {}  # channel ids are the old recorder's

    def record_latched(self, time_s, step):
        """The latched messages as last sent (/clock, ~/bodies, /tf_static)
        into the recording, at sim time `time_s`: a recording started
        mid-session has them from its start, as a late subscriber gets them."""
        if self.recorder is None:
            return
        time_ns = sim_time_ns(time_s)
        for publisher, (msg_class, data) in list(self._latched_sent.items()):
            topic = self._topic[publisher]
            self._record(self.recorder.write, topic, msg_class, data, time_ns, step, self._qos[topic])

    # -- per step ----------------------------------------------------------
    def send_clock(self, time_ns, step):
        self._send_cdr(self.clock, Clock, clock_cdr(time_ns), time_ns, step)

    def send_state(self, world, time_ns, step):
        """Poses, contacts, the odometry and markers someone reads, of one step."""
        rows, markers = self._odom_rows, self._markers_on
        datas = self._build(world.state, world.contacts, time_ns, rows, markers)
        publishers = [self.poses, self.contacts]
        publishers += [self.odom[i] for i in rows]
        if markers:
            publishers.append(self.markers)
        if self.tf.has_dynamic:
            publishers.append(self.tf.dynamic)
            datas.append(self.tf.build(world.state, time_ns))
        for publisher, data in zip(publishers, datas):
            publisher.publish(data)
        if self.recorder is not None:
            self._record(self._record_state, publishers, datas, time_ns, step)

    def _record_state(self, publishers, datas, time_ns, step):
        channels = self._channels
        ids = [channels.get(p) for p in publishers]
        if None in ids:
            ids = [self._channel(p) for p in publishers]
        self.recorder.write_many(ids, datas, time_ns, step)

    def _channel(self, publisher):
        cid = self._channels.get(publisher)
        if cid is None:
            topic = self._topic[publisher]
            cid = self.recorder.channel(topic, publisher.msg_type, self._qos[topic])
            self._channels[publisher] = cid
        return cid

    def send_bodies(self, world, time_ns, step):
        """The latched body list (~/bodies: one marker per body, id = its row
        in ~/poses, ns and text = its name; after a delete, DELETE markers
        for the ids no longer used, so a viewer drops them) and the static
        bodies' /tf_static."""
        n = len(self.model.names)
        gone = [(i, self._body_ns.get(i, "")) for i in range(n, self._bodies_sent)]
        data = body_markers_cdr(self.model, world.state.pos, world.state.quat, time_ns, gone)
        self._bodies_sent = n
        self._body_ns = dict(enumerate(self.model.names))
        self._send_cdr(self.bodies, MarkerArray, data, time_ns, step)
        self._send_cdr(self.tf.static, TFMessage, self.tf.build_static(world.state, time_ns), time_ns, step)

    def record_request(self, topic, msg, time_ns, step):
        """A simulator-standard request as received, for --resimulate."""
        self._keep(topic, type(msg), serialize_message(msg), time_ns, step, COMMANDS)

    def _keep(self, topic, msg_class, data, time_ns, step, qos):
        """A message --resimulate needs: into the history and the recording."""
        if self.history is not None:
            self.history.add(topic, msg_class, data, time_ns, step, qos)
        if self.recorder is not None:
            self._record(self.recorder.write, topic, msg_class, data, time_ns, step, qos)

    def send_diagnostics(self, msg, time_ns, step):
        self._send(self.diagnostics, msg, time_ns, step)

    # -- recording only ----------------------------------------------------
    def record_command(self, command, time_ns, step):
        """An applied command, at the sim time and index of the step that
        applied it. Commands the node made itself (a wrench timing out) are
        recorded as the zero WrenchStamped they amount to."""
        if self.recorder is None and self.history is None:
            return
        data = command.raw
        if not data:
            msg = WrenchStamped()
            msg.header.stamp = time_msg(time_ns)
            msg.header.frame_id = command.frame
            data = serialize_message(msg)
        topic = command.topic or f"{self._node.get_fully_qualified_name()}/{command.body}/wrench"
        self._keep(topic, WrenchStamped, data, time_ns, step, COMMANDS)

    def record_reset(self, time_ns, step):
        self._record_event(RESET_EVENT, time_ns, step)

    def record_isolation(self, names, time_ns, step):
        """Bodies frozen at step `step` after a non-finite state: `isolate a,b`."""
        self._record_event(f"{ISOLATE_EVENT} {','.join(names)}", time_ns, step)

    def _record_event(self, text, time_ns, step):
        if self.recorder is None and self.history is None:
            return
        self._keep(self.events_topic, String, serialize_message(String(data=text)), time_ns, step, STREAM)


def _state_builder(model, logger):
    """`build(state, contacts, time_ns, odom_rows, markers)` -> the CDR bytes
    of the poses, the contacts, the odometry of the bodies in `odom_rows`
    and, if `markers`, the markers, in that order. The builders of
    msg_adapters.cdr keep one buffer each and write all bodies at once; if
    they cannot lay out what this rmw serializes, the object builders and
    rclpy's serializer give the same messages, more slowly."""
    try:
        poses = PoseArrayCdr(len(model.names))
        odometry = OdometryCdr(model.names)
        cloud = ContactCloudCdr()
    except CdrLayoutError as exc:
        logger.warning(f"per-step messages go through rclpy's serializer: {exc}")
        return _serialized_state_builder(model)
    markers_builder = _markers_builder(model, logger)

    def build(s, contacts, time_ns, odom_rows, markers):
        datas = [poses.build(s.pos, s.quat, time_ns), cloud.build(contacts, time_ns)]
        if odom_rows:
            datas += odometry.build(s.pos, s.quat, s.vel, s.omega, time_ns, odom_rows)
        if markers:
            datas.append(markers_builder(s.pos, s.quat, contacts, time_ns))
        return datas

    return build


def _markers_builder(model, logger):
    """`build(pos, quat, contacts, time_ns)` -> the CDR of ~/markers, laid out
    when first asked for (someone subscribed): 10,000 bodies' markers take
    1.5 s to lay out, and most sessions never draw them."""
    made = []

    def build(pos, quat, contacts, time_ns):
        if not made:
            try:
                made.append(SceneMarkersCdr(model, capacity=max(64, 4 * len(model.names))).build)
            except CdrLayoutError as exc:
                logger.warning(f"~/markers goes through rclpy's serializer: {exc}")
                objects = SceneMarkers(model)
                made.append(lambda *args: serialize_message(objects.build(*args)))
        return made[0](pos, quat, contacts, time_ns)

    return build


def _serialized_state_builder(model):
    odometry, scene_markers = BodyOdometry(model.names), SceneMarkers(model)

    def build(s, contacts, time_ns, odom_rows, markers):
        msgs = [pose_array(s.pos, s.quat, time_ns), contact_cloud(contacts, time_ns)]
        if odom_rows:
            every = odometry.build(s.pos, s.quat, s.vel, s.omega, time_ns)
            msgs += [every[i] for i in odom_rows]
        if markers:
            msgs.append(scene_markers.build(s.pos, s.quat, contacts, time_ns))
        return [serialize_message(m) for m in msgs]

    return build
