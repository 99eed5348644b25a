"""The fold screen's bound of |dN/dtheta| along a ring (cgamesh.meshing.normals.derivative_bound).

circles.fold_screen clears a ring when its smallest |N| over the columns exceeds this bound
times one column step: N cannot vanish between columns. So the bound must never be below the
true largest |dN/dtheta|, measured here densely, and it is exact for a field that only turns.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from cgamesh.meshing import normals as normal_field


def dense_derivative(coefficients: np.ndarray, samples: int = 4096) -> np.ndarray:
    """(K,) the largest |dN/dtheta| over ``samples`` angles of each ring."""
    theta = np.linspace(0.0, 2.0 * np.pi, samples, endpoint=False)
    slope = np.einsum("ma,kac->kmc", normal_field.trig_basis_derivative(theta), coefficients)
    return np.linalg.norm(slope, axis=-1).max(axis=1)


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from([2, 3]), st.sampled_from([1e-6, 1.0, 1e6]))
def test_the_bound_is_never_below_the_largest_derivative(seed, columns, scale):
    rng = np.random.default_rng(seed)
    coefficients = rng.normal(size=(16, normal_field.TERMS, columns)) * scale
    # some rings with only a few harmonics, some with parallel or equal cos and sin rows
    coefficients[:4, 3:] = 0.0
    coefficients[4:8, 2] = coefficients[4:8, 1] * rng.normal(size=(4, 1))
    coefficients[8:10, 4] = coefficients[8:10, 3]
    bound = normal_field.derivative_bound(coefficients)
    measured = dense_derivative(coefficients)
    assert np.all(bound >= measured)
    # and never looser than the sum of the coefficient rows' lengths times their frequency
    frequency = np.concatenate([[0.0], np.repeat(np.arange(1, normal_field.TRIG_DEGREE + 1), 2)])
    assert np.all(bound <= (np.linalg.norm(coefficients, axis=-1) @ frequency) * (1.0 + 1e-9))


def test_a_field_that_only_turns_is_bounded_exactly():
    """A circle moving across its plane: N = r (cos theta, sin theta) in the ring's frame, so
    |dN/dtheta| = r everywhere; the bound is r (to its 1e-9 margin), and with eight columns the
    smallest |N| = r clears one column step (pi / 4 r), which the rows' lengths (2 r) did not."""
    r = 2.5
    coefficients = np.zeros((1, normal_field.TERMS, 2))
    coefficients[0, 1, 0] = coefficients[0, 2, 1] = r
    bound = normal_field.derivative_bound(coefficients)
    assert abs(bound[0] - r) <= 1e-8 * r
    assert r > bound[0] * (2.0 * np.pi / 8)
    assert not r > 2.0 * r * (2.0 * np.pi / 8)
