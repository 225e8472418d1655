"""The shock sweep's energy guard (shock_propagation.GAIN, _settle_layer): a
layer whose settle raised its bodies' kinetic energy is put back as the
sweeps left it, velocities and impulses.

The bug it guards: settled on each of its supports with the support
immovable, a body on two supports that move apart cannot follow both; the
settle then made it try, and threw the top boxes off a tall pyramid. The
scene here is the smallest of that kind: a box across two boxes that slide
apart on the floor, one along +y and one along −y. Settled body by body,
as the sweep settles a layer, the top box leaves with its kinetic energy
grown about 50-fold; the sweep must leave it, and the impulses on it, as
the sweeps had them.
"""
import numpy as np
import pytest

from physics_core import load_scene
from physics_core.collision import shock_propagation as SP
from physics_core.collision.contact_data import RESTING_BLOCK, SHOCK_ON, VELOCITY_TOLERANCE
from physics_core.collision.contact_layout import BODY_A, BODY_B
from physics_core.collision.contact_stages import SETTLE
from physics_core.collision.manifold_friction import FIRST
from substep_rows import rows_after_sweeps

DT = 1 / 240


def _box(name, y_speed, x, z):
    return {"name": name, "shape": {"type": "box", "half_extents": [0.1, 0.1, 0.1]},
            "mass": 1.0, "position": [x, 0.0, z], "velocity": [0.0, y_speed, 0.0]}


def _sliding_apart(speed):
    """A box across two boxes sliding apart along ±y at `speed` m/s, its
    rows solved by the sweeps as solve_stage runs them: (world, tables,
    vel, omega, masses, store, the sweep's settle tolerance, (changes, bound))."""
    w = load_scene({"dt": DT, "gravity": "earth", "effects": {"contacts": {"sleep": False}},
                    "bodies": [{"name": "floor", "shape": {"type": "plane"}, "static": True},
                               _box("left", -speed, -0.11, 0.1), _box("right", speed, 0.11, 0.1),
                               _box("top", 0.0, 0.0, 0.3)]})
    R, I, M, MI, vel, omega, quat, store, changes, bound = rows_after_sweeps(w, DT)
    masses = (w._inv_mass, w.inv_inertia, quat)
    return (w, (R, I, M, MI), vel, omega, masses, store,
            SETTLE * w.contact_system.fp[VELOCITY_TOLERANCE], (changes, bound))


def _settled_one_by_one(w, tables, vel, omega, masses, store, tolerance, unsettled):
    """The sweep's layers settled body by body with no guard: (layer of each
    body, the velocities after)."""
    R, I, M, MI = tables
    cs = w.contact_system
    layer, graph = SP.support_layers(R, I, MI, len(vel), store)
    layer = np.array(layer)
    SP.leave_out_settled(I, MI, layer, graph, unsettled, store)
    order, _, uppers = (np.array(x) for x in SP._upward_order(I, MI, layer, store))
    resting = (cs.ip[RESTING_BLOCK] != 0, np.zeros(SP.WS_SHAPE))
    s = 0
    while s < len(order):
        t = SP._run_end(uppers, s)
        SP._settle_body(tables, order[s:t].copy(), uppers[s], vel, omega, cs.ip[SHOCK_ON],
                        tolerance, layer, masses, resting, store)
        s = t
    return layer, vel, omega


def _lambdas_on(tables, body):
    """The λ of the rows and anchors of every manifold of `body`, as the
    sweep saves them (shock_propagation._lambdas)."""
    R, I, M, MI = tables
    ms = np.array([k for k in range(len(MI)) if body in (I[MI[k, FIRST], BODY_A],
                                                          I[MI[k, FIRST], BODY_B])])
    saved = np.empty((len(R) + len(MI), 3))
    return saved[:SP._lambdas(R, M, MI, ms, saved, False)]


@pytest.mark.parametrize("speed", [0.5, 1.0, 2.0])
def test_a_box_across_two_boxes_sliding_apart_is_not_thrown(speed):
    w, tables, vel, omega, masses, store, tolerance, unsettled = _sliding_apart(speed)
    top = list(w.model.names).index("top")
    before = SP._kinetic_energy(top, vel, omega, masses)
    copies = tuple(t.copy() for t in tables)
    layer, v1, o1 = _settled_one_by_one(w, copies, vel.copy(), omega.copy(), masses, store,
                                        tolerance, unsettled)
    assert layer[top] == 2, "the top box is not the layer above the sliding boxes"
    gained = SP._kinetic_energy(top, v1, o1, masses)
    assert gained > 10.0 * before > 0.0, (
        f"settled alone the top box went from {before:.3e} J to {gained:.3e} J: "
        "this scene no longer tests the guard")
    lam_before = _lambdas_on(tables, top)
    v, o = vel.copy(), omega.copy()
    R, I, M, MI = tables
    cs = w.contact_system
    visited, _ = SP.shock_sweep(R, I, M, MI, v, o, len(v), cs.ip[SHOCK_ON], tolerance, masses,
                                cs.ip[RESTING_BLOCK] != 0, unsettled, store)
    assert visited > 0
    after = SP._kinetic_energy(top, v, o, masses)
    assert after <= before * (1.0 + 1e-4), f"the top box left with {after:.3e} J from {before:.3e}"
    # put back exactly: its velocities and the impulses on it as the sweeps left them
    assert np.array_equal(v[top], vel[top]) and np.array_equal(o[top], omega[top])
    assert len(lam_before) and np.array_equal(lam_before, _lambdas_on(tables, top))
