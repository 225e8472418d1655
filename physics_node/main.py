"""`physics-node`: start the physics node.

Human flags map onto ROS parameters; `--ros-args -p name:=value` works too,
and a human flag wins when both set the same parameter.
"""

import argparse
import os
import signal
import sys

import rclpy
from rclpy.exceptions import InvalidParameterTypeException, InvalidParameterValueException
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.parameter import Parameter
from rclpy.signals import SignalHandlerOptions

from physics_core import SceneError

from .dds_profile import use_reply_profile
from .foxglove_server import FoxgloveError
from .node import PhysicsNode
from .parameters import ODOMETRY_MODES, ParameterValueError, coerce


def build_parser():
    p = argparse.ArgumentParser(
        prog="physics-node",
        description="Rigid-body physics node for ROS 2: forces and impulses in, poses and contacts out.",
        epilog="ROS arguments go after --ros-args, e.g. --ros-args -p publish_every:=4",
    )
    p.add_argument("--scene", metavar="FILE", help="scene YAML file (default: the built-in scene)")
    p.add_argument("--record", metavar="FILE.mcap", help="record the session to this MCAP file")
    p.add_argument("--duration", type=float, metavar="S", help="sim seconds to run, then exit (0 = until stopped)")
    p.add_argument("--rtf", type=float, metavar="X", help="real-time factor (0 = as fast as possible)")
    p.add_argument("--paused", action="store_true", default=None, help="start paused")
    p.add_argument(
        "--max-bodies",
        type=int,
        metavar="N",
        help="most bodies a scene may declare (default 10,000; see README, Limits and hostile input)",
    )
    p.add_argument(
        "--odometry",
        choices=ODOMETRY_MODES,
        help="per-body odometry: only to topics with a subscriber (default) or every body every step",
    )
    p.add_argument(
        "--foxglove",
        nargs="?",
        type=int,
        const=DEFAULT_FOXGLOVE_PORT,
        metavar="PORT",
        help=f"serve the live world to the Foxglove app over its WebSocket protocol (port {DEFAULT_FOXGLOVE_PORT} "
        "if none given; 0 = any free port)",
    )
    p.add_argument("--foxglove-host", default="127.0.0.1", metavar="HOST",
                   help="address the Foxglove server listens on (default 127.0.0.1: this machine only; 0.0.0.0: all)")
    p.add_argument("--foxglove-rate", type=float, default=30.0, metavar="HZ",
                   help="scene updates per wall second while running (default 30; every step while paused)")
    p.add_argument(
        "--executor",
        choices=EXECUTORS,
        default="events",
        help="rclpy executor: 'events' (default; cost per tick independent of the number of topics) "
        "or 'single' (rclpy's SingleThreadedExecutor)",
    )
    return p


DEFAULT_FOXGLOVE_PORT = 8765


def foxglove_bridge(args):
    """The Foxglove server asked for by --foxglove, or None."""
    if args.foxglove is None:
        return None
    from .foxglove_server import FoxgloveBridge

    return FoxgloveBridge(args.foxglove, args.foxglove_host, args.foxglove_rate)


# rclpy's SingleThreadedExecutor rebuilds a wait set of every subscription,
# timer and service before each callback: with the two command topics per body
# that is about 1.2 ms per timer tick at 100 bodies and 16 ms at 1,000 (CPU
# time, this machine), more than the step itself. The events executor is
# woken by the middleware for what is ready: 0.08-0.12 ms per tick whatever
# the number of bodies.
EXECUTORS = ("events", "single")


def make_executor(kind="events"):
    """The executor the node is spun by; 'events' falls back to the
    single-threaded one on an rclpy without it."""
    if kind == "events":
        try:
            from rclpy.experimental import EventsExecutor
        except ImportError:
            return SingleThreadedExecutor()
        return EventsExecutor()
    return SingleThreadedExecutor()


def parameter_overrides(args):
    pairs = {
        "scene": args.scene,
        "record": args.record,
        "duration": args.duration,
        "real_time_factor": args.rtf,
        "paused": args.paused,
        "odometry": args.odometry,
        "max_bodies": args.max_bodies,
    }
    # The same checks as a parameter set at run time (ParameterValueError).
    return [Parameter(name, value=coerce(name, value)) for name, value in pairs.items() if value is not None]


