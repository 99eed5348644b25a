"""Batched products of multivectors stored as (..., 32) float64 arrays.

A product is bilinear: with A and B the coefficients of the blades each operand can carry,
the result is the outer product A B^T, flattened, times a fixed sign-and-placement matrix
(one matrix product over the whole batch). Callers name the grades their operands carry (a
circle is grade 3, a rotor grades 0, 2, 4), and the matrix for that pattern is built once
and cached: a circle times a circle is a 100-column product, not 1024, with no
per-element Python. Where an operand lives in a smaller subspace than whole grades (a
Euclidean rotation rotor: 1, e12, e13, e23), callers may name its blades instead
(``Blades``): a product of two such rotors is then 16 columns, not 121. On a batch (one
axis of two rows or more) the same sums are formed one non-zero term at a time, as whole-row
multiplies and adds over the batch (``_term_lists``), instead of through the mostly-zero
matrix: 4-25x faster on circles, the same bits.
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
# Batches from this many rows are summed term by term (``_term_lists``), smaller ones through
# the matrix (``rows_times``: a lone row multiplied as two, as a batch sums it): the same bits
# either way (tests/test_products_sparse.py), and the crossover in time lies between 50 and 500 rows.
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
    # the blades present, ascending (np.unique would import numpy.ma, 1.3 MB resident, to look for a mask)
    blades_out = np.flatnonzero(np.bincount(result[sign != 0.0], minlength=BLADE_COUNT))
    column = np.searchsorted(blades_out, result)
    matrix = np.zeros((blades_a.size * blades_b.size, max(blades_out.size, 1)))
    rows = np.arange(matrix.shape[0])
    keep = sign.ravel() != 0.0
    matrix[rows[keep], column.ravel()[keep]] = sign.ravel()[keep]
    return blades_a, blades_b, blades_out, matrix


@lru_cache(maxsize=None)
def _term_lists(kind: str, grades_a: tuple, grades_b: tuple, grades_out: tuple):
    """The product as sums of signed blade-pair products: for each result blade (index into
    blades_out), its terms (i, j, positive) meaning +-a_i b_j, in the matrix's row order.

    Each pair of blades makes one blade, so the sign-and-placement matrix has one non-zero per
    row and entries +-1: its product sums, for each result blade, the rounded a_i b_j of its rows
    in row order from zero, and so does adding the terms one at a time (a zero entry adds nothing,
    a +-1 factor rounds nothing). Both agree bit for bit on a batch of two rows or more along one
    axis, up to 256 blade pairs (measured against numpy's and OpenBLAS's products; past 256 pairs
    the matrix product sums in blocks, another order: None).
    """
    blades_a, blades_b, blades_out, matrix = _bilinear_map(kind, grades_a, grades_b, grades_out)
    if blades_a.size * blades_b.size > 256 or not blades_out.size:
        return None
    lists = []
    for k in range(blades_out.size):
        rows = np.flatnonzero(matrix[:, k])
        lists.append(tuple((int(r // blades_b.size), int(r % blades_b.size), bool(matrix[r, k] > 0.0))
                           for r in rows))
    return tuple(lists)


@lru_cache(maxsize=None)
def _single_blade_columns(kind: str, grades_a: tuple, grades_b: tuple, grades_out: tuple):
    """A product with a one-blade operand as a signed gather: result column c is a's column
    ``source[c]`` times b's coefficient times ``factor[c]`` (0 where no term lands)."""
    blades_a, _, blades_out, _ = _bilinear_map(kind, grades_a, grades_b, grades_out)
    source = np.zeros(BLADE_COUNT, dtype=np.int64)
    factor = np.zeros(BLADE_COUNT)
    for k, terms in enumerate(_term_lists(kind, grades_a, grades_b, grades_out)):
        for i, _, positive in terms:  # one term per result blade: b has one blade
            source[blades_out[k]] = blades_a[i]
            factor[blades_out[k]] = 1.0 if positive else -1.0
    return source, factor


def _summed_rows(terms, left, right, rows: int) -> np.ndarray:
    """(O, rows): each result blade's ``_term_lists`` terms summed one at a time from zero, from
    operand rows left (A, rows) and right (B, rows) (a row may be a scalar broadcast along the
    batch): whole-row multiplies and adds into preallocated rows, no gathers."""
    summed = np.empty((len(terms), rows))
    scratch = np.empty(rows)
    for k, blade_terms in enumerate(terms):
        out = summed[k]
        if not blade_terms:
            out.fill(0.0)
            continue
        i, j, positive = blade_terms[0]
        np.multiply(left[i], right[j], out=out)
        # 0 + term (or 0 - term), as the sum from zero: -0.0 becomes 0.0
        if positive:
            np.add(out, 0.0, out=out)
        else:
            np.subtract(0.0, out, out=out)
        for i, j, positive in blade_terms[1:]:
            np.multiply(left[i], right[j], out=scratch)
            if positive:
                np.add(out, scratch, out=out)
            else:
                np.subtract(out, scratch, out=out)
    return summed


