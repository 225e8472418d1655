"""`physics-node --foxglove [PORT]`: the live world served over Foxglove's
WebSocket protocol (foxglove-sdk), so the Foxglove app can watch and drive a
node installed from PyPI alone (no foxglove_bridge, no ROS CLI).

Served channels:
- `<node>/scene` (foxglove.SceneUpdate): every body as its shape at its pose
  and the contact events of the step as arrows; `<node>/transforms`
  (foxglove.FrameTransforms): world -> each moving body. Both at most
  `rate` times a wall second while running, and at every step and reset
  while paused.
- every topic the node publishes or records (`~/poses`, `~/contacts`,
  `/clock`, `~/bodies`, `/diagnostics`, `~/markers` and the applied
  commands), as the same CDR bytes (ros2msg schemas), at sim time.
Time: the server's clock is sim time (the Time capability). Services (JSON):
`pause`, `play`, `step`, `reset`, handled by the node's own ROS service
handlers on the node's thread.
"""

import json
import queue
import threading
import time

from rclpy.clock import Clock, ClockType
from rclpy.qos import DurabilityPolicy
from std_srvs.srv import Empty, Trigger

from msg_adapters import ros2msg_schema, sim_time_ns, type_name

from .qos import STREAM

DEFAULT_PORT = 8765
DEFAULT_HOST = "127.0.0.1"
DEFAULT_RATE = 30.0  # scene updates per wall second while running
SERVICE_TIMEOUT_S = 5.0
SERVICE_POLL_S = 0.01  # how often the node's thread looks for service calls
TIME_PERIOD_S = 0.02  # the server's time is sent at most this often while running
SERVICES = ("pause", "play", "step", "reset")

_OBJECT_SCHEMA = b'{"type": "object"}'
_RESPONSE_SCHEMA = json.dumps({
    "type": "object",
    "properties": {
        "success": {"type": "boolean"}, "message": {"type": "string"}, "paused": {"type": "boolean"},
        "step": {"type": "integer"}, "sim_time": {"type": "number"},
    },
}).encode()


class FoxgloveError(RuntimeError):
    """A --foxglove setting that cannot be served: the SDK missing, a bad port, an address in use."""


def _sdk():
    try:
        import foxglove
    except ImportError as exc:
        raise FoxgloveError(
            "--foxglove needs the foxglove-sdk package: pip install 'physics_node[foxglove]' (make install has it)"
        ) from exc
    return foxglove


