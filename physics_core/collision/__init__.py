"""Collision detection and response (COURSE.md 5)."""


def build_contact_stages(model):
    raise NotImplementedError("contacts are not available yet")