def row_product(kind: str, left: np.ndarray, right: np.ndarray, grades_a: Sequence[int], grades_b: Sequence[int],
                grades_out: Sequence[int]) -> tuple[np.ndarray, np.ndarray]:
    """A product of operands stored blade-major: left (A, K) the coefficients of the blades
    ``grades_a`` admits (layout order), one row per blade (a row of shape (1,) is a constant),
    right (B, K) likewise. Returns (blades_out, (O, K) rows): the same sums, so the same bits,
    as the (..., 32) products on a batch, without a (K, 32) array or a gather of its columns.
    At most 256 blade pairs."""
    blades_a, blades_b, blades_out, terms = product_terms(kind, grades_a, grades_b, grades_out)
    if terms is None:
        raise ValueError(f"row_product takes at most 256 blade pairs, got {blades_a.size * blades_b.size}")
    return blades_out, _summed_rows(terms, left, right, max(np.shape(left)[-1], np.shape(right)[-1]))


def admitted_rows(blades: np.ndarray, rows: np.ndarray, grades: Sequence[int]) -> np.ndarray:
    """Rows of every blade ``grades`` admits from rows (len(blades), K) of ``blades`` (zero where
    ``blades`` has none; rows of blades it does not admit are dropped), as a product's result
    becomes the operand of the next."""
    size, target, source = _admission(tuple(int(b) for b in blades), _selection(grades))
    full = np.zeros((size, rows.shape[1]))
    full[target] = rows[source]
    return full


@lru_cache(maxsize=None)
def _admission(blades: tuple[int, ...], selection) -> tuple[int, np.ndarray, np.ndarray]:
    """admitted_rows' placement, once per (blades, grades): the admitted blade count, and which
    row of the result (target) each admitted row of ``blades`` (source) fills."""
    admitted = np.flatnonzero(_mask(selection))
    blades = np.asarray(blades, dtype=np.int64)
    source = np.flatnonzero(np.isin(blades, admitted))
    return admitted.size, np.searchsorted(admitted, blades[source]), source


def _product(kind, a, b, grades_a, grades_b, grades_out):
    selections = _selection(grades_a), _selection(grades_b), _selection(grades_out)
    blades_a, blades_b, blades_out, matrix = _bilinear_map(kind, *selections)
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    shape = np.broadcast_shapes(a.shape[:-1], b.shape[:-1])
    # one batch axis of SPARSE_MIN_ROWS rows or more: the terms summed one at a time, faster
    # there; below it the one matrix product (4-5x faster on a few rows: a tiny input's fixed
    # cost), which sums every row's terms in the same order (rows_times: a lone row too)
    terms = _term_lists(kind, *selections) if len(shape) == 1 and shape[0] >= SPARSE_MIN_ROWS else None
    if terms is not None and blades_b.size == 1:
        # a times one blade (a dual): each result blade takes one term, a signed column of a
        # (0.0 + term, as the sums from zero give: -0.0 becomes 0.0); np.take, several times
        # faster than indexing columns with an index array
        source, factor = _single_blade_columns(kind, *selections)
        coefficient = np.broadcast_to(b[..., blades_b[0]], shape)[:, None]
        return np.take(np.broadcast_to(a, shape + (BLADE_COUNT,)), source, axis=-1) * (coefficient * factor) + 0.0
    if terms is not None:
        # operands blade-major, each blade a contiguous row (a constant operand: a row of scalars);
        # rows strided through the (rows, 32) layout would make every term several times slower
        left = np.moveaxis(a, -1, 0)[blades_a]
        right = np.moveaxis(b, -1, 0)[blades_b]
        out = np.zeros(shape + (BLADE_COUNT,))
        out[:, blades_out] = _summed_rows(terms, left, right, shape[0]).T  # only the result's blades cross back
        return out
    out = np.zeros(shape + (BLADE_COUNT,))
    if blades_out.size:
        left = a[..., blades_a][..., :, None]
        right = b[..., blades_b][..., None, :]
        pairs = (left * right).reshape(shape + (blades_a.size * blades_b.size,))
        out[..., blades_out] = rows_times(pairs, matrix)
    return out


def product_terms(kind: str, grades_a: Sequence[int], grades_b: Sequence[int], grades_out: Sequence[int]):
    """(blades_a, blades_b, blades_out, terms) of a product restricted to grades (or ``Blades``):
    terms[k] lists result blade blades_out[k]'s terms (i, j, positive), +-a[blades_a[i]] b[blades_b[j]],
    in the order the batched products sum them; for callers that form a product's few terms
    themselves (operands not stored as (..., 32) multivectors). None past 256 blade pairs."""
    selections = _selection(grades_a), _selection(grades_b), _selection(grades_out)
    blades_a, blades_b, blades_out, _ = _bilinear_map(kind, *selections)
    return blades_a, blades_b, blades_out, _term_lists(kind, *selections)


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
