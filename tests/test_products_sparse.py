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


@pytest.mark.parametrize("kind, grades_a, grades_b, grades_out, carried_a, carried_b", [
    ("outer", (3,), (1,), products.ALL_GRADES, None, (4, 5)),  # a circle with n_inf
    ("geometric", (3,), (1,), (2, 4), None, (4, 5)),
    ("geometric", (1,), (1,), ROTOR, (1, 2, 3), (1, 2, 3)),  # two Euclidean vectors
    ("geometric", ROTOR, (1,), (1, 3), None, (1,)),  # a rotor applied to e1
])
def test_dropping_the_blades_an_operand_never_carries_keeps_the_bits(kind, grades_a, grades_b, grades_out,
                                                                      carried_a, carried_b):
    """Rows of blades that are zero contribute exact zeros, which a sum from zero of finite terms
    does not change: naming only the carried blades (``Blades``) gives the same rows, bit for bit."""
    rng = np.random.default_rng(5)
    rows = 257
    full_a, full_b, full_out, _ = products.product_terms(kind, grades_a, grades_b, grades_out)
    left = rng.normal(size=(len(full_a), rows)) * np.exp(3.0 * rng.normal(size=(1, rows)))
    right = rng.normal(size=(len(full_b), rows))
    selections = []
    for full, carried, values in ((full_a, carried_a, left), (full_b, carried_b, right)):
        if carried is None:
            selections.append((grades_a if values is left else grades_b, values))
            continue
        values[~np.isin(full, carried)] = 0.0  # the blades it does not carry
        selections.append((products.Blades(carried), values[np.isin(full, carried)]))
    (sel_a, rows_a), (sel_b, rows_b) = selections
    blades, expected = products.row_product(kind, left, right, grades_a, grades_b, grades_out)
    got_blades, got = products.row_product(kind, rows_a, rows_b, sel_a, sel_b, grades_out)
    assert set(got_blades) <= set(blades) and len(got_blades) > 0
    np.testing.assert_array_equal(got, expected[np.searchsorted(blades, got_blades)])
    assert not np.any(np.delete(expected, np.searchsorted(blades, got_blades), axis=0))  # the rest is zero
