"""`physics-replay FILE.mcap`: play a recording back onto ROS, re-run it
exactly (`--resimulate`), or write a crash-cut file out complete (`--recover`).
"""

import argparse
import sys
import time

import rclpy
from rclpy.duration import Duration
from rclpy.executors import ExternalShutdownException
from rosgraph_msgs.msg import Clock

from msg_adapters import message_class, time_msg

from .dds_profile import use_reply_profile
from .qos import LATCHED, STREAM
from .recording_reader import Recording, recover
from .resimulate import ERROR, resimulate

REPLAY_NODE = "physics_replay"


def build_parser():
    p = argparse.ArgumentParser(
        prog="physics-replay",
        description="Replay a physics_node recording: republish it with sim-time pacing and /clock, "
        "or re-run it and check every pose bit for bit.",
    )
    p.add_argument("file", help="recording (.mcap)")
    p.add_argument(
        "--rate",
        type=float,
        default=1.0,
        help="playback speed; 2 = twice real time, 0 = as fast as reliable subscribers acknowledge",
    )
    p.add_argument(
        "--resimulate",
        action="store_true",
        help="rebuild the world from the embedded scene, re-apply the recorded commands and compare poses; "
        "exit status 0 match, 1 diverge, 2 error",
    )
    p.add_argument(
        "--wait",
        type=float,
        default=2.0,
        metavar="S",
        help="wall seconds to wait for a subscriber to connect before playing (starts as soon as one has)",
    )
    p.add_argument("--recover", metavar="OUT", help="write the readable part of FILE to OUT as a complete MCAP")
    return p


def main(argv=None):
    argv = list(sys.argv if argv is None else argv)
    args = build_parser().parse_args(rclpy.utilities.remove_ros_args(args=argv)[1:])
    if args.resimulate:
        result = resimulate(args.file)
        print(result.report(), flush=True)
        return result.status
    try:
        if args.recover:
            count = recover(args.file, args.recover)
            print(f"wrote {count} messages to {args.recover}", flush=True)
            return 0
        recording = Recording(args.file)
    except (OSError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr, flush=True)
        return ERROR
    if not 0 <= args.rate < float("inf"):
        print(f"error: --rate must be a finite number >= 0, got {args.rate!r}", file=sys.stderr)
        return ERROR
    use_reply_profile()     # before rclpy.init: no service reply lost to slow discovery
    rclpy.init(args=argv)
    node = rclpy.create_node(REPLAY_NODE)
    try:
        count = republish(node, recording, args.rate, args.wait)
        print(f"replayed {count} messages from {args.file}", flush=True)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


def _qos_of(channel):
    text = channel.metadata.get("offered_qos_profiles", "") if channel else ""
    return LATCHED if "transient_local" in text else STREAM


def _wait_for_listeners(publishers, timeout, settle=0.5):
    """Wait until some publisher has a subscriber and no further publisher has
    matched for `settle` seconds (one listening process matches its
    subscriptions one by one), or until `timeout`."""
    end = time.monotonic() + max(timeout, 0.0)
    matched, last_change = 0, None
    while time.monotonic() < end:
        now_matched = sum(p.get_subscription_count() > 0 for p in publishers)
        if now_matched > matched:
            matched, last_change = now_matched, time.monotonic()
        elif matched and time.monotonic() - last_change >= settle:
            return True
        time.sleep(0.02)
    return matched > 0


def republish(node, recording, rate, wait=2.0):
    """Publish every recorded message in file order, paced by its log time
    (sim time) divided by `rate`, with /clock at each new sim time. The
    recorded /clock is replaced by this one."""
    clock = node.create_publisher(Clock, "/clock", LATCHED)
    # Every publisher exists before the first message, and play starts once
    # someone listens: discovering a new process can take seconds, and
    # volatile messages sent before that are lost.
    publishers = {
        topic: node.create_publisher(message_class(type_name), topic, _qos_of(recording.channels.get(topic)))
        for topic, type_name in recording.topics().items()
        if topic != "/clock"
    }
    _wait_for_listeners([clock, *publishers.values()], wait)
    window = _InFlight() if rate == 0 else None
    wall_start = sim_start = last = None
    count = 0
    for m in recording.messages():
        if not rclpy.ok():
            break
        if m.topic == "/clock":
            continue
        t = m.log_time
        if sim_start is None or t < last:  # first message, or a reset
            wall_start, sim_start = time.monotonic(), t
        if rate > 0:
            delay = wall_start + (t - sim_start) / 1e9 / rate - time.monotonic()
            if delay > 0:
                time.sleep(delay)
        if t != last:
            _publish(clock, Clock(clock=time_msg(t)), window)
            last = t
        _publish(publishers[m.topic], m.data, window)
        count += 1
    _drain([clock, *publishers.values()])
    return count


class _InFlight:
    """Flow control for `--rate 0`: before a publisher's history (its QoS
    depth) could overwrite a message no reliable subscriber has acknowledged
    yet, wait until they have (up to `timeout` s, so a stalled subscriber
    slows the replay down but cannot hang it). Without it, publishing as
    fast as possible through a depth-10 history delivered 22-33 % of the
    poses."""

    def __init__(self, timeout=1.0):
        self.timeout = Duration(nanoseconds=int(timeout * 1e9))
        self._sent = {}

    def before(self, publisher):
        sent = self._sent.get(publisher, 0)
        if sent >= max(int(publisher.qos_profile.depth), 1):
            publisher.wait_for_all_acked(self.timeout)
            sent = 0
        self._sent[publisher] = sent + 1


def _publish(publisher, msg, window):
    if window is not None:
        window.before(publisher)
    publisher.publish(msg)


def _drain(publishers, timeout=2.0):
    """Wait (up to `timeout` s in all) until every reliable subscriber has
    acknowledged what was published: a process that exits at once takes its
    last, still unsent messages with it (the final /clock and poses)."""
    deadline = time.monotonic() + timeout
    for p in publishers:
        left = deadline - time.monotonic()
        if left <= 0:
            return
        p.wait_for_all_acked(Duration(nanoseconds=int(left * 1e9)))


if __name__ == "__main__":
    sys.exit(main())
