"""Products summed one operand blade at a time equal the sign-and-placement matrix product, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from cgamesh.geometry.algebra import products

GRADE_SETS = [(1,), (2,), (3,), (4,), (5,), (0,), (2, 4), (0, 2, 4), (1, 3), (0, 1, 2, 3, 4, 5)]
ROTOR = products.Blades((0, 6, 7, 10))


def dense(kind, a, b, grades_a, grades_b, grades_out):
    """The reference: every blade pair's product through the (mostly zero) matrix."""
    sel = [products._selection(g) for g in (grades_a, grades_b, grades_out)]
    blades_a, blades_b, blades_out, matrix = products._bilinear_map(kind, *sel)
    out = np.zeros(a.shape[:-1] + (32,))
    if blades_out.size:
        pairs = (a[:, blades_a][:, :, None] * b[:, blades_b][:, None, :]).reshape(len(a), -1)
        out[:, blades_out] = pairs @ matrix
    return out


@pytest.mark.parametrize("kind", ["geometric", "outer", "inner"])
@pytest.mark.parametrize("rows", [2, 3, 64, 2500])
def test_sparse_sums_equal_the_matrix_product(kind, rows):
    rng = np.random.default_rng(rows)
    outputs = [(0, 1, 2, 3, 4, 5), (0,), (1,), (2, 4)] if kind == "geometric" else [(0, 1, 2, 3, 4, 5)]
    cases = [(ga, gb, go) for ga in GRADE_SETS for gb in GRADE_SETS for go in outputs]
    cases.append((ROTOR, ROTOR, ROTOR))
    taken = 0
    for grades_a, grades_b, grades_out in cases:
        a = rng.normal(size=(rows, 32)) * np.exp(3.0 * rng.normal(size=(rows, 1)))
        b = rng.normal(size=(rows, 32))
        got = products._product(kind, a, b, grades_a, grades_b, grades_out)
        sel = [products._selection(g) for g in (grades_a, grades_b, grades_out)]
        taken += products._term_lists(kind, *sel) is not None
        np.testing.assert_array_equal(got, dense(kind, a, b, grades_a, grades_b, grades_out))
    assert taken > 0  # the blade-by-blade sums were exercised, not only the matrix
