"""Freezing one side of a contact row for the shock-propagation sweep
(shock_propagation._freeze_row, _freeze_anchor): the lower body made
immovable; the row's effective masses computed again when a body's sweeps
need them (_row_masses, _frozen_masses; a body the resting solve settles
never reads them).

Every number the sweeps read must be what the full recompute gives: a side
that is immovable already (a static or sleeping body: its inverse mass and
turns +0.0) is left as it is and its masses come back with the bits the
row was built with, and an anchored manifold's row (friction on the
anchor) gets only its normal's effective mass anew. Checked bit for bit on
random rows (Hypothesis).
"""
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from physics_core.collision import shock_propagation as SP
from physics_core.collision.contact_build import effective_masses
from physics_core.collision.contact_layout import (ARM_A, ARM_B, DIR, G_TN, INV_MASS_A, INV_MASS_B,
                                                   K_A, K_B, MASS_N, NCOL, TURN_A, TURN_B, W_TT,
                                                   W_TT_INV, direction_columns)
from physics_core.collision.manifold_friction import IMA, IMB, MCOL, TA, TB, W_INV, _invert

# the columns only a single point's friction reads (sequential_impulses.update_contact)
POINT_ONLY = [W_TT + i for i in range(4)] + [W_TT_INV + i for i in range(4)] + [G_TN, G_TN + 1,
                                                                                K_A, K_B]


def _row(seed, frozen_side=None):
    """A contact row with a unit normal, random tangents, arms, turns and masses."""
    rng = np.random.default_rng(seed)
    R = np.zeros((1, NCOL))
    n = rng.normal(size=3)
    R[0, DIR:DIR + 3] = n / np.linalg.norm(n)
    R[0, direction_columns(DIR)[3:]] = rng.normal(size=6)
    R[0, direction_columns(ARM_A) + direction_columns(ARM_B)] = rng.normal(size=18)
    R[0, direction_columns(TURN_A) + direction_columns(TURN_B)] = rng.normal(size=18)
    R[0, INV_MASS_A], R[0, INV_MASS_B] = rng.uniform(0.1, 10.0, 2)
    if frozen_side is not None:
        R[0, INV_MASS_A if frozen_side == 0 else INV_MASS_B] = 0.0
        turn = TURN_A if frozen_side == 0 else TURN_B
        R[0, direction_columns(turn)] = 0.0
    effective_masses(R, 0)
    return R


def _full_freeze(R, side):
    """The freeze without shortcuts: zero the side, every effective mass again."""
    out = R.copy()
    out[0, INV_MASS_A if side == 0 else INV_MASS_B] = 0.0
    turn = TURN_A if side == 0 else TURN_B
    out[0, direction_columns(turn)] = 0.0
    effective_masses(out, 0)
    return out


@settings(max_examples=200, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), side=st.integers(0, 1), anchored=st.booleans())
def test_freezing_a_movable_side_gives_the_full_recompute_bit_for_bit(seed, side, anchored):
    R = _row(seed)
    want = _full_freeze(R, side)
    SP._freeze_row(R, 0, side)
    SP._row_masses(R, 0, anchored)
    keep = [c for c in range(NCOL) if not (anchored and c in POINT_ONLY)]
    assert R[0, keep].tobytes() == want[0, keep].tobytes()
    assert R[0, MASS_N] == want[0, MASS_N] > 0.0


@settings(max_examples=100, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), side=st.integers(0, 1), anchored=st.booleans())
def test_freezing_a_side_already_immovable_changes_no_bit(seed, side, anchored):
    R = _row(seed, frozen_side=side)
    before = R.copy()
    SP._freeze_row(R, 0, side)
    SP._row_masses(R, 0, anchored)
    assert R.tobytes() == before.tobytes() == _full_freeze(before, side).tobytes()


def test_a_negative_zero_turn_is_written_positive_by_the_freeze():
    R = _row(7, frozen_side=1)
    col = direction_columns(TURN_B)[4]                       # t1's, about y
    R[0, col] = -0.0
    SP._freeze_row(R, 0, 1)
    assert np.copysign(1.0, R[0, col]) == 1.0               # written as the freeze writes it
    assert R.tobytes() == _full_freeze(R, 1).tobytes()


@settings(max_examples=100, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), side=st.integers(0, 1))
def test_an_anchor_frozen_twice_is_the_anchor_frozen_once(seed, side):
    rng = np.random.default_rng(seed)
    M = np.zeros((1, MCOL))
    M[0, :W_INV] = rng.normal(size=W_INV)      # directions, arms, turns, inverse masses
    M[0, IMA], M[0, IMB] = rng.uniform(0.1, 10.0, 2)
    w = np.zeros((3, 3))
    SP._freeze_anchor(M, 0, side)
    _invert(M, 0, w)                     # as _frozen_masses gives it
    once = M.copy()
    turn = TA if side == 0 else TB
    assert M[0, IMA if side == 0 else IMB] == 0.0 and not M[0, direction_columns(turn)].any()
    SP._freeze_anchor(M, 0, side)
    assert M.tobytes() == once.tobytes()
    _invert(M, 0, w)
    assert M.tobytes() == once.tobytes()
