"""Batched products of multivectors stored as (..., 32) float64 arrays.

A product is bilinear: with A and B the coefficients of the blades each operand can carry,
the result is the outer product A B^T, flattened, times a fixed sign-and-placement matrix
(one matrix product over the whole batch). Callers name the grades their operands carry (a
circle is grade 3, a rotor grades 0, 2, 4), and the matrix for that pattern is built once
and cached: a circle times a circle is a 100-column product, not 1024, with no
per-element Python. Where an operand lives in a smaller subspace than whole grades (a
Euclidean rotation rotor: 1, e12, e13, e23), callers may name its blades instead
(``Blades``): a product of two such rotors is then 16 columns, not 121. Where the operands
carry many blades (circles, duals), the same sums are formed one operand blade at a time
instead of through the mostly-zero matrix (``_sparse_steps``): 2-5x faster, the same bits.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Sequence

import numpy as np

from cgamesh.geometry.algebra.stable_rows import rows_times
from cgamesh.geometry.algebra.layout import (
    BLADE_COUNT,
    GEOMETRIC_SIGN,
    GRADES,
    INNER_SIGN,
    OUTER_SIGN,
    PRODUCT_INDEX,
    REVERSE_SIGN,
)

ALL_GRADES = (0, 1, 2, 3, 4, 5)
# Batches from this many rows are summed blade by blade (``_sparse_steps``), smaller ones
# through the matrix: the same bits either way (tests/test_products_sparse.py), and the
# crossover in time lies between 50 and 500 rows.
SPARSE_MIN_ROWS = 128
_SIGN_TABLES = {"geometric": GEOMETRIC_SIGN, "outer": OUTER_SIGN, "inner": INNER_SIGN}


class Blades(tuple):
    """An explicit set of blade indices, accepted wherever a product takes grades."""


def _selection(grades_or_blades: Sequence[int]) -> tuple[str, tuple[int, ...]]:
    """A hashable, canonical key, tagged so that blades (1, 2) and grades (1, 2) differ."""
    kind = "blades" if isinstance(grades_or_blades, Blades) else "grades"
    return kind, tuple(sorted(grades_or_blades))


def _mask(selection: tuple[str, tuple[int, ...]]) -> np.ndarray:
    """(32,) bool: the blades a selection admits."""
    kind, members = selection
    return np.isin(np.arange(len(GRADES)) if kind == "blades" else GRADES, members)


@lru_cache(maxsize=None)
def _bilinear_map(kind: str, grades_a: tuple, grades_b: tuple, grades_out: tuple):
    """The product restricted to operand and result grades (or ``Blades``), as a matrix.

    Returns (blades_a, blades_b, blades_out, matrix): with A = a[..., blades_a] and
    B = b[..., blades_b], the result's blades_out coefficients are outer(A, B) @ matrix,
    where outer(A, B) is flattened row-major to (..., len(blades_a) * len(blades_b)).
    """
    signs = _SIGN_TABLES[kind]
    blades_a = np.flatnonzero(_mask(grades_a))
    blades_b = np.flatnonzero(_mask(grades_b))
    result = PRODUCT_INDEX[np.ix_(blades_a, blades_b)]
    sign = signs[np.ix_(blades_a, blades_b)] * _mask(grades_out)[result]
    blades_out = np.unique(result[sign != 0.0])
    column = np.searchsorted(blades_out, result)
    matrix = np.zeros((blades_a.size * blades_b.size, max(blades_out.size, 1)))
    rows = np.arange(matrix.shape[0])
    keep = sign.ravel() != 0.0
    matrix[rows[keep], column.ravel()[keep]] = sign.ravel()[keep]
    return blades_a, blades_b, blades_out, matrix


@lru_cache(maxsize=None)
def _sparse_steps(kind: str, grades_a: tuple, grades_b: tuple, grades_out: tuple):
    """The product as one step per blade i of a: the result columns ks gain a_i * (signs * b_js).

    Each pair of blades makes one blade, so the sign-and-placement matrix has one non-zero per
    row; summing its terms in row order from zero is what the matrix product does (a zero
    entry adds nothing), so both ways agree bit for bit on a batch of two rows or more along
    one axis, up to 256 blade pairs (measured against numpy's and OpenBLAS's products).
    Returns None where the dense matrix product is the faster (few blade pairs and several
    result blades: small rotors, vectors).
    """
    blades_a, blades_b, blades_out, matrix = _bilinear_map(kind, grades_a, grades_b, grades_out)
    pairs = blades_a.size * blades_b.size
    if (pairs <= 25 and blades_out.size > 1) or pairs > 256:
        return None  # (past 256 pairs the matrix product sums in blocks: another order)
    per_a = matrix.reshape(blades_a.size, blades_b.size, -1)
    steps = []
    for i in range(blades_a.size):
        js, ks = np.nonzero(per_a[i])
        if js.size:
            steps.append((i, js, ks, per_a[i][js, ks][:, None]))
    return tuple(steps)


@lru_cache(maxsize=None)
def _single_blade_columns(kind: str, grades_a: tuple, grades_b: tuple, grades_out: tuple):
    """A product with a one-blade operand as a signed gather: result column c is a's column
    ``source[c]`` times b's coefficient times ``factor[c]`` (0 where no term lands)."""
    blades_a, _, blades_out, _ = _bilinear_map(kind, grades_a, grades_b, grades_out)
    source = np.zeros(BLADE_COUNT, dtype=np.int64)
    factor = np.zeros(BLADE_COUNT)
    for i, _, ks, signs in _sparse_steps(kind, grades_a, grades_b, grades_out):
        source[blades_out[ks]] = blades_a[i]
        factor[blades_out[ks]] = signs[:, 0]
    return source, factor