class FoxgloveBridge:
    """Made before the node; `attach(node, recorder)` starts the server and
    returns the sink the node's Outputs write to (the recorder, if any, gets
    everything it got before)."""

    def __init__(self, port=DEFAULT_PORT, host=DEFAULT_HOST, rate=DEFAULT_RATE):
        if not 0 <= int(port) <= 65535:
            raise FoxgloveError(f"--foxglove port must be within 0..65535, got {port}")
        if not rate > 0:
            raise FoxgloveError(f"--foxglove-rate must be > 0, got {rate}")
        self.port, self.host, self.rate = int(port), host, float(rate)
        self._sdk = _sdk()
        self.server = None
        self.node = None
        self._calls = queue.Queue()
        self._channels = {}  # topic -> foxglove Channel
        self._last_scene = self._last_time = -1e9
        self._late_subscriber = threading.Event()  # set by the server's thread, served on the node's
        self.tap = None

    # -- set-up ------------------------------------------------------------------
    def attach(self, node, recorder):
        from foxglove.channels import FrameTransformsChannel, SceneUpdateChannel

        from .foxglove_scene import SceneMessages

        fg = self._sdk
        self.node = node
        self.context = fg.Context()
        prefix = node.get_fully_qualified_name()
        self.scene_channel = SceneUpdateChannel(f"{prefix}/scene", context=self.context)
        self.transforms_channel = FrameTransformsChannel(f"{prefix}/transforms", context=self.context)
        self.scene = SceneMessages(node.model)
        try:
            self.server = fg.start_server(
                name=f"physics_node {prefix}",
                host=self.host,
                port=self.port,
                capabilities=[fg.Capability.Time, fg.Capability.Services],
                supported_encodings=["json"],
                services=[self._service(name) for name in SERVICES],
                server_listener=_Listener(self._late_subscriber),
                context=self.context,
            )
        except Exception as exc:  # the SDK raises its own error types for a bind failure
            raise FoxgloveError(f"--foxglove: cannot serve on {self.host}:{self.port}: {exc}") from exc
        node.create_timer(SERVICE_POLL_S, self.serve_calls, clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.tap = OutputTap(recorder, self, prefix + "/poses")
        return self.tap

    def bodies_changed(self, model):
        """Bodies were spawned or deleted: the scene draws the new body list."""
        from .foxglove_scene import SceneMessages

        self.scene = SceneMessages(model)

    @property
    def url(self):
        return f"ws://{self.host}:{self.server.port}" if self.server is not None else ""

    def close(self):
        if self.server is not None:
            self.server.stop()
            self.server = None

    # -- forwarded topics and the scene ---------------------------------------------
    def channel(self, topic, msg_class):
        ch = self._channels.get(topic)
        if ch is None:
            fg = self._sdk
            schema = fg.Schema(name=type_name(msg_class), encoding="ros2msg", data=ros2msg_schema(msg_class).encode())
            ch = fg.Channel(topic, schema=schema, message_encoding="cdr", context=self.context)
            self._channels[topic] = ch
        return ch

    def state_sent(self, time_ns, force=False):
        """The node sent a step's poses: the scene and transforms of that step,
        throttled to `rate` while running (every one while paused: steps and resets)."""
        now = time.monotonic()
        node = self.node
        if not (force or node.paused) and now - self._last_scene < 1.0 / self.rate:
            return
        self._last_scene = now
        s = node.world.state
        pos, quat = s.pos.tolist(), s.quat.tolist()
        if self.scene_channel.has_sinks():
            self.scene_channel.log(self.scene.scene_update(pos, quat, node.world.contacts, time_ns), log_time=time_ns)
        if self.transforms_channel.has_sinks():
            self.transforms_channel.log(self.scene.transforms(pos, quat, time_ns), log_time=time_ns)
        self.send_time(time_ns, force=True)

    def send_time(self, time_ns, force=False):
        now = time.monotonic()
        if self.server is not None and (force or self.node.paused or now - self._last_time >= TIME_PERIOD_S):
            self._last_time = now
            self.server.broadcast_time(int(time_ns))

    # -- services ------------------------------------------------------------------
    def _service(self, name):
        fg = self._sdk
        schema = fg.ServiceSchema(
            f"physics_node/{name}",
            request=fg.MessageSchema(encoding="json", schema=fg.Schema(name="Empty", encoding="jsonschema",
                                                                       data=_OBJECT_SCHEMA)),
            response=fg.MessageSchema(encoding="json", schema=fg.Schema(name="Result", encoding="jsonschema",
                                                                        data=_RESPONSE_SCHEMA)),
        )
        return fg.Service(name, schema=schema, handler=lambda request: self._call(name))

    def _call(self, name):
        """Runs on the server's thread: hand the call to the node's thread and wait for it."""
        done, result = threading.Event(), {}
        self._calls.put((name, done, result))
        if not done.wait(SERVICE_TIMEOUT_S):
            raise RuntimeError(f"{name}: the node did not answer within {SERVICE_TIMEOUT_S:g} s")
        return json.dumps(result).encode()

    def serve_calls(self):
        """On the node's thread (a timer): the pending service calls, through
        the same handlers as the node's ROS services; and, for a client that
        has just subscribed, the world as it is now (a paused node sends
        nothing by itself) and the last message of each latched topic."""
        if self._late_subscriber.is_set():
            self._late_subscriber.clear()
            self.tap.resend_latched()
            self.state_sent(sim_time_ns(self.node.world.time), force=True)
        while True:
            try:
                name, done, result = self._calls.get_nowait()
            except queue.Empty:
                return
            try:
                result.update(self._run(name))
            except Exception as exc:  # a failed call answers with why; the node runs on
                result.update(success=False, message=f"{type(exc).__name__}: {exc}")
            finally:
                node = self.node
                result.update(paused=bool(node.paused), step=int(node.world.step_index), sim_time=node.world.time)
                done.set()

    def _run(self, name):
        node = self.node
        if name == "step":
            response = node._on_step(None, Trigger.Response())
            return {"success": bool(response.success), "message": response.message}
        handler = {"pause": node._on_pause, "play": node._on_unpause, "reset": node._on_reset}[name]
        handler(None, Empty.Response())
        if name == "play" and node.faulted:
            return {"success": False, "message": f"{node.faulted}; call reset first"}
        self.send_time(sim_time_ns(node.world.time), force=True)
        return {"success": True, "message": {"pause": "paused", "play": "running", "reset": "world reset"}[name]}


class _Listener:
    """The server's callbacks (on its own thread): a subscription only raises a flag."""

    def __init__(self, flag):
        self._flag = flag

    def on_subscribe(self, client, channel):
        self._flag.set()


class OutputTap:
    """What the node's Outputs write to in place of the recorder: each message
    goes to the recorder (if any) and to the bridge's channel of its topic;
    a step's poses also trigger the bridge's scene update."""

    def __init__(self, recorder, bridge, poses_topic):
        self.recorder = recorder
        self.bridge = bridge
        self.poses_topic = poses_topic
        self._ids = []  # tap channel id -> (recorder channel id, foxglove channel, is the poses topic)
        self._specs = []  # tap channel id -> (topic, msg class, qos), to register with a later recorder
        self._index = {}
        self._latched = set()  # tap ids of transient-local topics (/clock, ~/bodies)
        self._last = {}  # tap id -> (data, time ns) of its latest message, for latched topics

    @property
    def path(self):
        return self.recorder.path if self.recorder is not None else ""

    def set_recorder(self, recorder):
        """Record into `recorder` from now on (None: stop); Foxglove keeps its channels."""
        self.recorder = recorder
        self._ids = [(None, ch, is_poses) for _, ch, is_poses in self._ids]

    def _recorder_id(self, cid):
        rid, ch, is_poses = self._ids[cid]
        if rid is None:
            topic, msg_class, qos = self._specs[cid]
            rid = self.recorder.channel(topic, msg_class, STREAM if qos is None else qos)
            self._ids[cid] = (rid, ch, is_poses)
        return rid

    def channel(self, topic, msg_class, qos=None):
        key = (topic, msg_class)
        cid = self._index.get(key)
        if cid is None:
            self._ids.append((None, self.bridge.channel(topic, msg_class), topic == self.poses_topic))
            self._specs.append((topic, msg_class, qos))
            cid = len(self._ids) - 1
            if self.recorder is not None:
                self._recorder_id(cid)
            self._index[key] = cid
            if qos is not None and qos.durability == DurabilityPolicy.TRANSIENT_LOCAL:
                self._latched.add(cid)
        return cid

    def write(self, topic, msg_class, data, time_ns, step=0, qos=None):
        self.write_many((self.channel(topic, msg_class, qos),), (data,), time_ns, step)

    def write_many(self, channel_ids, datas, time_ns, step=0):
        if self.recorder is not None:
            self.recorder.write_many([self._recorder_id(c) for c in channel_ids], datas, time_ns, step)
        rows = [self._ids[c] for c in channel_ids]
        poses = False
        for cid, (_, ch, is_poses), data in zip(channel_ids, rows, datas):
            data = bytes(data)
            ch.log(data, log_time=int(time_ns))
            poses = poses or is_poses
            if cid in self._latched:
                self._last[cid] = (data, int(time_ns))
        if poses:
            self.bridge.state_sent(time_ns)
        else:
            self.bridge.send_time(time_ns)

    def resend_latched(self):
        """The last message of each transient-local topic again, for a client
        that subscribed after it was sent (as a ROS late joiner gets it)."""
        for cid, (data, time_ns) in list(self._last.items()):
            self._ids[cid][1].log(data, log_time=time_ns)
