"""The finite check run after every stage (physics_core/finite.py): a body
state is accepted exactly when every component of its pose and velocity is
a number no larger in size than STATE_LIMIT (NaN, ±inf and huge values all
refused), wherever the bad component sits, for any number of bodies."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from physics_core.command_limits import STATE_LIMIT
from physics_core.finite import all_finite, non_finite_bodies, velocities_finite

BAD = (np.nan, np.inf, -np.inf, 2.0 * STATE_LIMIT, -np.nextafter(STATE_LIMIT, np.inf))
GOOD_EDGE = (STATE_LIMIT, -STATE_LIMIT, 0.0, -0.0, 5e-324)
WIDTHS = (3, 4, 3, 3)               # pos, quat, vel, omega


def state(n, seed):
    rng = np.random.default_rng(seed)
    return [rng.normal(size=(n, w)) for w in WIDTHS]


def numpy_finite(arrays):
    return all(bool((np.abs(a) <= STATE_LIMIT).all()) for a in arrays)


@settings(max_examples=150, deadline=None)
@given(n=st.integers(1, 40), seed=st.integers(0, 2 ** 16), which=st.integers(0, 3),
       at=st.integers(0, 10 ** 6), bad=st.sampled_from(BAD))
def test_one_bad_component_anywhere_is_found(n, seed, which, at, bad):
    arrays = state(n, seed)
    row, col = divmod(at % (n * WIDTHS[which]), WIDTHS[which])
    arrays[which][row, col] = bad
    assert not all_finite(*arrays)
    assert velocities_finite(arrays[2], arrays[3]) == (which < 2)
    assert non_finite_bodies(*arrays).tolist() == [row]


@settings(max_examples=60, deadline=None)
@given(n=st.integers(0, 40), seed=st.integers(0, 2 ** 16), edge=st.sampled_from(GOOD_EDGE))
def test_finite_states_up_to_the_limit_pass(n, seed, edge):
    arrays = state(n, seed)
    if n:
        arrays[1][n - 1, 3] = edge
    assert all_finite(*arrays) and velocities_finite(arrays[2], arrays[3])
    assert numpy_finite(arrays)


@pytest.mark.parametrize("n", [1, 7, 1000])
def test_the_check_agrees_with_numpys_on_many_bad_values(n):
    rng = np.random.default_rng(n)
    for _ in range(50):
        arrays = state(n, rng.integers(1 << 30))
        for a in arrays:
            mask = rng.random(a.shape) < 0.3 / a.size
            a[mask] = rng.choice(BAD, size=int(mask.sum()))
        assert all_finite(*arrays) == numpy_finite(arrays)
        assert velocities_finite(arrays[2], arrays[3]) == numpy_finite(arrays[2:])
