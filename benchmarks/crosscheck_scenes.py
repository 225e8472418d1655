"""The cross-check's scenes and their closed forms (COURSE.md), one engine-neutral spec each.

A `Spec` is a flat ground plane at z = 0, a gravity vector and a few bodies
(box: half extents, sphere: radius), each with mass, start position and
velocity, and C_R. Friction is the course's dry steel on steel pair,
μ_s = 0.6, μ_k = 0.4 (COURSE.md 2). This engine takes both from its material
table; PyBullet and MuJoCo have a single Coulomb coefficient, so each row
gives them the one its closed form uses (`peer_mu`): μ_k where the body
slides, μ_s where it must hold. The inclines tilt gravity by θ instead of
the plane (the same physics: only the angle between g and the normal
counts), so every engine sees one flat plane.

Each row's `measure(reader)` turns a run into the row's one number; the
reader is the engine adapter of benchmarks/crosscheck_engines.py.
"""
import math
from dataclasses import dataclass, field

G = 9.81
DT = 1.0 / 240.0
MU_S, MU_K = 0.6, 0.4                 # COURSE.md 2, steel on steel (dry)
SLIDER = (0.2, 0.15, 0.05)            # a low box: it slides rather than tips
V_SLIDE = 3.0                         # m/s
BALL_R = 0.1
DROP_H0 = 1.0                         # m, the ball's lowest point above the floor
C_R = 0.8
V_ROLL = 2.0                          # m/s
INCLINE_MARGIN = math.radians(1.0)    # the inclines are the friction angle ∓ this
STACK_BOXES, STACK_HALF = 20, 0.25    # 0.5 m cubes, 1 kg
HEAVY, LIGHT, PAIR_HALF = 1000.0, 1.0, 0.1


@dataclass(frozen=True)
class Body:
    shape: str                        # "box" | "sphere"
    size: tuple                       # half extents | (radius,)
    mass: float
    position: tuple
    velocity: tuple = (0.0, 0.0, 0.0)
    restitution: float = 0.0


@dataclass(frozen=True)
class Spec:
    gravity: tuple
    bodies: tuple
    peer_mu: float                    # PyBullet's and MuJoCo's one friction coefficient
    duration: float                   # s simulated
    bouncy: bool = False              # MuJoCo: C_R mapped to its contact damping


@dataclass(frozen=True)
class Row:
    key: str
    title: str
    closed_form: float
    formula: str                      # the closed form as written in COURSE.md
    course: str                       # the section it comes from
    unit: str
    spec: Spec
    measure: object = field(repr=False)   # callable(reader, spec) -> float


def slider(velocity=(0.0, 0.0, 0.0)):
    """A 2 kg low box lying flat on the floor."""
    return Body("box", SLIDER, 2.0, (0.0, 0.0, SLIDER[2]), velocity)


def tilted(theta):
    """Gravity making angle θ with the floor's normal; downhill is +x."""
    return (G * math.sin(theta), 0.0, -G * math.cos(theta))


def slide_distance(rd, spec):
    return rd.position(0)[0] - spec.bodies[0].position[0]


def first_apex(rd, spec):
    """Highest point of the lowest point of the ball between its first bounce and its
    next descent: at each step in free flight (out of contact by > 1 mm) the apex of the
    ballistic arc from that state, z − r + v_z² / 2g, so the sampling adds no error."""
    r, up, apex = spec.bodies[0].size[0], False, float("nan")
    for _ in range(round(spec.duration / DT)):
        rd.step(1)
        z, vz = rd.position(0)[2] - r, rd.velocity(0)[2]
        if vz > 0.0 and z > 1e-3:
            up = True
            apex = z + vz * vz / (2.0 * G) if apex != apex else max(apex, z + vz * vz / (2.0 * G))
        elif up and vz < 0.0:
            break
    return apex


def end_speed(rd, spec):
    rd.step(round(spec.duration / DT))
    return rd.velocity(0)[0]


def end_displacement(rd, spec, body=0):
    rd.step(round(spec.duration / DT))
    return math.dist(rd.position(body), spec.bodies[body].position)


def top_displacement(rd, spec):
    return end_displacement(rd, spec, len(spec.bodies) - 1)


