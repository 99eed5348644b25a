"""row_lengths and unit_rows sum the squares column by column: the same bits as np.linalg.norm, unit
rows, zeros kept."""

from __future__ import annotations

import numpy as np
import pytest

from cgamesh.geometry.algebra.conformal import EUCLIDEAN, vector
from cgamesh.meshing.normals import row_lengths, unit_rows


def by_norm(values: np.ndarray) -> np.ndarray:
    return values / np.maximum(np.linalg.norm(values, axis=-1, keepdims=True), np.finfo(float).tiny)


@pytest.mark.parametrize("columns", [2, 3, 4])
@pytest.mark.parametrize("shape", [(1,), (5,), (2048,), (849, 7), (3, 9)])
def test_unit_rows_equal_the_norm_bit_for_bit(columns, shape):
    rng = np.random.default_rng(columns * 100 + len(shape))
    values = rng.normal(size=shape + (columns,)) * np.exp(30.0 * rng.normal(size=shape + (1,)))
    values.reshape(-1, columns)[0] = 0.0  # a zero row stays zero
    values.reshape(-1, columns)[-1, 0] = 0.0  # an axis-aligned row stays exact
    for view in (values, values[:-1], values[1:], values[..., ::-1]):  # views as the callers pass
        np.testing.assert_array_equal(row_lengths(view), np.linalg.norm(view, axis=-1))
        got = unit_rows(view)
        np.testing.assert_array_equal(got, by_norm(view))
        lengths = np.linalg.norm(got, axis=-1)
        assert np.all((np.abs(lengths - 1.0) <= 1e-15) | (lengths == 0.0))
    assert not np.any(unit_rows(values).reshape(-1, columns)[0])


def test_vector_places_the_euclidean_coordinates():
    x = np.random.default_rng(1).normal(size=(4, 3))
    out = vector(x)
    np.testing.assert_array_equal(out[:, EUCLIDEAN], x)
    out[:, EUCLIDEAN] = 0.0
    assert not np.any(out)
