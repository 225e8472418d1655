"""Scenes, user measures and recordings shared by the physics-sweep tests."""
import os
import time

# A ball dropped on a floor (contacts) beside a second ball in free flight.
DROP_SCENE = {
    "dt": 1.0 / 240.0,
    "integrator": "semi_implicit_euler",
    "gravity": [0.0, 0.0, -9.81],
    "effects": {"contacts": {"iterations": 8, "ccd": True, "sleep": False}},
    "bodies": [
        {"name": "ground", "shape": {"type": "plane", "normal": [0, 0, 1], "offset": 0.0}},
        {"name": "ball", "shape": {"type": "sphere", "radius": 0.1}, "mass": 1.0,
         "restitution": 0.5, "position": [0.0, 0.0, 1.0]},
        {"name": "probe", "shape": {"type": "sphere", "radius": 0.05}, "mass": 0.2,
         "position": [5.0, 0.0, 2.0], "velocity": [0.0, 0.0, 3.0]},
    ],
    "friction": [{"a": "default", "b": "default", "static": 0.5, "kinetic": 0.4}],
}

# No contacts: a closed form for every step of semi-implicit Euler.
FREE_SCENE = {
    "dt": 0.01,
    "integrator": "semi_implicit_euler",
    "gravity": [0.0, 0.0, -9.81],
    "bodies": [{"name": "ball", "shape": {"type": "sphere", "radius": 0.1}, "mass": 2.0,
                "position": [0.0, 0.0, 1.0], "velocity": [1.0, 0.0, 4.0]}],
}


def ball_height(world):
    """A user measure: the ball's height above its radius, m."""
    return float(world.body("ball").position[2] - 0.1)


def not_a_number(world):
    return "high"


# ---- for the Ray tests ----------------------------------------------------------
STALL_ENV = "PHYSICS_SWEEP_TEST_STALL"


def stall_once(world):
    """The ball's height; the first run to find `$STALL_ENV/armed` claims it
    (an atomic rename), writes its pid and waits there to be killed, so a
    test kills a worker that is certainly inside a task."""
    folder = os.environ.get(STALL_ENV)
    if folder:
        try:
            os.rename(os.path.join(folder, "armed"), os.path.join(folder, "claimed"))
        except FileNotFoundError:
            pass
        else:
            with open(os.path.join(folder, "pid.tmp"), "w") as f:
                f.write(str(os.getpid()))
            os.replace(os.path.join(folder, "pid.tmp"), os.path.join(folder, "pid"))
            deadline = time.monotonic() + 120.0
            while time.monotonic() < deadline:     # killed long before
                time.sleep(0.05)
    return ball_height(world)


def slow_height(world):
    """The ball's height, after 10 ms of wall time: runs long enough that a
    sweep can be interrupted half-way."""
    time.sleep(0.01)
    return ball_height(world)


# A box thrown up tumbling about all three axes beside a falling ball: the
# corpus recordings (the ball takes an impulse on the way).
SPIN_SCENE = """\
dt: 0.004
integrator: velocity_verlet
gravity: earth
bodies:
  - {name: ball, shape: {type: sphere, radius: 0.15}, mass: 1.5, position: [0, 0, 2]}
  - name: box
    shape: {type: box, half_extents: [0.3, 0.1, 0.05]}
    density: 700.0
    position: [1, 0.5, 1]
    velocity: [0, 0, 2]
    angular_velocity: [1.1, -0.4, 3.0]
"""


def write_recording(path, scene_text, steps, impulse_at=None, tamper_step=None, node="/physics"):
    """A recording as the node writes one (scene attachment, session metadata,
    commands at the step that applied them, every step's PoseArray), made in
    this process through the node's own Stepper and Recorder; `tamper_step`
    moves the second body's recorded y by one ulp at that step."""
    import tempfile

    import numpy as np
    from geometry_msgs.msg import PoseArray, WrenchStamped
    from rclpy.serialization import serialize_message

    from msg_adapters import pose_array, wrench_stamped
    from physics_core import load_scene
    from physics_node.commands import Command
    from physics_node.recorder import SCENE_MEDIA_TYPE, SESSION_METADATA, Recorder
    from physics_node.stepping import Stepper

    with tempfile.TemporaryDirectory() as tmp:
        scene_path = os.path.join(tmp, "scene.yaml")
        with open(scene_path, "w") as f:
            f.write(scene_text)
        world = load_scene(scene_path)
    stepper = Stepper(world)
    with Recorder(path) as rec:
        rec.add_attachment("scene.yaml", scene_text.encode(), SCENE_MEDIA_TYPE)
        rec.add_metadata(SESSION_METADATA, {"node": node, "engine_version": "0.1.0"})
        for _ in range(steps):
            t_ns = round(world.time * 1e9)
            if world.step_index == impulse_at:
                msg = wrench_stamped([0.0, 0.0, 3.0], stamp_ns=t_ns)
                raw = serialize_message(msg)
                topic = f"{node}/ball/impulse"
                stepper.submit(Command("impulse", "ball", "world", np.array([0.0, 0.0, 3.0]), np.zeros(3),
                                       topic=topic, raw=raw))
                rec.write(topic, WrenchStamped, raw, t_ns, step=world.step_index)
            stepper.advance()
            msg = pose_array(world.state.pos, world.state.quat, round(world.time * 1e9))
            if world.step_index == tamper_step:
                msg.poses[1].position.y = float(np.nextafter(msg.poses[1].position.y, 1.0))
            rec.write(f"{node}/poses", PoseArray, serialize_message(msg), round(world.time * 1e9),
                      step=world.step_index)