def how_to_push(node):
    """The lines printed at start: how to push a body from another terminal."""
    dynamic = [n for i, n in enumerate(node.model.names) if not node.model.is_static[i]]
    body = dynamic[0] if dynamic else node.model.names[0]
    ns = node.get_fully_qualified_name()
    python = os.path.relpath(sys.executable) if not os.path.isabs(os.path.relpath(sys.executable)) else sys.executable
    one_liner = (
        f"{python} -c \"import rclpy, time; from geometry_msgs.msg import WrenchStamped as W; "
        f"from rclpy.duration import Duration; rclpy.init(); "
        f"n = rclpy.create_node('pusher'); p = n.create_publisher(W, '{ns}/{body}/impulse', 10); "
        f"m = W(); m.header.frame_id = 'world'; m.wrench.force.x = 2.0; m.wrench.force.z = 3.0; "
        f"[time.sleep(0.1) for _ in range(100) if p.get_subscription_count() == 0]; "
        f"p.publish(m); p.wait_for_all_acked(Duration(seconds=10))\""
    )
    lines = [
        f"physics: {len(node.model.names)} bodies ({_first_names(node.model.names)}) from {node.scene_path}",
        f"physics: dt = {node.world.dt:.6g} s, real-time factor {node.settings.real_time_factor:g}"
        + (", paused" if node.paused else ""),
    ]
    if node.on_demand:
        lines.append(f"physics: each body's topics are made once a peer uses them (more than "
                     f"topics_on_demand_above = {node.settings.topics_on_demand_above} bodies)")
    if node.recorder is not None:
        lines.append(f"physics: recording to {node.recorder.path} (closed cleanly on Ctrl-C)")
    lines += [
        "",
        f"Push '{body}' from another terminal (same RMW_IMPLEMENTATION and ROS_DOMAIN_ID):",
        f"  ros2 topic pub --once {ns}/{body}/impulse geometry_msgs/msg/WrenchStamped "
        f"\"{{header: {{frame_id: world}}, wrench: {{force: {{x: 2.0, z: 3.0}}}}}}\"",
        "  or, without the ros2 CLI:",
        f"  {one_liner}",
        f"  or hold a force and follow the body: {python} examples/push_and_follow.py --body {body} --force 5 0 0",
        f"Watch it: ros2 topic echo {ns}/{body}/odom",
        "",
    ]
    return "\n".join(lines)


def _first_names(names, shown=20):
    more = f" and {len(names) - shown} more" if len(names) > shown else ""
    return ", ".join(names[:shown]) + more


class StopRequest:
    """Ctrl-C and SIGTERM ask the spin loop to stop between callbacks, so a
    step or a recording write is never cut in half. A second signal stops at
    once (the recording is still closed on the way out)."""

    def __init__(self):
        self.signal_name = None

    def install(self):
        for sig in (signal.SIGINT, signal.SIGTERM):
            signal.signal(sig, self._handle)

    def _handle(self, signum, _frame):
        if self.signal_name is not None:
            raise KeyboardInterrupt
        self.signal_name = signal.Signals(signum).name

    @property
    def requested(self):
        return self.signal_name is not None


def main(argv=None):
    argv = list(sys.argv if argv is None else argv)
    args = build_parser().parse_args(rclpy.utilities.remove_ros_args(args=argv)[1:])
    try:
        overrides = parameter_overrides(args)
    except ParameterValueError as exc:
        print(f"physics-node: {exc}", file=sys.stderr, flush=True)
        return 2
    stop = StopRequest()
    stop.install()
    use_reply_profile()     # before rclpy.init: no service reply lost to slow discovery
    rclpy.init(args=argv, signal_handler_options=SignalHandlerOptions.NO)
    node = None
    status = 0
    try:
        node = PhysicsNode(parameter_overrides=overrides, foxglove=foxglove_bridge(args))
        try:
            print(how_to_push(node), flush=True)
            if node.foxglove is not None:
                print(f"physics: Foxglove server at {node.foxglove.url} "
                      "(Foxglove app: Open connection -> Foxglove WebSocket)", flush=True)
        except OSError:
            pass  # no usable stdout (closed pipe): the node runs on regardless
        executor = make_executor(args.executor)
        executor.add_node(node)
        while rclpy.ok() and not node.finished and not stop.requested:
            executor.spin_once(timeout_sec=0.1)
        if stop.requested:
            node.get_logger().info(f"{stop.signal_name}: stopping")
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except (SceneError, ParameterValueError, FoxgloveError) as exc:
        print(f"physics-node: {exc}", file=sys.stderr, flush=True)
        status = 2
    except (InvalidParameterValueException, InvalidParameterTypeException) as exc:
        # `--ros-args -p real_time_factor:=1e308`: refused by the descriptor's range
        print(f"physics-node: {' '.join(str(exc).split())}", file=sys.stderr, flush=True)
        status = 2
    finally:
        if node is not None:
            node.close()
            node.destroy_node()
        rclpy.try_shutdown()
    return status


if __name__ == "__main__":
    sys.exit(main())
