"""Continuous collision (placeholder until time of impact lands)."""


def ccd(world, h, params, scratch):
    return
