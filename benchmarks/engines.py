"""The same rigid-body scene built in this engine, PyBullet and MuJoCo.

A scene here is a plain list of bodies on a ground plane, `[(shape, size,
position)]` with shape "box" (size = half extents) or "sphere" (size =
radius), all of `MASS` kg, and the same step for every engine: dt, solver
iterations, no sleeping (every body awake: the worst case, and the only one
all three engines can be put in). `build(engine, bodies)` returns a
`step(n)` callable, a `positions()` reader and a `stages()` reader (seconds
per named stage so far; this engine only, None for the others).
"""
import numpy as np

MASS = 1.0
DT = 1.0 / 240.0
ITERATIONS = 8
ENGINES = ("physics_core", "pybullet", "mujoco")


def build(engine, bodies, dt=DT, iterations=ITERATIONS):
    return {"physics_core": _ours, "pybullet": _pybullet, "mujoco": _mujoco}[engine](
        bodies, dt, iterations)


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
    return step, positions, lambda: None


def _mujoco(bodies, dt, iterations):
    import mujoco
    geoms = []
    for i, (shape, size, pos) in enumerate(bodies):
        sz = " ".join(f"{c:g}" for c in np.atleast_1d(size))
        geoms.append(f'<body pos="{pos[0]:g} {pos[1]:g} {pos[2]:g}"><freejoint/>'
                     f'<geom type="{shape}" size="{sz}" mass="{MASS:g}"/></body>')
    xml = (f'<mujoco><option timestep="{dt:g}" iterations="{iterations}"/>'
           '<size memory="' + f'{max(64, 2 * len(bodies))}M' + '"/>'
           '<worldbody><geom type="plane" size="0 0 1"/>' + "".join(geoms)
           + "</worldbody></mujoco>")
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)

    def step(n):
        for _ in range(n):
            mujoco.mj_step(model, data)

    def positions():
        return data.xpos[1:].copy()
    return step, positions, lambda: None
