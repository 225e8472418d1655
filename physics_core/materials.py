"""Friction coefficients between material pairs (COURSE.md 2, the course's table).

Looked up by the two bodies' material names in either order. The course
lists steel on steel twice: `steel`–`steel` is the dry 0.6/0.4 row and the
material `steel_clean` picks the 0.74/0.57 row. A pair in neither the table
nor the scene's `friction:` list falls back to FALLBACK_FRICTION, and the
scene's model records which pairs used it.
"""

# (material a, material b): (mu_static, mu_kinetic)
COURSE_PAIRS = {
    ("steel", "steel"): (0.6, 0.4),
    ("steel_greasy", "steel"): (0.1, 0.05),
    ("steel_greasy", "steel_greasy"): (0.1, 0.05),
    ("teflon", "steel"): (0.041, 0.04),
    ("brake_lining", "cast_iron"): (0.4, 0.3),
    ("rubber", "concrete"): (1.0, 0.9),
    ("rubber", "concrete_wet"): (0.30, 0.25),
    ("metal", "ice"): (0.022, 0.02),
    ("steel_clean", "steel_clean"): (0.74, 0.57),
    ("steel_clean", "steel"): (0.74, 0.57),
    ("aluminium", "steel"): (0.61, 0.47),
    ("copper", "steel"): (0.53, 0.36),
    ("nickel", "nickel"): (1.1, 0.53),
    ("glass", "glass"): (0.94, 0.40),
    ("copper", "glass"): (0.68, 0.53),
}

COURSE_MATERIALS = sorted({m for pair in COURSE_PAIRS for m in pair})

# Used when a body names no material.
DEFAULT_MATERIAL = "default"

# For a pair in neither table: a dry, everyday contact (between the course's
# brake-lining and steel rows), so objects neither skate nor stick unusually.
FALLBACK_FRICTION = (0.5, 0.4)


def pair_key(a: str, b: str):
    return (a, b) if a <= b else (b, a)


def build_table(extra_pairs: dict):
    """Canonical {(a, b) sorted: (mu_s, mu_k)} from the course plus scene overrides."""
    table = {pair_key(a, b): v for (a, b), v in COURSE_PAIRS.items()}
    for (a, b), v in extra_pairs.items():
        table[pair_key(a, b)] = v
    return table
