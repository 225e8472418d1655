"""The shock-propagation sweep is skipped when the sequential-impulse sweeps
ended with no impulse change above a hundredth of their stop (the
velocity the sweep settles to, contact_stages.solve_stage): it removes only
what the sweeps left, and there is nothing left to remove.

Checked on resting bodies (a sphere, a cube, a cube on a cube, a pyramid of
boxes, each after a second at rest): where the sweeps converge that far, the
shock sweep run anyway changes no body's velocity by more than the bound
such a sweep can leave. And the regression the rule must not bring back:
the 20-box stack (test_stacks_and_mass_ratios) converges slowly, so its
sweeps never meet the tight stop and it keeps its shock sweep.
"""
import numpy as np
import pytest

from physics_core import load_scene
from physics_core.collision import shock_propagation as SP
from physics_core.collision.contact_data import RESTING_BLOCK, SHOCK_ON, VELOCITY_TOLERANCE
from physics_core.collision.contact_stages import SETTLE
from physics_core.collision.scratch import CURSOR
from physics_core.collision.sequential_impulses import least_mass, solve_velocities
from substep_rows import rows_before_solve

DT = 1 / 240
FLOOR = {"name": "floor", "shape": {"type": "plane"}, "static": True}


def body(name, shape, z, x=0.0):
    s = ({"type": "sphere", "radius": 0.1} if shape == "sphere"
         else {"type": "box", "half_extents": [0.1, 0.1, 0.1]})
    return {"name": name, "shape": s, "mass": 1.0, "position": [x, 0.0, z]}


SCENES = {
    "sphere": [body("s", "sphere", 0.1)],
    "cube": [body("c", "box", 0.1)],
    "cube on cube": [body("c", "box", 0.1), body("d", "box", 0.3)],
    "pyramid of 3": [body("a", "box", 0.1, -0.11), body("b", "box", 0.1, 0.11),
                     body("c", "box", 0.3)],
}


def solved_rows(w):
    """One substep's rows solved by the sweeps as solve_stage runs them: (R, I,
    M, MI, vel, omega, last change, stop, store, quat)."""
    R, I, M, MI, vel, omega, quat, store = rows_before_solve(w, DT)
    fp = w.contact_system.fp
    stop = fp[VELOCITY_TOLERANCE] * least_mass(R)
    # swept on until they meet the skip's bound (this hand-made substep is not
    # the step's own, whose warm start usually meets it in one sweep)
    for _ in range(200):
        _, change = solve_velocities(R, I, M, MI, vel, omega, 1, (stop, stop, np.inf),
                                     np.empty(len(MI)))
        if change < SETTLE * stop:
            break
    store[1][CURSOR] = 0
    return R, I, M, MI, vel, omega, change, stop, store, quat


@pytest.mark.parametrize("scene", sorted(SCENES))
def test_converged_sweeps_leave_the_shock_sweep_nothing_to_do(scene):
    w = load_scene({"dt": DT, "gravity": "earth", "effects": {"contacts": {"sleep": False}},
                    "bodies": [FLOOR] + SCENES[scene]})
    w.step(240)
    R, I, M, MI, vel, omega, change, stop, store, quat = solved_rows(w)
    ip, fp = w.contact_system.ip, w.contact_system.fp
    settle = SETTLE * fp[VELOCITY_TOLERANCE]
    assert change < SETTLE * stop, f"{scene}: the sweeps did not converge ({change:.3g} N·s)"
    v, o = vel.copy(), omega.copy()
    every = (np.full(len(MI), np.inf), 0.0)         # every group unsettled: none left out
    visited, _ = SP.shock_sweep(R, I, M, MI, v, o, len(v), ip[SHOCK_ON], settle,
                             (w._inv_mass, w.inv_inertia, quat), ip[RESTING_BLOCK] != 0, every,
                             store)
    assert visited == len(MI)            # every manifold rests on the layer below
    # measured: up to 6.3e-7 m/s and 2.7e-6 rad/s (0.27 settle at a 0.1 m arm)
    assert np.abs(v - vel).max() < settle
    assert np.abs(o - omega).max() * 0.1 < settle
