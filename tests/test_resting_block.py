"""The resting solve of the shock-propagation sweep (physics_core/collision/
resting_block.py): a body on one frozen support through three or more
points is settled at once, to the state the sweeps converge to.

Checked on the manifold itself (every row's condition met after the solve,
the impulses within their bounds), against the sweeps with the solve off
(`resting_block: false`), and where it must decline (a sliding box, an
edge of two points).
"""
import numpy as np
import pytest

from physics_core import load_scene
from physics_core.collision import contact_stages as CS
from physics_core.collision import shock_propagation as SP
from physics_core.collision.contact_build import row_velocity
from physics_core.collision.contact_layout import BIAS, BODY_A, BODY_B, INV_MASS_A, LAM
from physics_core.collision.manifold_friction import COUNT, FIRST, M_LAM, M_MU_S, RADIUS
from physics_core.collision.resting_block import WS_SHAPE, settle_resting
from physics_core.collision.scratch import CURSOR
from physics_core.collision.sequential_impulses import solve_velocities
from substep_rows import rows_before_solve

FLOOR = {"name": "floor", "shape": {"type": "plane"}, "static": True, "material": "steel"}
DT = 1 / 240
ONE = np.array([0])        # the manifold solved: the first (the lowest body's)
TOLERANCE = 1e-6           # m/s, the settle's (1/100 of the default velocity_tolerance)


def cube(name, z, x=0.0, mass=1.0, half=0.1, velocity=(0.0, 0.0, 0.0)):
    return {"name": name, "shape": {"type": "box", "half_extents": [half, half, half]},
            "mass": mass, "material": "steel", "restitution": 0.0, "position": [x, 0.0, z],
            "velocity": list(velocity)}


def world(bodies, **contacts):
    return load_scene({"dt": DT, "gravity": "earth",
                       "effects": {"contacts": dict({"sleep": False}, **contacts)},
                       "bodies": [FLOOR] + bodies})


def one_sided_manifolds(w):
    """The shock sweep's inputs one substep on: the rows solved by the
    sweeps, then the layers' one-sided copies (as contact_substep builds them)."""
    R, I, M, MI, vel, omega, quat, store = rows_before_solve(w, DT)
    ip = w.contact_system.ip
    solve_velocities(R, I, M, MI, vel, omega, ip[CS.ITERATIONS], (-1.0, -1.0, np.inf),
                     np.empty(len(MI)))
    store[1][CURSOR] = 0
    layer, _ = SP.support_layers(R, I, MI, len(vel), store)
    order, _, _ = SP._upward_order(I, MI, layer, store)
    one_sided = tuple(np.array(x) for x in SP._one_sided(R, I, M, MI, layer, order, store))
    return one_sided, vel, omega, (w._inv_mass, w.inv_inertia, quat)


def upper(one_sided, m):
    """The body of manifold m whose side of the one-sided rows is not frozen."""
    R1, I1, _, MI1 = one_sided
    first = MI1[m, FIRST]
    return I1[first, BODY_B] if R1[first, INV_MASS_A] == 0.0 else I1[first, BODY_A]


def test_a_cube_on_the_floor_is_settled_with_every_row_met():
    w = world([cube("c", 0.1 - 0.001)])
    w.step(60)
    one_sided, vel, omega, masses = one_sided_manifolds(w)
    R1, I1, M1, MI1 = one_sided
    assert MI1[0, COUNT] == 4
    # a nudge the rows must take out, small enough that every corner keeps
    # pushing and friction holds: a slip, a sink, a tilt rate and a twist
    vel[1] += (0.002, -0.001, -0.01)
    omega[1] += (0.03, -0.02, 0.01)
    assert settle_resting(one_sided, ONE, upper(one_sided, 0), vel, omega, masses, TOLERANCE,
                          np.zeros(WS_SHAPE))
    first, count = MI1[0, FIRST], MI1[0, COUNT]
    a, b = I1[first, 0], I1[first, 1]
    for c in range(first, first + count):
        assert abs(row_velocity(R1, c, 0, a, b, vel, omega) - R1[c, BIAS]) < 1e-12
        assert R1[c, LAM] >= 0.0
    for r in range(3):
        assert abs(row_velocity(M1, 0, r, a, b, vel, omega)) < 1e-12   # the rows' layout
    # resting on the floor: no velocity is left at all (COURSE.md 5, resting contact)
    assert np.abs(vel[1]).max() < 1e-12 and np.abs(omega[1]).max() < 1e-12
    ln = R1[first:first + count, LAM].sum()
    assert np.hypot(M1[0, M_LAM], M1[0, M_LAM + 1]) <= M1[0, M_MU_S] * ln
    assert abs(M1[0, M_LAM + 2]) <= M1[0, M_MU_S] * ln * M1[0, RADIUS]


