"""A crosscheck_scenes.Spec built in this engine, PyBullet and MuJoCo, each at its own defaults.

`build(engine, spec)` returns a `Reader`: `step(n)`, `position(i)` and
`velocity(i)` (world frame, body i of spec.bodies) and `settings`, a line
saying what was set and which defaults were left (read back from the engine
where it can report them). What every engine gets alike: the same bodies,
start, gravity and dt = 1/240 s, no sleeping, no damping, no rolling or
spinning friction.
"""
import math
from dataclasses import dataclass

import numpy as np

from .crosscheck_scenes import DT, MU_K, MU_S

ENGINES = ("physics_core", "pybullet", "mujoco")
TITLES = {"physics_core": "this engine", "pybullet": "PyBullet", "mujoco": "MuJoCo"}


@dataclass
class Reader:
    step: object
    position: object
    velocity: object
    settings: str


def build(engine, spec):
    return {"physics_core": _ours, "pybullet": _pybullet, "mujoco": _mujoco}[engine](spec)


# ---- this engine ------------------------------------------------------------------------
def _ours(spec):
    from physics_core import load_scene
    from physics_core.contact_params import ContactParams
    scene = {"dt": DT, "gravity": list(spec.gravity), "effects": {"contacts": {"sleep": False}},
             "bodies": [{"name": "ground", "shape": {"type": "plane"}, "static": True,
                         "material": "steel"}]}
    for i, b in enumerate(spec.bodies):
        shape = ({"type": "box", "half_extents": list(b.size)} if b.shape == "box"
                 else {"type": "sphere", "radius": b.size[0]})
        scene["bodies"].append({"name": f"b{i}", "shape": shape, "mass": b.mass, "material": "steel",
                                "restitution": b.restitution, "position": list(b.position),
                                "velocity": list(b.velocity)})
    world = load_scene(scene)
    d = ContactParams()
    names = [f"b{i}" for i in range(len(spec.bodies))]
    settings = (f"defaults: {d.iterations} velocity iterations (early stop at {d.velocity_tolerance:g} m/s), "
                f"{d.position_iterations} position iterations, slop {d.slop * 1e3:g} mm, "
                f"restitution above {d.restitution_threshold:g} m/s; μ_s = {MU_S}, μ_k = {MU_K} from the "
                "material table (steel on steel); sleep off")
    return Reader(world.step, lambda i: world.body(names[i]).position.copy(),
                  lambda i: world.body(names[i]).velocity.copy(), settings)


# ---- PyBullet ---------------------------------------------------------------------------
def _pybullet(spec):
    import pybullet as p
    c = p.connect(p.DIRECT)
    p.setGravity(*spec.gravity, physicsClientId=c)
    p.setTimeStep(DT, physicsClientId=c)
    ground = p.createMultiBody(0, p.createCollisionShape(p.GEOM_PLANE, physicsClientId=c),
                               physicsClientId=c)
    # PyBullet multiplies the two bodies' friction and restitution: the ground's 1 passes
    # the body's through unchanged
    p.changeDynamics(ground, -1, lateralFriction=1.0, restitution=1.0, physicsClientId=c)
    ids = []
    for b in spec.bodies:
        shape = (p.createCollisionShape(p.GEOM_BOX, halfExtents=list(b.size), physicsClientId=c)
                 if b.shape == "box" else
                 p.createCollisionShape(p.GEOM_SPHERE, radius=b.size[0], physicsClientId=c))
        k = p.createMultiBody(b.mass, shape, basePosition=list(b.position), physicsClientId=c)
        p.changeDynamics(k, -1, lateralFriction=spec.peer_mu, restitution=b.restitution,
                         rollingFriction=0.0, spinningFriction=0.0, linearDamping=0.0,
                         angularDamping=0.0, activationState=p.ACTIVATION_STATE_DISABLE_SLEEPING,
                         physicsClientId=c)
        p.resetBaseVelocity(k, list(b.velocity), [0.0, 0.0, 0.0], physicsClientId=c)
        ids.append(k)
    e = p.getPhysicsEngineParameters(physicsClientId=c)

    def step(n):
        for _ in range(n):
            p.stepSimulation(physicsClientId=c)
    settings = (f"defaults: {e['numSolverIterations']} solver iterations, split impulse "
                f"{'on' if e.get('useSplitImpulse') else 'off'}, "
                f"cone friction {'on' if e.get('enableConeFriction') else 'off'}; set: one μ (the row's, "
                "below), restitution = C_R (times the ground's 1), rolling and spinning friction 0, "
                "linear and angular damping 0 (default 0.04), sleeping off")
    return Reader(step,
                  lambda i: np.array(p.getBasePositionAndOrientation(ids[i], physicsClientId=c)[0]),
                  lambda i: np.array(p.getBaseVelocity(ids[i], physicsClientId=c)[0]), settings)


