"""Batched products of multivectors stored as (..., 32) float64 arrays.

A product is evaluated as a sum of terms a[..., i] * b[..., j] * sign into output blade k.
Only the terms between blades that can be non-zero are kept: callers name the grades
their operands carry (a circle is grade 3, a rotor grades 0, 2, 4), and the term list for
that pattern is built once and cached. So a circle times a circle costs 100 terms, not
1024, with no per-element Python.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Sequence

import numpy as np

from cgamesh.algebra.layout import (
    BLADE_COUNT,
    GEOMETRIC_SIGN,
    GRADES,
    INNER_SIGN,
    OUTER_SIGN,
    PRODUCT_INDEX,
    REVERSE_SIGN,
)

ALL_GRADES = (0, 1, 2, 3, 4, 5)
_SIGN_TABLES = {"geometric": GEOMETRIC_SIGN, "outer": OUTER_SIGN, "inner": INNER_SIGN}


@lru_cache(maxsize=None)
def _terms(kind: str, grades_a: tuple, grades_b: tuple, grades_out: tuple):
    """Term list of a product restricted to operand and result grades.

    Returns (ia, ib, signs, out_blades, group_starts): the terms sorted by output blade,
    ``out_blades`` the distinct output blades and ``group_starts`` where each one's run of
    terms begins (for ``np.add.reduceat``).
    """
    signs = _SIGN_TABLES[kind]
    ia, ib = np.nonzero(
        np.isin(GRADES, grades_a)[:, None]
        & np.isin(GRADES, grades_b)[None, :]
        & (signs != 0.0)
        & np.isin(GRADES[PRODUCT_INDEX], grades_out)
    )
    k = PRODUCT_INDEX[ia, ib]
    order = np.argsort(k, kind="stable")
    ia, ib, k = ia[order], ib[order], k[order]
    out_blades, group_starts = np.unique(k, return_index=True)
    return ia, ib, signs[ia, ib], out_blades, group_starts


def _product(kind, a, b, grades_a, grades_b, grades_out):
    ia, ib, signs, out_blades, starts = _terms(
        kind, tuple(sorted(grades_a)), tuple(sorted(grades_b)), tuple(sorted(grades_out))
    )
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    shape = np.broadcast_shapes(a.shape[:-1], b.shape[:-1])
    out = np.zeros(shape + (BLADE_COUNT,))
    if ia.size:
        terms = a[..., ia] * b[..., ib]
        terms *= signs
        out[..., out_blades] = np.add.reduceat(terms, starts, axis=-1)
    return out


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
