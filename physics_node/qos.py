"""QoS of every topic the node offers or takes, and its rosbag2 YAML form."""

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from .limits import SERVICE_QUEUE_DEPTH

# Streams: reliable so recorders and tests see every step, volatile.
STREAM = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=10,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)
# /clock and ~/bodies: a late joiner gets the latest value at once. Reliable
# + transient-local is offered, which also satisfies best-effort subscribers
# such as the sim-time clock of other nodes.
LATCHED = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=1,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)
# /tf and /tf_static as tf2_ros offers them (reliable, depth 100 / latched).
TF = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=100,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)
TF_STATIC = LATCHED
# Services: a reliable request queue deep enough for a burst of calls
# (limits.SERVICE_QUEUE_DEPTH); rclpy's default of 10 loses the 11th request
# of a burst without answering it.
SERVICES = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=SERVICE_QUEUE_DEPTH,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)
# Commands: reliable, KEEP_ALL. A KEEP_LAST reader overwrites what the node
# has not taken yet when a peer publishes faster than it is read (20,000
# wrenches at 30,000/s: 16 % applied, nothing counted); a KEEP_ALL reader
# instead withholds its acknowledgement, so a reliable writer waits (its
# `publish` blocks up to the middleware's blocking time) and nothing that
# was acknowledged is lost. The reader's history is bounded by the
# middleware's resource limits (Fast DDS: 400 samples per topic by default),
# the node's queue by limits.py. A best-effort writer is matched too; what it
# sends past a full reader is lost in transit, before the node can count it.
COMMANDS = QoSProfile(
    history=HistoryPolicy.KEEP_ALL,
    depth=100,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)


def per_body_events():
    """Event callbacks for the per-body publishers and subscriptions (odometry,
    wrench, impulse): none. rclpy otherwise gives each one handlers that log
    incompatible-QoS and incompatible-type peers, and every handler is a
    waitable the executor re-examines before every callback: with 100 bodies
    about 600 of them, over 10 ms per timer tick. The peer with the
    mismatched QoS or type still logs it on its side; the node-wide topics
    keep rclpy's default handlers."""
    from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks

    return (
        PublisherEventCallbacks(use_default_callbacks=False),
        SubscriptionEventCallbacks(use_default_callbacks=False),
    )


# rmw's "infinite" duration, as rosbag2 writes it.
_INFINITE = {"sec": 9223372036, "nsec": 854775807}

_HISTORY = {HistoryPolicy.KEEP_LAST: "keep_last", HistoryPolicy.KEEP_ALL: "keep_all"}
_RELIABILITY = {ReliabilityPolicy.RELIABLE: "reliable", ReliabilityPolicy.BEST_EFFORT: "best_effort"}
_DURABILITY = {DurabilityPolicy.VOLATILE: "volatile", DurabilityPolicy.TRANSIENT_LOCAL: "transient_local"}


def offered_qos_yaml(profile):
    """`offered_qos_profiles` channel metadata: a YAML list with one profile,
    in the string-enum layout rosbag2 has written since metadata version 9."""
    lines = [
        f"- history: {_HISTORY.get(profile.history, 'keep_last')}",
        f"  depth: {int(profile.depth)}",
        f"  reliability: {_RELIABILITY.get(profile.reliability, 'reliable')}",
        f"  durability: {_DURABILITY.get(profile.durability, 'volatile')}",
    ]
    for key in ("deadline", "lifespan"):
        lines += [f"  {key}:", f"    sec: {_INFINITE['sec']}", f"    nsec: {_INFINITE['nsec']}"]
    lines += ["  liveliness: automatic", "  liveliness_lease_duration:"]
    lines += [f"    sec: {_INFINITE['sec']}", f"    nsec: {_INFINITE['nsec']}"]
    lines += ["  avoid_ros_namespace_conventions: false"]
    return "\n".join(lines) + "\n"
