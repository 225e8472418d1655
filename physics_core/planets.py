"""Uniform-gravity presets from the course's planet masses and radii (COURSE.md 2).

g = G m_planet / (r_planet + h)²; at h = 0 this gives Earth 9.81, Moon 1.62,
Mars 3.70 m/s² (the course rounds Mars to 3.69).
"""
G_COURSE = 6.673e-11  # m³ kg⁻¹ s⁻², the course's value of G

PLANETS = {
    "earth": {"mass": 5.98e24, "radius": 6.377e6},
    "moon": {"mass": 7.35e22, "radius": 1.738e6},
    "mars": {"mass": 6.42e23, "radius": 3.403e6},
}


def surface_gravity(planet: str, altitude: float = 0.0) -> float:
    """Magnitude of g (m/s²) at `altitude` metres above the planet's surface."""
    p = PLANETS[planet]
    return G_COURSE * p["mass"] / (p["radius"] + altitude) ** 2