# ---- MuJoCo -----------------------------------------------------------------------------
def mujoco_dampratio(e):
    """MuJoCo's contact is a damped spring; a linear spring–damper released at contact
    leaves with e = exp(−ζ π / √(1 − ζ²)), so ζ = −ln e / √(π² + ln² e). MuJoCo's solref
    (timeconst, dampratio) sets ζ directly (its documentation: 'dampratio' of the
    reference mass-spring-damper, whose stiffness is 1 / (timeconst · dampratio)²)."""
    if e <= 0.0:
        return 1.0
    return -math.log(e) / math.sqrt(math.pi ** 2 + math.log(e) ** 2)


SPRING_STEPS = 10               # steps per period of MuJoCo's contact spring in the bounce


def mujoco_timeconst(e, dt=DT, steps=SPRING_STEPS):
    """The solref timeconst that makes the bounce's contact spring (ω = 1 / (τ ζ)) last
    `steps` steps per period, 2π τ ζ = steps · dt, so the step resolves it. MuJoCo's default
    0.02 s at ζ = 0.071 (C_R 0.8) is ω dt = 2.9, a spring the step cannot follow: measured
    on 2026-12-01, its first apex was 0.42 m for the closed form's 0.64 m."""
    return max(0.02, steps * dt / (2.0 * math.pi * mujoco_dampratio(e)))


def _mujoco_xml(spec):
    mu = f'{spec.peer_mu:g} 0 0'
    e = max((b.restitution for b in spec.bodies), default=0.0)
    ref = f' solref="{mujoco_timeconst(e):.6g} {mujoco_dampratio(e):.6g}"' if spec.bouncy else ""
    geoms = []
    for b in spec.bodies:
        size = " ".join(f"{s:.9g}" for s in b.size)
        geoms.append(f'<body pos="{" ".join(f"{x:.9g}" for x in b.position)}"><freejoint/>'
                     f'<geom type="{b.shape}" size="{size}" mass="{b.mass:.9g}"/></body>')
    g = " ".join(f"{x:.12g}" for x in spec.gravity)
    # every geom: condim 3 (sliding friction only; 6 would add rolling friction), the row's μ,
    # and for the bounce the damping ratio of its C_R (solref is mixed between the two geoms,
    # so both carry it)
    return (f'<mujoco><option timestep="{DT:.12g}" gravity="{g}"/>'
            f'<default><geom condim="3" friction="{mu}"{ref}/></default>'
            '<worldbody><geom type="plane" size="0 0 1"/>' + "".join(geoms) + "</worldbody></mujoco>")


def _mujoco(spec):
    import mujoco
    model = mujoco.MjModel.from_xml_string(_mujoco_xml(spec))
    data = mujoco.MjData(model)
    for i, b in enumerate(spec.bodies):
        data.qvel[6 * i:6 * i + 3] = b.velocity        # a free joint's linear velocity is world frame
    solver = {0: "PGS", 1: "CG", 2: "Newton"}[int(model.opt.solver)]
    cone = {0: "pyramidal", 1: "elliptic"}[int(model.opt.cone)]
    settings = (f"defaults: {solver} solver, {model.opt.iterations} iterations, {cone} cone, "
                f"solref (0.02 s, 1), solimp default; set: condim 3 (no rolling or torsional "
                f"friction), one μ (the row's, below); for the bounce, solref from C_R "
                "(crosscheck_engines.mujoco_dampratio and mujoco_timeconst)")

    def step(n):
        for _ in range(n):
            mujoco.mj_step(model, data)
    return Reader(step, lambda i: data.xpos[i + 1].copy(),
                  lambda i: data.qvel[6 * i:6 * i + 3].copy(), settings)
