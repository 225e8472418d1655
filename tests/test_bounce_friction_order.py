"""Regression: a box landing across two boxes left its plane in the collision
pass (physics_core/collision/visit_order.py).

Three cubes in the x–z plane, the top one landing at 2.3 m/s across the
two below (the speed the top rows of a pyramid of 10,000 boxes land at):
the scene is its own mirror image in y, so no body may move along y or
turn about x or z. The pass applied each corner's friction in key order,
two corners of one side of the face first, and left the bodies moving at
up to 4.78 mm/s along y and turning at 0.138 rad/s about z after one
substep. From opposite corners first it leaves 1.46 mm/s and 0.027 rad/s:
point-by-point friction still turns the body between the first two
corners and the others, less. Checked on the pass itself
(rows_before_solve: the rows of the impact substep, the pass applied), and
over a second of the scene (the boxes stay within 0.06 mm of their plane).
"""
import numpy as np
import pytest

from physics_core import load_scene
from substep_rows import rows_before_solve

DT = 1 / 240
HALF = 0.1
SPEED = 2.3
FLOOR = {"name": "floor", "shape": {"type": "plane"}, "static": True}


def cube(name, x, z, vz=0.0):
    return {"name": name, "shape": {"type": "box", "half_extents": [HALF] * 3}, "mass": 1.0,
            "position": [x, 0.0, z], "velocity": [0.0, 0.0, vz]}


def three_boxes():
    with pytest.warns(UserWarning, match="fallback"):
        return load_scene({"dt": DT, "gravity": "earth",
                           "effects": {"contacts": {"sleep": False}},
                           "bodies": [FLOOR, cube("left", -1.01 * HALF, HALF),
                                      cube("right", 1.01 * HALF, HALF),
                                      cube("top", 0.0, 3 * HALF + 0.002, -SPEED)]})


def _out_of_plane(vel, omega):
    """The largest y velocity (m/s) and x, z turn (rad/s) of the boxes."""
    return float(np.abs(vel[1:, 1]).max()), float(np.abs(omega[1:, [0, 2]]).max())


def test_box_landing_across_two_boxes_left_its_plane_in_the_pass():
    R, I, M, MI, vel, omega, quat, store = rows_before_solve(three_boxes(), DT)
    assert np.abs(omega[1:, 1]).max() > 1.0       # the blow turns them in the plane
    drift, turn = _out_of_plane(vel, omega)
    assert drift <= 2.5e-3 and turn <= 0.05


def test_box_landing_across_two_boxes_stays_in_its_plane():
    w = three_boxes()
    for _ in range(240):
        w.step()
        assert np.abs(w.state.pos[1:, 1]).max() <= 1e-4     # m, over the first second
