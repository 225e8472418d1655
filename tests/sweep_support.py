"""Scenes and a user measure shared by the physics-sweep tests."""

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
