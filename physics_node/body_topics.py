"""Each body's own topics: `~/<body>/wrench` and `~/<body>/impulse` in,
`~/<body>/odom` out (INTERFACE.md), made at start or when a peer uses them.

Making ROS endpoints one by one costs O(n²) in rmw_fastrtps: each one made
or destroyed republishes the participant's whole endpoint list
(ros_discovery_info). Measured with the node (this machine, under load):
1,000 bodies (3,000 endpoints) took 2.1 s to make and 9.8 s to destroy,
2,000 bodies 7.7 s and 36 s; 10,000 bodies took minutes to start and hung
in destroy_publisher on shutdown.

So a world of more than `topics_on_demand_above` bodies at start (the
parameter, default ON_DEMAND_ABOVE) makes none of them then. Its graph scan
(every 0.5 s, shared with unknown_bodies.py) looks for the bodies' topics:
`wrench`/`impulse` appear in the graph once a peer publishes (or subscribes)
there, `odom` once a peer subscribes. Each topic found is queued, and at
most ON_DEMAND_PER_TICK are made every ON_DEMAND_TICK_S (one endpoint costs
0.5-1 ms), so /clock keeps its rate while many peers appear; a topic made
stays until its body is deleted. Smaller worlds make every topic at start,
as before. Spawned bodies follow the mode the node started in.

The trade-off: what a peer publishes before the node's subscription exists
and is matched is lost in transit, as with any ROS subscription made after
its publisher (a volatile reader never sees earlier samples). A peer that
must not lose its first command waits for `get_subscription_count() > 0`
(the one-liner `physics-node` prints does), about 0.5-1 s after it starts
publishing here.
"""

from collections import deque

from geometry_msgs.msg import WrenchStamped

from .commands import IMPULSE, WRENCH
from .qos import COMMANDS, per_body_events

ODOMETRY = "odom"
KINDS = (WRENCH, IMPULSE, ODOMETRY)
ON_DEMAND_ABOVE = 256  # bodies; 768 endpoints take about 0.5 s to make and as long to destroy
ON_DEMAND_TICK_S = 0.1
ON_DEMAND_PER_TICK = 16


class BodyTopics:
    """The command subscriptions of the bodies, and (on demand) which of
    their topics are still to be made. `outputs` makes the odometry
    publishers; `on_command(body, kind)` gives a subscription's callback."""

    def __init__(self, node, outputs, on_command, on_demand=False):
        self._node = node
        self._outputs = outputs
        self._on_command = on_command
        self.on_demand = bool(on_demand)
        self.topics = {}  # (body, kind) -> the subscription's topic name
        self.subscriptions = {}  # (body, kind) -> subscription
        self._bodies = set()  # bodies whose topics are made or wanted
        self._wanted = {}  # on demand: topic name -> (body, kind), not made yet
        self._queue = deque()  # wanted topics seen in the graph, in the order seen
        self._queued = set()

    @property
    def waiting(self):
        """Topics not made yet (0 unless on demand)."""
        return len(self._wanted)

    @property
    def made(self):
        """Per-body endpoints made: command subscriptions and odometry publishers."""
        return len(self.subscriptions) + self._outputs.odometry_publishers

    def add(self, names, paths=None):
        """Topics for bodies not seen before (under `paths[name]`, an entity
        namespace, when given): made now, or wanted on demand."""
        for name in names:
            if name in self._bodies:
                continue
            self._bodies.add(name)
            path = (paths or {}).get(name, name)
            if not self.on_demand:
                for kind in (WRENCH, IMPULSE):
                    self._subscribe(name, kind, path)
                continue
            for kind in KINDS:
                self._wanted[self._node.resolve_topic_name(f"~/{path}/{kind}")] = (name, kind, path)

    def remove(self, names):
        """Bodies deleted: their subscriptions destroyed, nothing more wanted
        for them (their odometry publishers are Outputs')."""
        gone = set(names) & self._bodies
        self._bodies -= gone
        for key in [k for k in self.subscriptions if k[0] in gone]:
            self._node.destroy_subscription(self.subscriptions.pop(key))
            self.topics.pop(key, None)
        for topic in [t for t, (name, _, _) in self._wanted.items() if name in gone]:
            del self._wanted[topic]

    def found(self, topics):
        """A graph scan's (name, types) pairs: queue the wanted topics among them."""
        if not self._wanted:
            return
        for topic, _types in topics:
            if topic in self._wanted and topic not in self._queued:
                self._queue.append(topic)
                self._queued.add(topic)

    def make_queued(self, limit=ON_DEMAND_PER_TICK):
        """Make up to `limit` queued topics; how many were made."""
        made = 0
        while self._queue and made < limit:
            topic = self._queue.popleft()
            self._queued.discard(topic)
            wanted = self._wanted.pop(topic, None)
            if wanted is None:
                continue  # its body was deleted meanwhile
            name, kind, path = wanted
            if kind == ODOMETRY:
                self._outputs.add_odometry(name)
            else:
                self._subscribe(name, kind, path)
            made += 1
        return made

    def _subscribe(self, name, kind, path):
        _, command_events = per_body_events()
        sub = self._node.create_subscription(
            WrenchStamped,
            f"~/{path}/{kind}",
            self._on_command(name, kind),
            COMMANDS,
            raw=True,
            event_callbacks=command_events,
        )
        self.topics[(name, kind)] = sub.topic_name
        self.subscriptions[(name, kind)] = sub