def test_a_cube_leaving_the_floor_is_not_pulled_back():
    """Rising at 0.5 m/s, the cube needs no impulse: holding it to the floor
    would take a pull, which a contact cannot give."""
    w = world([cube("c", 0.1 - 0.001)])
    w.step(60)
    one_sided, vel, omega, masses = one_sided_manifolds(w)
    vel[1, 2] += 0.5
    before = (vel.copy(), omega.copy(), one_sided[0].copy(), one_sided[2].copy())
    assert not settle_resting(one_sided, ONE, upper(one_sided, 0), vel, omega, masses, TOLERANCE,
                              np.zeros(WS_SHAPE))
    for x, y in zip(before, (vel, omega, one_sided[0], one_sided[2])):
        assert x.tobytes() == y.tobytes()


def test_a_sliding_cube_is_left_to_the_sweeps():
    w = world([cube("c", 0.1 - 0.001, velocity=(3.0, 0.0, 0.0))])
    w.step(2)
    one_sided, vel, omega, masses = one_sided_manifolds(w)
    before = (vel.copy(), omega.copy(), one_sided[0].copy(), one_sided[2].copy())
    assert not settle_resting(one_sided, ONE, upper(one_sided, 0), vel, omega, masses, TOLERANCE,
                              np.zeros(WS_SHAPE))
    for x, y in zip(before, (vel, omega, one_sided[0], one_sided[2])):
        assert x.tobytes() == y.tobytes()       # declined: nothing changed (bit for bit)


def test_a_cube_on_an_edge_is_left_to_the_sweeps():
    """Two points fix five of the six velocities (the tilt about the edge is free)."""
    w = world([cube("low", 0.1 - 0.001), cube("top", 0.3 - 0.002, half=0.1)])
    tilted = w.state.quat.copy()
    tilted[2] = (np.cos(np.pi / 8), 0.0, np.sin(np.pi / 8), 0.0)
    w.state.quat[:] = tilted
    w.state.pos[2, 2] = 0.2 + 0.1 * np.sqrt(2) - 0.001
    one_sided, vel, omega, masses = one_sided_manifolds(w)
    MI1 = one_sided[3]
    edges = [m for m in range(len(MI1)) if MI1[m, COUNT] == 2]
    assert edges
    for m in edges:
        assert not settle_resting(one_sided, np.array([m]), upper(one_sided, m), vel, omega, masses,
                                  TOLERANCE, np.zeros(WS_SHAPE))


@pytest.mark.parametrize("scene", ["tower", "pyramid"])
def test_resting_solve_on_and_off_agree_to_the_sweeps_tolerance(scene):
    if scene == "tower":
        bodies = [cube(f"c{i}", 0.1 + 0.2 * i + 0.002 * i, x=0.004 * i) for i in range(6)]
    else:
        bodies = [cube(f"c{r}{k}", 0.1 + 0.202 * r, x=-0.101 * (3 - r) + 0.202 * k)
                  for r in range(4) for k in range(4 - r)]
    on, off = world(bodies), world(bodies, resting_block=False)
    for w in (on, off):
        w.step(480)
    # both at rest where they were put: the two solves reach the same state
    # up to what the sweeps leave (their tolerance, 1e-6 m/s, over 2 s)
    assert np.abs(on.state.pos - off.state.pos).max() < 1e-4
    assert np.abs(on.state.vel).max() < 1e-3 and np.abs(off.state.vel).max() < 1e-3


def test_a_solve_that_leaves_one_point_pulling_is_refused():
    """The whole face still pushes (its total is > 0), but one corner would
    pull: a contact cannot, so the face is left to the sweeps."""
    from physics_core.collision.resting_block import VEC, _holds
    w = world([cube("c", 0.1 - 0.001)])
    w.step(60)
    one_sided, _, _, _ = one_sided_manifolds(w)
    R1, _, M1, MI1 = one_sided
    first, count = MI1[0, FIRST], MI1[0, COUNT]
    ws = np.zeros(WS_SHAPE)
    ws[VEC, 1:count] = 1e-3                     # three corners push harder
    assert _holds(R1, M1, MI1, 0, ws, 0)
    ws[VEC, 0] = -R1[first, LAM] - 1e-4         # and one would pull
    assert not _holds(R1, M1, MI1, 0, ws, 0)
    assert R1[first:first + count, LAM].sum() + ws[VEC, :count].sum() > 0.0
