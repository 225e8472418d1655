"""Contact scenes with known answers, for the contact part of the accuracy study.

- `bounce`: a ball dropped on the ground. With restitution e, the apex
  heights are h_n = e^{2n} h₀ (COURSE.md 5) while impacts are faster than
  the resting threshold.
- `bullet`: a small fast sphere fired at a thin static wall, elastic. It
  touches the wall at t* = gap / speed; without time of impact it would
  cross the wall in one step.
- `stack`: boxes resting on each other on the ground; exact answer: nothing
  moves.
"""

BOUNCE_H0 = 1.0            # m, drop height of the ball's lowest point
BOUNCE_E = 0.8
BOUNCE_RADIUS = 0.1
BOUNCES = 5                # apexes compared (all with impact speeds well above the threshold)
BOUNCE_DURATION = 3.0      # s: covers the first BOUNCES bounces


def bounce(integrator, dt, substeps=1):
    return {"dt": dt, "substeps": substeps, "integrator": integrator, "gravity": "earth",
            "effects": {"contacts": {"sleep": False}},
            "bodies": [{"name": "ground", "shape": {"type": "plane"}, "static": True,
                        "material": "concrete", "restitution": 1.0},
                       {"name": "ball", "shape": {"type": "sphere", "radius": BOUNCE_RADIUS},
                        "mass": 1.0, "material": "rubber", "restitution": BOUNCE_E,
                        "position": [0.0, 0.0, BOUNCE_H0 + BOUNCE_RADIUS]}]}


def bounce_apexes_exact(n=BOUNCES):
    return [BOUNCE_E ** (2 * (k + 1)) * BOUNCE_H0 for k in range(n)]


BULLET_RADIUS = 0.05
BULLET_SPEED = 50.0        # m/s: 0.83 m per 1/60 s step, 8 × the ball's diameter
WALL_HALF = 0.02           # m, half thickness of the wall
BULLET_DT = 1.0 / 60.0


def bullet(dt, start_gap, ccd, ccd_iterations=30, substeps=1):
    """The ball starts `start_gap` m before touching the wall at x = 0, moving +x."""
    contacts = {"sleep": False, "ccd": ccd, "restitution_threshold": 0.0}
    if ccd:
        # the bisection count alone decides when it stops
        contacts.update(ccd_iterations=ccd_iterations, ccd_tolerance=1e-12)
    return {"dt": dt, "substeps": substeps, "integrator": "semi_implicit_euler",
            "effects": {"contacts": contacts},
            "bodies": [{"name": "wall", "shape": {"type": "box", "half_extents": [WALL_HALF, 1.0, 1.0]},
                        "static": True, "material": "steel", "restitution": 1.0},
                       {"name": "bullet", "shape": {"type": "sphere", "radius": BULLET_RADIUS},
                        "mass": 0.01, "material": "steel", "restitution": 1.0,
                        "position": [-(WALL_HALF + BULLET_RADIUS + start_gap), 0.0, 0.0],
                        "velocity": [BULLET_SPEED, 0.0, 0.0]}]}


STACK_HALF = 0.25


def stack(boxes, iterations, dt=1.0 / 60.0):
    bodies = [{"name": "ground", "shape": {"type": "plane"}, "static": True, "material": "steel"}]
    for i in range(boxes):
        bodies.append({"name": f"box{i}", "shape": {"type": "box", "half_extents": [STACK_HALF] * 3},
                       "mass": 1.0, "material": "steel", "restitution": 0.0,
                       "position": [0.0, 0.0, STACK_HALF * (2 * i + 1)]})
    return {"dt": dt, "gravity": "earth", "bodies": bodies,
            # sleep off: the solver must hold the stack on every step
            "effects": {"contacts": {"iterations": iterations, "sleep": False}}}
