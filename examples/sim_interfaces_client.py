"""Drive the physics node only through the ROS simulator standard
(simulation_interfaces): spawn a box above the ground, step 240 times while
paused, read its state, teleport it, delete it, reset.

    make run                                              # in one terminal
    .venv/bin/python examples/sim_interfaces_client.py    # in another

Any simulator that implements the standard's services under a node (Gazebo's
`/gzserver/...`) can be driven the same way with --node.
"""

import argparse
import sys

import rclpy
from geometry_msgs.msg import PoseStamped
from simulation_interfaces import srv
from simulation_interfaces.msg import EntityState, Result, SimulationState

BOX = """\
name: falling_box
shape: {type: box, half_extents: [0.2, 0.2, 0.2]}
mass: 2.0
material: steel
"""


class Client:
    def __init__(self, node_name):
        self.node = rclpy.create_node("sim_interfaces_client")
        self.prefix = node_name.rstrip("/")
        self.clients = {}

    def call(self, service, timeout=30.0, **fields):
        kind = getattr(srv, "".join(part.capitalize() for part in service.split("_")))
        client = self.clients.get(service) or self.node.create_client(kind, f"{self.prefix}/{service}")
        self.clients[service] = client
        if not client.wait_for_service(timeout_sec=timeout):
            sys.exit(f"no service {self.prefix}/{service}: is the node running (make run)?")
        future = client.call_async(kind.Request(**fields))
        rclpy.spin_until_future_complete(self.node, future, timeout_sec=timeout)
        reply = future.result()
        if reply is None:
            sys.exit(f"{service}: no reply within {timeout} s")
        result = getattr(reply, "result", None)
        if result is not None and result.result != Result.RESULT_OK:
            sys.exit(f"{service} failed with code {result.result}: {result.error_message}")
        return reply


def show(label, state):
    p, v = state.pose.position, state.twist.linear
    print(f"{label}: t = {state.header.stamp.sec + state.header.stamp.nanosec * 1e-9:.4f} s, "
          f"position ({p.x:.4f}, {p.y:.4f}, {p.z:.4f}) m, velocity ({v.x:.4f}, {v.y:.4f}, {v.z:.4f}) m/s")  # fmt: skip


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--node", default="/physics", help="the simulator node's name (default /physics)")
    parser.add_argument("--height", type=float, default=2.0, help="spawn height of the box, m")
    args = parser.parse_args(argv)
    rclpy.init()
    c = Client(args.node)
    try:
        features = c.call("get_simulator_features").features
        print(f"spawn formats: {features.spawn_formats}; {len(features.features)} features")
        state = c.call("get_simulation_state").state.state
        if state == SimulationState.STATE_PLAYING:
            c.call("set_simulation_state", state=SimulationState(state=SimulationState.STATE_PAUSED))

        pose = PoseStamped()
        pose.header.frame_id = "world"
        pose.pose.position.z = args.height
        name = c.call("spawn_entity", name="falling_box", allow_renaming=True, resource_string=BOX, initial_pose=pose).entity_name
        print(f"spawned {name!r} at z = {args.height} m")
        show("before stepping", c.call("get_entity_state", entity=name).state)

        c.call("step_simulation", steps=240)
        show("after 240 steps", c.call("get_entity_state", entity=name).state)

        teleport = EntityState()
        teleport.header.frame_id = "world"
        teleport.pose.position.x, teleport.pose.position.z = 1.0, 3.0
        teleport.twist.linear.x = 0.5
        c.call("set_entity_state", entity=name, state=teleport)
        show("teleported", c.call("get_entity_state", entity=name).state)
        c.call("step_simulation", steps=24)
        show("24 steps later", c.call("get_entity_state", entity=name).state)

        c.call("delete_entity", entity=name)
        print(f"deleted {name!r}; entities now: {c.call('get_entities').entities}")
        c.call("reset_simulation", scope=srv.ResetSimulation.Request.SCOPE_ALL)
        print("reset: the scene as loaded, at t = 0")
    finally:
        c.node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
