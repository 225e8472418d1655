#!/usr/bin/env python3
"""Push a body of the running physics node and follow where it goes.

    physics-node &                      # or: make run
    python examples/push_and_follow.py --body ball --force 5 0 0 --seconds 2
    python examples/push_and_follow.py --body crate --force 0 0 30 --frame body
    python examples/push_and_follow.py --body ball --impulse 0 0 4

A wrench is held on the body for `--seconds` of sim time, then released (a
zero wrench); an impulse is applied once. Meanwhile the body's odometry is
printed a few times per sim second. The node runs on sim time from /clock,
like any other node in a simulation.

The push counts from when it acts: the script waits until the physics node
has acknowledged the message (reliable delivery; on a loaded machine that can
take longer than the whole push), then follows from the first odometry whose
velocity differs from the one before the push, or, if the body does not
respond (pushed into the ground), from the sim time at which it was sent.
"""

import argparse
import sys
import time

import rclpy
from rclpy.executors import ExternalShutdownException
from geometry_msgs.msg import WrenchStamped
from nav_msgs.msg import Odometry
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.parameter import Parameter


class PushAndFollow(Node):
    def __init__(self, args):
        super().__init__("push_and_follow", parameter_overrides=[Parameter("use_sim_time", value=True)])
        self.args = args
        base = f"{args.physics.rstrip('/')}/{args.body}"
        kind = "impulse" if args.impulse else "wrench"
        self.command = self.create_publisher(WrenchStamped, f"{base}/{kind}", 10)
        self.create_subscription(Odometry, f"{base}/odom", self.on_odom, 10)
        self.pushed_at = None  # sim seconds: when the push took effect
        self.sent_at = None  # sim seconds of the newest odometry when it was sent
        self.latest_stamp = None  # sim seconds of the newest odometry
        self.twist = None  # the newest odometry's velocity, to see when the push acts
        self.last_print = -1.0
        self.done = False

    def push(self, vector):
        msg = WrenchStamped()
        msg.header.stamp = self.get_clock().now().to_msg()
        # `world` axes, or the body's own axes (frame_id = the body's name).
        msg.header.frame_id = self.args.body if self.args.frame == "body" else "world"
        msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z = (float(v) for v in vector)
        self.command.publish(msg)
        # reliable delivery: returns once the physics node has the message
        return self.command.wait_for_all_acked(Duration(seconds=self.args.wait))

    def on_odom(self, msg):
        t = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
        twist = msg.twist.twist
        twist = (twist.linear.x, twist.linear.y, twist.linear.z, twist.angular.x, twist.angular.y, twist.angular.z)
        moved = self.sent_at is not None and twist != self.twist and t > self.sent_at
        self.latest_stamp, self.twist = t, (self.twist if self.sent_at is not None else twist)
        if self.pushed_at is None and moved:
            self.pushed_at = t - 1e-9  # the first step the push acted in
        if self.pushed_at is None or t < self.pushed_at:
            return  # odometry from before the push
        if t - self.last_print >= 1.0 / self.args.print_rate:
            p, v = msg.pose.pose.position, msg.twist.twist.linear
            print(
                f"t={t:8.3f} s  {self.args.body}: position ({p.x:+.4f}, {p.y:+.4f}, {p.z:+.4f}) m"
                f"  body-frame velocity ({v.x:+.4f}, {v.y:+.4f}, {v.z:+.4f}) m/s",
                flush=True,
            )
            self.last_print = t
        if t - self.pushed_at >= self.args.seconds:
            self.done = True


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--body", default="ball", help="body name in the scene (default: ball)")
    group = p.add_mutually_exclusive_group()
    group.add_argument("--force", nargs=3, type=float, metavar=("FX", "FY", "FZ"), help="held force, N")
    group.add_argument("--impulse", nargs=3, type=float, metavar=("JX", "JY", "JZ"), help="one impulse, N·s")
    p.add_argument("--frame", choices=("world", "body"), default="world", help="axes of the vector")
    p.add_argument("--seconds", type=float, default=2.0, help="sim seconds to hold the force and follow")
    p.add_argument("--print-rate", type=float, default=4.0, help="lines per sim second")
    p.add_argument("--physics", default="/physics", help="the physics node's name (default /physics)")
    p.add_argument("--wait", type=float, default=10.0, help="wall seconds to wait for the physics node")
    args = p.parse_args(rclpy.utilities.remove_ros_args(args=sys.argv if argv is None else argv)[1:])
    if args.force is None and args.impulse is None:
        args.force = [5.0, 0.0, 0.0]

    rclpy.init(args=argv)
    node = PushAndFollow(args)
    try:
        # Wait until the physics node hears us and we hear it: its odometry
        # also says what sim time it is (paused nodes publish none: unpause).
        deadline = time.monotonic() + args.wait
        while node.command.get_subscription_count() == 0 or node.latest_stamp is None:
            if time.monotonic() > deadline:
                print(f"no running physics node on {node.command.topic_name}", file=sys.stderr)
                return 1
            rclpy.spin_once(node, timeout_sec=0.05)
        node.sent_at = node.latest_stamp
        if not node.push(args.impulse or args.force):
            print(f"the physics node did not acknowledge {node.command.topic_name}", file=sys.stderr)
            return 1
        print(f"{'impulse' if args.impulse else 'force'} {args.impulse or args.force} sent on "
              f"{node.command.topic_name} at t={node.sent_at:.3f} s", flush=True)
        respond_by = time.monotonic() + args.wait
        deadline = respond_by + args.seconds * 100
        while not node.done and time.monotonic() < deadline:
            rclpy.spin_once(node, timeout_sec=0.05)
            if node.pushed_at is None and time.monotonic() > respond_by:
                node.pushed_at = node.sent_at  # the body did not respond: count from the send
        if args.impulse is None:
            node.push([0.0, 0.0, 0.0])  # let go (waits until the node has it)
        return 0
    except (KeyboardInterrupt, ExternalShutdownException):  # Ctrl-C, or SIGTERM through rclpy's handler
        return 0
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    sys.exit(main())
