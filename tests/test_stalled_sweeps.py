"""The sequential-impulse sweeps stop once their largest change has stalled
(sequential_impulses.solve_velocities: above shock_propagation.STALL times
the largest two sweeps before), where the shock-propagation sweep follows
them and settles what they leave.

The bug this guards: a pile of cubes at rest (benchmarks/box_pile.py) ran
all its `iterations` sweeps every substep: each cube's four corners share
its load in a line of ways, and the sweeps move the load along that line
by about as much every sweep (converging at about 0.998 a sweep), the
largest change 4.3e-5 N·s in the third sweep and in the eighth, above the
stop (1.3e-5); with a face's points moved together first
(sequential_impulses.even_share), 5.4e-5 and 5.2e-5, about 0.992 a sweep.
Checked here on that pile after a second: more sweeps do
not shrink the change, the sweeps now stop at it, and the shock sweep after
them leaves the bodies' velocities as it leaves them after all eight
sweeps, within its own settle tolerance (measured: 1.6e-8 m/s, 1.6e-7 rad/s);
and a gentle collision in the air beside the pile, which no shock sweep
visits, keeps its solve within the velocity tolerance.
"""
import numpy as np

from benchmarks.box_pile import boxes
from benchmarks.engines import scene_of
from physics_core import load_scene
from physics_core.collision import shock_propagation as SP
from physics_core.collision.contact_data import (ITERATIONS, RESTING_BLOCK, SHOCK_ON,
                                                 VELOCITY_TOLERANCE)
from physics_core.collision.contact_stages import SETTLE
from physics_core.collision.scratch import CURSOR
from physics_core.collision.sequential_impulses import least_mass, solve_velocities
from substep_rows import rows_before_solve

DT = 1 / 240


def pile_at_rest(n=100):
    """The benchmark's pile of n cubes (sleep off) one second after the drop."""
    w = load_scene(scene_of(boxes(n), DT))
    w.step(240)
    return w


def solved(w, iterations, stall):
    """One substep's sweeps as solve_stage runs them (at most `iterations`,
    stall factor `stall`), then the shock sweep: (sweeps, last change, the
    stop, vel, omega after both)."""
    R, I, M, MI, vel, omega, quat, store = rows_before_solve(w, DT)
    cs = w.contact_system
    limit = cs.fp[VELOCITY_TOLERANCE] * least_mass(R)
    changes = np.empty(len(MI))
    sweeps, change = solve_velocities(R, I, M, MI, vel, omega, iterations,
                                      (limit, SETTLE * limit, stall), changes)
    store[1][CURSOR] = 0
    SP.shock_sweep(R, I, M, MI, vel, omega, len(vel), cs.ip[SHOCK_ON],
                   SETTLE * cs.fp[VELOCITY_TOLERANCE], (w._inv_mass, w.inv_inertia, quat),
                   cs.ip[RESTING_BLOCK] != 0, (changes, SETTLE * limit), store)
    return sweeps, change, limit, vel, omega


def test_a_pile_of_cubes_at_rest_stops_sweeping_when_its_change_stalls():
    w = pile_at_rest()
    iterations = w.contact_system.ip[ITERATIONS]
    _, at_three, limit, _, _ = solved(w, 3, np.inf)
    full, at_all, _, v_all, o_all = solved(w, iterations, np.inf)
    assert full == iterations and at_all >= limit, "the pile's sweeps converged: no cycle"
    # five more sweeps leave the largest change where it was
    assert at_all > SP.STALL * at_three, (at_three, at_all)
    sweeps, _, _, v, o = solved(w, iterations, SP.STALL)
    assert sweeps == 3            # the first sweep with a change two sweeps before
    # the shock sweep settles every body on its supports either way
    settle = SETTLE * w.contact_system.fp[VELOCITY_TOLERANCE]
    assert np.abs(v - v_all).max() < settle
    assert np.abs(o - o_all).max() * 0.1 < settle        # at a cube's 0.1 m half size


def test_a_gentle_collision_in_the_air_beside_the_pile_keeps_its_solve_within_the_tolerance():
    """The stop is on the largest change of the whole solve: a group of bodies
    touching nothing immovable, which no shock sweep visits, is cut with
    the pile only when its own changes have fallen under the pile's. Eight
    cubes (masses 0.1 to 10 kg) in a row in the air beside the resting
    pile, the first pushed into the others at 0.05 m/s: its sweeps stop at
    5 of 8, and the row's velocities differ from those after all eight by
    less than the velocity tolerance the sweeps stop at (measured 2.8e-5
    m/s, and 2.8e-4 rad/s: 2.8e-5 m/s at a cube's 0.1 m half size)."""
    w = pile_at_rest()
    masses = [1.0, 1.0, 10.0, 1.0, 0.1, 1.0, 1.0, 1.0]
    TURNED = [np.cos(0.01), 0.0, 0.0, np.sin(0.01)]        # 0.02 rad about z
    for k, m in enumerate(masses):
        w.add_body({"name": f"f{k}", "shape": {"type": "box", "half_extents": [0.1, 0.1, 0.1]},
                    "mass": m, "position": [10.0 + 0.199 * k, 0.0, 20.0],
                    "orientation": [1.0, 0.0, 0.0, 0.0] if k % 2 == 0 else TURNED,
                    "velocity": [0.05 if k == 0 else 0.0, 0.015 * (k % 2), 0.0],
                    "angular_velocity": [0.0, 0.0, 0.05 if k == 1 else 0.0]})
    row = [list(w.model.names).index(f"f{k}") for k in range(len(masses))]
    tolerance = w.contact_system.fp[VELOCITY_TOLERANCE]
    ends = {}
    for stall in (np.inf, SP.STALL):
        R, I, M, MI, vel, omega, quat, store = rows_before_solve(w, DT)
        assert (np.isin(I[:, 0], row) | np.isin(I[:, 1], row)).sum() >= 7 * 2  # the row touches
        limit = tolerance * least_mass(R)
        sweeps, _ = solve_velocities(R, I, M, MI, vel, omega, w.contact_system.ip[ITERATIONS],
                                     (limit, SETTLE * limit, stall), np.empty(len(MI)))
        ends[stall] = (sweeps, vel[row], omega[row])
    assert ends[np.inf][0] == w.contact_system.ip[ITERATIONS] and ends[SP.STALL][0] < ends[np.inf][0]
    assert np.abs(ends[SP.STALL][1] - ends[np.inf][1]).max() < tolerance
    assert np.abs(ends[SP.STALL][2] - ends[np.inf][2]).max() * 0.1 < tolerance
