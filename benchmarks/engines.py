"""The same rigid-body scene built in this engine, PyBullet and MuJoCo.

A scene here is a plain list of bodies on a ground plane, `[(shape, size,
position)]` with shape "box" (size = half extents) or "sphere" (size =
radius), all of `MASS` kg, and the same step for every engine: dt, solver
iterations, no sleeping (every body awake: the worst case, and the only one
all three engines can be put in). MuJoCo is run twice, with its default
Newton solver ("mujoco") and with its conjugate-gradient one ("mujoco-cg"):
neither is faster on every scene (Newton takes seconds a step on a pile of
1,000 spheres, CG is several times faster on a pyramid of 1,000 boxes),
so a comparison is made against the faster of the two. Its third, PGS, was
slower than CG on every sphere pile, box pile and pyramid of 1 to 1,000
bodies measured, and on the pyramid of 10,000. `build(engine, bodies)` returns a
`step(n)` callable, a `positions()` reader and a `stages()` reader (seconds
per named stage so far; this engine only, None for the others).
"""
import weakref

import numpy as np

MASS = 1.0
DT = 1.0 / 240.0
ITERATIONS = 8
ENGINES = ("physics_core", "pybullet", "mujoco", "mujoco-cg")
PEERS = ENGINES[1:]
LABELS = {"physics_core": "this engine", "pybullet": "PyBullet", "mujoco": "MuJoCo (Newton)",
          "mujoco-cg": "MuJoCo (CG)"}
_SOLVER = {"mujoco": "Newton", "mujoco-cg": "CG"}


def module_of(engine):
    """The Python module an engine is imported from (both MuJoCo solvers: mujoco)."""
    return "mujoco" if engine in _SOLVER else engine


def build(engine, bodies, dt=DT, iterations=ITERATIONS):
    if engine in _SOLVER:
        return _mujoco(bodies, dt, iterations, _SOLVER[engine])
    return {"physics_core": _ours, "pybullet": _pybullet}[engine](bodies, dt, iterations)


def scene_of(bodies, dt=DT, iterations=ITERATIONS):
    """This engine's scene dict for a body list [(shape, size, position)]: a
    ground plane, then body b{i} of MASS kg for each, sleep off."""
    scene = {"dt": dt, "gravity": [0.0, 0.0, -9.81],
             "effects": {"contacts": {"iterations": iterations, "sleep": False}},
             "bodies": [{"name": "ground", "shape": {"type": "plane"}, "static": True}]}
    for i, (shape, size, pos) in enumerate(bodies):
        s = ({"type": "box", "half_extents": list(size)} if shape == "box"
             else {"type": "sphere", "radius": float(size)})
        scene["bodies"].append({"name": f"b{i}", "shape": s, "mass": MASS,
                                "position": [float(c) for c in pos]})
    return scene


def _ours(bodies, dt, iterations):
    import warnings

    from physics_core import load_scene
    scene = scene_of(bodies, dt, iterations)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)     # default-material friction fallback
        world = load_scene(scene, max_bodies=len(scene["bodies"]))   # the 10,000-body rows have a ground too
    return (lambda n: world.step(n)), (lambda: world.state.pos[1:].copy()), \
        (lambda: dict(world.profile))


def _pybullet(bodies, dt, iterations):
    import pybullet as p
    client = p.connect(p.DIRECT)
    p.setGravity(0, 0, -9.81, physicsClientId=client)
    p.setTimeStep(dt, physicsClientId=client)
    p.setPhysicsEngineParameter(numSolverIterations=iterations, numSubSteps=0,
                                physicsClientId=client)
    plane = p.createCollisionShape(p.GEOM_PLANE, physicsClientId=client)
    p.createMultiBody(0, plane, physicsClientId=client)
    shapes, ids = {}, []
    for shape, size, pos in bodies:
        key = (shape, tuple(np.atleast_1d(size)))
        if key not in shapes:
            shapes[key] = (p.createCollisionShape(p.GEOM_BOX, halfExtents=list(size), physicsClientId=client)
                           if shape == "box" else
                           p.createCollisionShape(p.GEOM_SPHERE, radius=float(size), physicsClientId=client))
        b = p.createMultiBody(MASS, shapes[key], basePosition=list(pos), physicsClientId=client)
        p.changeDynamics(b, -1, activationState=p.ACTIVATION_STATE_DISABLE_SLEEPING,
                         physicsClientId=client)
        ids.append(b)

    def step(n):
        for _ in range(n):
            p.stepSimulation(physicsClientId=client)

    def positions():
        return np.array([p.getBasePositionAndOrientation(b, physicsClientId=client)[0] for b in ids])
    # the client is let go with its step: a benchmark that builds the scene
    # again for each timed window (measure.py, pile_compare.py) holds one at a time
    weakref.finalize(step, p.disconnect, physicsClientId=client)
    return step, positions, lambda: None


def mujoco_xml(bodies, dt, iterations, solver):
    """MJCF of the scene: a free body per entry over a ground plane, `solver`
    one of MuJoCo's "Newton" (its default), "CG" or "PGS"."""
    geoms = []
    for shape, size, pos in bodies:
        sz = " ".join(f"{c:g}" for c in np.atleast_1d(size))
        geoms.append(f'<body pos="{pos[0]:g} {pos[1]:g} {pos[2]:g}"><freejoint/>'
                     f'<geom type="{shape}" size="{sz}" mass="{MASS:g}"/></body>')
    return (f'<mujoco><option timestep="{dt:g}" iterations="{iterations}" solver="{solver}"/>'
            '<size memory="' + f'{max(64, 2 * len(bodies))}M' + '"/>'
            '<worldbody><geom type="plane" size="0 0 1"/>' + "".join(geoms)
            + "</worldbody></mujoco>")


def _mujoco(bodies, dt, iterations, solver):
    import mujoco
    model = mujoco.MjModel.from_xml_string(mujoco_xml(bodies, dt, iterations, solver))
    data = mujoco.MjData(model)

    def step(n):
        for _ in range(n):
            mujoco.mj_step(model, data)

    def positions():
        return data.xpos[1:].copy()
    return step, positions, lambda: None
