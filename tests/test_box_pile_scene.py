"""The box pile `physics-bench scale` times (benchmarks/box_pile.py) is the
scene its docstring names: cubes dropped 5 cm layer on layer, off centre by
up to 1 cm, come to rest face on face."""
import numpy as np

from benchmarks import engines
from benchmarks.box_pile import HALF, boxes


def test_box_pile_cubes_start_apart_and_above_the_ground():
    for n in (1, 10, 100, 1000):
        pile = boxes(n)
        assert len(pile) == n
        centres = np.array([p for _, _, p in pile])
        assert (centres[:, 2] - HALF > 0.0).all()
        # no two cubes overlap: their centres are at least a cube apart along some axis
        d = np.abs(centres[:, None, :] - centres[None, :, :]).max(axis=2)
        np.fill_diagonal(d, np.inf)
        assert d.min() > 2 * HALF


def test_box_pile_of_ten_comes_to_rest_face_on_face():
    pile = boxes(10)
    start = np.array([p for _, _, p in pile])
    step, positions, _ = engines.build("physics_core", pile)
    step(480)                                   # 2 s at 240 Hz
    before = positions()
    step(60)
    after = positions()
    # at rest: under 1 mm of motion in the last quarter second
    assert np.abs(after - before).max() < 1e-3
    # each cube sits on the ground or on the cube below it: its height is a
    # whole number of cube sizes above HALF (to the slop and sag of resting contact)
    layer = np.rint((after[:, 2] - HALF) / (2 * HALF))
    assert np.abs(after[:, 2] - (HALF + 2 * HALF * layer)).max() < 2e-3
    assert set(layer.astype(int)) == {0, 1}
    # it landed where it was dropped: the 1 cm offsets do not topple a two-cube column
    assert np.abs(after[:, :2] - start[:, :2]).max() < 0.02