def _product(kind, a, b, grades_a, grades_b, grades_out):
    selections = _selection(grades_a), _selection(grades_b), _selection(grades_out)
    blades_a, blades_b, blades_out, matrix = _bilinear_map(kind, *selections)
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    shape = np.broadcast_shapes(a.shape[:-1], b.shape[:-1])
    # one batch axis of SPARSE_MIN_ROWS rows or more: there the matrix product sums row by row
    # in order, and the blade-by-blade sums (a few whole-row operations per blade) are faster;
    # below it the one matrix product is (4-5x on a few rows: a tiny input's fixed cost)
    steps = (_sparse_steps(kind, *selections) if blades_out.size and len(shape) == 1 and shape[0] >= SPARSE_MIN_ROWS
             else None)
    if steps is not None and blades_b.size == 1:
        # a times one blade (a dual): each result blade takes one term, a signed column of a
        # (0.0 + term, as the sums from zero give: -0.0 becomes 0.0); np.take, several times
        # faster than indexing columns with an index array
        source, factor = _single_blade_columns(kind, *selections)
        coefficient = np.broadcast_to(b[..., blades_b[0]], shape)[:, None]
        return np.take(np.broadcast_to(a, shape + (BLADE_COUNT,)), source, axis=-1) * (coefficient * factor) + 0.0
    if steps is not None:
        # one row per blade, the batch along it: each step is a few whole-row operations
        rows = shape[0]
        left = np.take(np.broadcast_to(a, shape + (BLADE_COUNT,)), blades_a, axis=-1).T
        right = np.take(np.broadcast_to(b, shape + (BLADE_COUNT,)), blades_b, axis=-1).T
        result = np.zeros((BLADE_COUNT, rows))
        for i, js, ks, signs in steps:
            result[blades_out[ks]] += left[i] * (right[js] * signs)
        return np.ascontiguousarray(result.T)
    out = np.zeros(shape + (BLADE_COUNT,))
    if blades_out.size:
        left = a[..., blades_a][..., :, None]
        right = b[..., blades_b][..., None, :]
        pairs = (left * right).reshape(shape + (blades_a.size * blades_b.size,))
        out[..., blades_out] = rows_times(pairs, matrix)
    return out



def right_operator(kind: str, b, grades_a: Sequence[int], grades_b: Sequence[int] = ALL_GRADES,
                   grades_out: Sequence[int] = ALL_GRADES) -> tuple[np.ndarray, np.ndarray]:
    """The linear map a -> a (kind) b for fixed b (..., 32), as (blades_a, matrix (..., A, 32)).

    Row i of the matrix is the product of the i-th blade admitted by ``grades_a`` with b, so
    for many a per b, a[..., blades_a] @ matrix gives the products: one small matrix product
    per b instead of a pairwise product per a. ``kind``: "geometric", "outer" or "inner".
    """
    blades_a, blades_b, blades_out, matrix = _bilinear_map(
        kind, _selection(grades_a), _selection(grades_b), _selection(grades_out)
    )
    b = np.asarray(b, dtype=np.float64)
    per_b = matrix.reshape(blades_a.size, blades_b.size, -1).transpose(1, 0, 2).reshape(blades_b.size, -1)
    out = np.zeros(b.shape[:-1] + (blades_a.size, BLADE_COUNT))
    if blades_out.size:
        out[..., blades_out] = rows_times(b[..., blades_b], per_b).reshape(
            b.shape[:-1] + (blades_a.size, blades_out.size))
    return blades_a, out


def geometric(a, b, grades_a: Sequence[int] = ALL_GRADES, grades_b: Sequence[int] = ALL_GRADES,
              grades_out: Sequence[int] = ALL_GRADES) -> np.ndarray:
    """Geometric product a b, optionally keeping only ``grades_out`` of the result."""
    return _product("geometric", a, b, grades_a, grades_b, grades_out)


def outer(a, b, grades_a: Sequence[int] = ALL_GRADES, grades_b: Sequence[int] = ALL_GRADES) -> np.ndarray:
    """Outer (wedge) product a ^ b."""
    return _product("outer", a, b, grades_a, grades_b, ALL_GRADES)


def inner(a, b, grades_a: Sequence[int] = ALL_GRADES, grades_b: Sequence[int] = ALL_GRADES) -> np.ndarray:
    """Hestenes inner product a | b (grade |r - s| of each pair, zero with a scalar), as clifford."""
    return _product("inner", a, b, grades_a, grades_b, ALL_GRADES)


def reverse(a) -> np.ndarray:
    """Reversion ~a."""
    return np.asarray(a, dtype=np.float64) * REVERSE_SIGN


def grade(a, *grades: int) -> np.ndarray:
    """The parts of a of the given grades (others set to zero)."""
    return np.where(np.isin(GRADES, grades), np.asarray(a, dtype=np.float64), 0.0)


def scalar_part(a) -> np.ndarray:
    """<a>_0 as an array of shape a.shape[:-1]."""
    return np.asarray(a)[..., 0]


PSEUDOSCALAR = np.zeros(BLADE_COUNT)
PSEUDOSCALAR[-1] = 1.0
# I^2 = -1 in G(4,1), so I^-1 = -I.
PSEUDOSCALAR_INVERSE = -PSEUDOSCALAR


def dual(a) -> np.ndarray:
    """Dual a I^-1, as clifford's ``MultiVector.dual()``."""
    return geometric(a, PSEUDOSCALAR_INVERSE, ALL_GRADES, (5,))
