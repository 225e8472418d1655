"""A box pile with n cubes, as an engines.py body list: the sphere pile of
pile_compare.py with 20 cm cubes in place of the balls.

Cubes of half size 0.1 m on a square grid of columns 0.25 m apart, ten
layers high (fewer below 100 cubes), layers 0.25 m apart so that each
falls 5 cm onto the one below, the lowest 5 cm above the ground, each
shifted by up to 1 cm sideways (fixed seed): the columns land face on
face, off centre, and every cube ends resting on a four-point manifold.
"""
import numpy as np

from .pile_compare import JITTER, LAYERS, SEED, SPACING

HALF = 0.1          # m, half size of each cube


def boxes(n, half=HALF, spacing=SPACING, layers=LAYERS, seed=SEED):
    """[(shape, size, position)] for benchmarks.engines: n cubes in columns."""
    side = (max(1, int(np.ceil(np.sqrt(n / layers)))) if n >= 10 * layers
            else max(1, int(np.ceil(n ** (1 / 3)))))
    i = np.arange(n)
    pos = np.stack([(i % side) * spacing, ((i // side) % side) * spacing,
                    half + 0.05 + (i // side ** 2) * spacing], axis=1).astype(float)
    pos[:, :2] += np.random.default_rng(seed).uniform(-JITTER, JITTER, (n, 2))
    return [("box", (half, half, half), p) for p in pos]
