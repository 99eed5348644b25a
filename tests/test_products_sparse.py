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
@pytest.mark.parametrize("rows", [2, 3, 64, 128, 2500])
def test_sparse_sums_equal_the_matrix_product(kind, rows, monkeypatch):
    # the blade-by-blade sums at every batch size (products take them from SPARSE_MIN_ROWS rows)
    monkeypatch.setattr(products, "SPARSE_MIN_ROWS", 2)
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


@pytest.mark.parametrize("kind", ["geometric", "outer", "inner"])
def test_a_row_has_the_same_bits_alone_and_in_a_batch(kind):
    """One surface's rings and a batch of many surfaces' rings are multiplied alike: a row's
    product does not depend on the length of the batch it comes in (one row included)."""
    rng = np.random.default_rng(7)
    a = rng.normal(size=(40, 32)) * np.exp(3.0 * rng.normal(size=(40, 1)))
    b = rng.normal(size=(40, 32))
    taken = 0
    for grades_a, grades_b in [(ga, gb) for ga in GRADE_SETS for gb in GRADE_SETS] + [(ROTOR, ROTOR)]:
        sel = [products._selection(g) for g in (grades_a, grades_b, products.ALL_GRADES)]
        if products._term_lists(kind, *sel) is None:
            continue  # past 256 blade pairs: the matrix product, whose order may depend on the batch
        taken += 1
        batch = products._product(kind, a, b, grades_a, grades_b, products.ALL_GRADES)
        for row in (0, 17):
            alone = products._product(kind, a[row:row + 1], b[row:row + 1], grades_a, grades_b, products.ALL_GRADES)
            np.testing.assert_array_equal(alone[0], batch[row])
            np.testing.assert_array_equal(products._product(kind, a[row:row + 2], b[row:row + 2], grades_a,
                                                            grades_b, products.ALL_GRADES), batch[row:row + 2])
    assert taken > 50


@pytest.mark.parametrize("grades", [((3,), (3,), (2,)), ((3,), (1,), (2, 4)), ((1,), (1,), (0, 2)), (ROTOR, ROTOR, ROTOR)])
def test_row_products_equal_the_multivector_products(grades):
    """Blade-major rows (the batched pass's layout) give the (..., 32) products' bits."""
    rng = np.random.default_rng(11)
    a = rng.normal(size=(300, 32)) * np.exp(3.0 * rng.normal(size=(300, 1)))
    b = rng.normal(size=(300, 32))
    grades_a, grades_b, grades_out = grades
    blades_a, blades_b, _, _ = products.product_terms("geometric", grades_a, grades_b, grades_out)
    expected = products.geometric(a, b, grades_a, grades_b, grades_out)
    blades_out, rows = products.row_product("geometric", a.T[blades_a], b.T[blades_b], grades_a, grades_b, grades_out)
    np.testing.assert_array_equal(rows, expected.T[blades_out])
    assert not np.any(np.delete(expected, blades_out, axis=1))
