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
"""

import argparse
import sys
import time

import rclpy
from rclpy.executors import ExternalShutdownException
from geometry_msgs.msg import WrenchStamped
from nav_msgs.msg import Odometry
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
        self.pushed_at = None  # sim seconds
        self.latest_stamp = None  # sim seconds of the newest odometry
        self.last_print = -1.0
        self.done = False

    def push(self, vector):
        msg = WrenchStamped()
        msg.header.stamp = self.get_clock().now().to_msg()
        # `world` axes, or the body's own axes (frame_id = the body's name).
        msg.header.frame_id = self.args.body if self.args.frame == "body" else "world"
        msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z = (float(v) for v in vector)
        self.command.publish(msg)

    def on_odom(self, msg):
        t = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
        self.latest_stamp = t
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
        node.push(args.impulse or args.force)
        node.pushed_at = node.latest_stamp
        print(f"{'impulse' if args.impulse else 'force'} {args.impulse or args.force} sent on "
              f"{node.command.topic_name} at t={node.pushed_at:.3f} s", flush=True)
        deadline = time.monotonic() + args.wait + args.seconds * 100
        while not node.done and time.monotonic() < deadline:
            rclpy.spin_once(node, timeout_sec=0.05)
        if args.impulse is None:
            node.push([0.0, 0.0, 0.0])  # let go
            time.sleep(0.2)
        return 0
    except (KeyboardInterrupt, ExternalShutdownException):  # Ctrl-C, or SIGTERM through rclpy's handler
        return 0
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    sys.exit(main())
