"""Random scenes without contacts, for property tests (Hypothesis) and the stability sweep.

`passive_scene(rng, integrator)` draws bodies, springs with dampers, drag,
gravity and pairwise gravitation: nothing in it injects energy, so the
energy can only stay or fall, up to the integrator's own error.
`isolated_scene` keeps only forces between bodies (springs, gravitation):
no external force, so total momentum must stay constant.

Parameters are bounded so each scene is resolved by its step: the fastest
spring oscillation has ω·dt ≤ OMEGA_DT, and linear drag takes at most half
a body's velocity per step. Outside those bounds an explicit integrator is
expected to gain energy, which is what the accuracy study measures instead.
`rng` is any random.Random (Hypothesis' `st.randoms()` in the tests).
"""
import math

OMEGA_DT = 0.05
DT_CHOICES = (1.0 / 480.0, 1.0 / 240.0, 1.0 / 120.0, 1.0 / 60.0)
# a box of half extents h turning about a spring at its corner stiffens the
# spring by up to (m r² / I) = 4.5 times; spheres are stiffer than boxes by less
ROTATIONAL_STIFFENING = 4.5


def _unit_quaternion(rng):
    q = [rng.uniform(-1.0, 1.0) for _ in range(4)]
    n = math.sqrt(sum(c * c for c in q))
    if n < 1e-3:          # too short to give a direction: no rotation
        return [1.0, 0.0, 0.0, 0.0]
    return [c / n for c in q]


def _vector(rng, scale):
    return [rng.uniform(-scale, scale) for _ in range(3)]


def _body(rng, i):
    sphere = rng.random() < 0.5
    shape = ({"type": "sphere", "radius": rng.uniform(0.05, 0.3)} if sphere else
             {"type": "box", "half_extents": [rng.uniform(0.05, 0.3) for _ in range(3)]})
    return {"name": f"b{i}", "shape": shape, "mass": rng.uniform(0.2, 5.0),
            "position": [3.0 * i + rng.uniform(-0.5, 0.5), rng.uniform(-1, 1), rng.uniform(-1, 1)],
            "orientation": _unit_quaternion(rng),
            "velocity": _vector(rng, 2.0), "angular_velocity": _vector(rng, 3.0)}


def _attachment(rng, body):
    s = body["shape"]
    size = [s["radius"]] * 3 if s["type"] == "sphere" else s["half_extents"]
    return [rng.uniform(-a, a) for a in size]


def _springs(rng, bodies, dt, to_world):
    n = len(bodies)
    pairs = [(a, b) for a in range(n) for b in range(a + 1, n)]
    ends = [(a, -1) for a in range(n)] if to_world else []
    chosen = [p for p in pairs + ends if rng.random() < 0.5]
    if not chosen:
        return []
    per_body = [sum(1 for p in chosen if i in p) for i in range(n)]
    springs = []
    for a, b in chosen:
        m_min = min(bodies[i]["mass"] for i in (a, b) if i >= 0)
        load = max(per_body[i] for i in (a, b) if i >= 0)
        k_max = (OMEGA_DT / dt) ** 2 * m_min / (ROTATIONAL_STIFFENING * load)
        k = rng.uniform(0.05, 1.0) * k_max
        spring = {"a": bodies[a]["name"], "stiffness": k, "rest_length": rng.uniform(0.0, 3.0),
                  "damping": rng.choice([0.0, rng.uniform(0.0, 0.2) * math.sqrt(k * m_min)]),
                  "point_a": _attachment(rng, bodies[a])}
        if b >= 0:
            spring.update(b=bodies[b]["name"], point_b=_attachment(rng, bodies[b]))
        else:
            spring.update(b="world", point_b=_vector(rng, 2.0))
        springs.append(spring)
    return springs


def _gravitation(rng, bodies):
    # softening of a body's size, and G small enough that the pull stays below ~10 m/s²
    soft = 0.5
    total = sum(b["mass"] for b in bodies)
    return {"G": rng.uniform(0.1, 1.0) * 10.0 * soft ** 2 / total, "softening": soft}


def passive_scene(rng, integrator):
    dt = rng.choice(DT_CHOICES)
    bodies = [_body(rng, i) for i in range(rng.randint(1, 4))]
    scene = {"dt": dt, "integrator": integrator, "bodies": bodies,
             "springs": _springs(rng, bodies, dt, to_world=True)}
    if rng.random() < 0.5:
        scene["gravity"] = rng.choice(["earth", "moon", "mars"])
    effects = {}
    if rng.random() < 0.5:
        m_min = min(b["mass"] for b in bodies)
        model = rng.choice(["linear", "quadratic"])
        effects["drag"] = ({"model": "linear", "b": rng.uniform(0.0, 0.5) * m_min / dt}
                           if model == "linear" else {"model": "quadratic"})
    if len(bodies) > 1 and rng.random() < 0.5:
        effects["gravitation"] = _gravitation(rng, bodies)
    if effects:
        scene["effects"] = effects
    return scene


def isolated_scene(rng, integrator):
    dt = rng.choice(DT_CHOICES)
    bodies = [_body(rng, i) for i in range(rng.randint(2, 4))]
    scene = {"dt": dt, "integrator": integrator, "bodies": bodies,
             "springs": _springs(rng, bodies, dt, to_world=False)}
    if rng.random() < 0.5 or not scene["springs"]:
        scene["effects"] = {"gravitation": _gravitation(rng, bodies)}
    return scene