def downhill_acceleration(rd, spec):
    """Slope of the downhill speed between 0.1 s (past the first contact) and the end."""
    rd.step(round(0.1 / DT))
    v0 = rd.velocity(0)[0]
    n = round((spec.duration - 0.1) / DT)
    rd.step(n)
    return (rd.velocity(0)[0] - v0) / (n * DT)


def sink(rd, spec):
    rd.step(round(spec.duration / DT))
    return spec.bodies[-1].position[2] - rd.position(len(spec.bodies) - 1)[2]


def slide_end(rd, spec):
    rd.step(round(spec.duration / DT))
    return slide_distance(rd, spec)


def rows(quick=False):
    """The six scenes (the incline as two rows: hold below, slide above)."""
    hold, slip = math.atan(MU_S) - INCLINE_MARGIN, math.atan(MU_S) + INCLINE_MARGIN
    stack = tuple(Body("box", (STACK_HALF,) * 3, 1.0, (0.0, 0.0, STACK_HALF * (2 * i + 1)))
                  for i in range(STACK_BOXES))
    pair = (Body("box", (PAIR_HALF,) * 3, LIGHT, (0.0, 0.0, PAIR_HALF)),
            Body("box", (PAIR_HALF,) * 3, HEAVY, (0.0, 0.0, 3 * PAIR_HALF)))
    down = (0.0, 0.0, -G)
    return [
        Row("slide", f"slide to stop: box at {V_SLIDE:g} m/s, μ_k = {MU_K}", V_SLIDE ** 2 / (2 * MU_K * G),
            "v0² / (2 μ_k g)", "2 (kinetic friction), 4 (v² = v0² + 2 a Δp)", "m",
            Spec(down, (slider((V_SLIDE, 0.0, 0.0)),),
                 MU_K, 1.5), slide_end),
        Row("bounce", f"bounce apex: ball dropped {DROP_H0:g} m, C_R = {C_R}", C_R ** 2 * DROP_H0,
            "C_R² h0", "5 (coefficient of restitution)", "m",
            Spec(down, (Body("sphere", (BALL_R,), 1.0, (0.0, 0.0, BALL_R + DROP_H0), restitution=C_R),),
                 MU_K, 1.5, bouncy=True), first_apex),
        Row("roll", f"roll at 5/7: ball sliding at {V_ROLL:g} m/s, no spin, μ_k = {MU_K}",
            5.0 / 7.0 * V_ROLL, "5/7 v0 (I = 2/5 m r²)", "5 (friction at contacts), 3 (τ = I α)", "m/s",
            Spec(down, (Body("sphere", (BALL_R,), 1.0, (0.0, 0.0, BALL_R), (V_ROLL, 0.0, 0.0)),),
                 MU_K, 1.0), end_speed),
        Row("incline_hold", "incline 1° below the friction angle: displacement after 3 s", 0.0,
            "0 (tangential force ≤ μ_s F_N)", "2 (static friction, normal force on an incline)", "m",
            Spec(tilted(hold), (slider(),), MU_S, 3.0),
            end_displacement),
        Row("incline_slide", "incline 1° above the friction angle: acceleration",
            G * (math.sin(slip) - MU_K * math.cos(slip)), "g (sin θ − μ_k cos θ)",
            "2 (kinetic friction, normal force on an incline)", "m/s²",
            Spec(tilted(slip), (slider(),), MU_K, 1.0),
            downhill_acceleration),
        Row("stack", f"stack drift: {STACK_BOXES} boxes of 0.5 m, top box after "
            f"{5 if quick else 10} s", 0.0, "0 (Newton 1 and 3: every box at rest)", "1, 2 (normal force)",
            "m", Spec(down, stack, MU_S, 5.0 if quick else 10.0), top_displacement),
        Row("mass_ratio", f"mass ratio: {HEAVY:g} kg cube on a {LIGHT:g} kg cube, sink after "
            f"{2 if quick else 5} s", 0.0, "0 (normal force = W of what rests on it)", "2 (normal force)",
            "m", Spec(down, pair, MU_S, 2.0 if quick else 5.0), sink),
    ]
