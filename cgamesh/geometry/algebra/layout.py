"""The blade layout of CGA G(4,1) and its product tables, built from first principles.

Blades are ordered exactly as ``clifford.g3c`` orders them (grade first, then
lexicographic): 1, e1..e5, e12, e13, ..., e45, e123, ..., e345, e1234, ..., e2345, e12345.
A multivector is a float64 array whose last axis holds these 32 coefficients.

Each blade is a bitmap (bit i set <=> e_{i+1} is a factor). The geometric product of two
basis blades is another basis blade (XOR of the bitmaps) times a sign that comes from
counting the swaps needed to sort the factors and from the metric e1..e4^2 = +1, e5^2 = -1.
The outer and inner products are grade selections of the same table, so one table is the
single source of truth.
"""

from __future__ import annotations

from itertools import combinations

import numpy as np

DIMENSION = 5
METRIC = (1.0, 1.0, 1.0, 1.0, -1.0)  # e1..e4 square to +1, e5 to -1

# Blade bitmaps in clifford's order: by grade, then lexicographic in the factor indices.
BLADE_BITMAPS: tuple[int, ...] = tuple(
    sum(1 << i for i in factors)
    for grade in range(DIMENSION + 1)
    for factors in combinations(range(DIMENSION), grade)
)
BLADE_COUNT = len(BLADE_BITMAPS)  # 32
BLADE_NAMES: tuple[str, ...] = tuple(
    "1" if b == 0 else "e" + "".join(str(i + 1) for i in range(DIMENSION) if b >> i & 1)
    for b in BLADE_BITMAPS
)
GRADES = np.array([bin(b).count("1") for b in BLADE_BITMAPS], dtype=np.int64)
_INDEX_OF_BITMAP = {b: i for i, b in enumerate(BLADE_BITMAPS)}


def blade_index(name: str) -> int:
    """Index of a basis blade by name, e.g. ``blade_index("e45")``; "1" is the scalar."""
    return BLADE_NAMES.index(name)


def grade_indices(*grades: int) -> np.ndarray:
    """Indices of the blades of the given grades, in layout order."""
    return np.flatnonzero(np.isin(GRADES, grades))


def _reordering_sign(a: int, b: int) -> int:
    """Sign of sorting the factors of blade a followed by blade b into canonical order."""
    a >>= 1
    swaps = 0
    while a:
        swaps += bin(a & b).count("1")
        a >>= 1
    return -1 if swaps & 1 else 1


def _basis_product(a: int, b: int) -> tuple[int, float]:
    """Geometric product of two basis blades: (result bitmap, sign including the metric)."""
    sign = float(_reordering_sign(a, b))
    common = a & b
    for i in range(DIMENSION):
        if common >> i & 1:
            sign *= METRIC[i]
    return a ^ b, sign


def _build_geometric_table() -> tuple[np.ndarray, np.ndarray]:
    """(32, 32) arrays: result blade index and sign of e_i e_j."""
    index = np.empty((BLADE_COUNT, BLADE_COUNT), dtype=np.int64)
    sign = np.empty((BLADE_COUNT, BLADE_COUNT))
    for i, a in enumerate(BLADE_BITMAPS):
        for j, b in enumerate(BLADE_BITMAPS):
            bitmap, s = _basis_product(a, b)
            index[i, j] = _INDEX_OF_BITMAP[bitmap]
            sign[i, j] = s
    return index, sign


PRODUCT_INDEX, GEOMETRIC_SIGN = _build_geometric_table()

# Outer product: the grade-(r+s) part of e_i e_j; inner product (Hestenes, as clifford's
# ``|``): the grade-|r-s| part, zero when either factor is a scalar.
_GRADE_I = GRADES[:, None]
_GRADE_J = GRADES[None, :]
_GRADE_K = GRADES[PRODUCT_INDEX]
OUTER_SIGN = np.where(_GRADE_K == _GRADE_I + _GRADE_J, GEOMETRIC_SIGN, 0.0)
INNER_SIGN = np.where(
    (_GRADE_K == np.abs(_GRADE_I - _GRADE_J)) & (_GRADE_I > 0) & (_GRADE_J > 0),
    GEOMETRIC_SIGN,
    0.0,
)

# Reverse: a grade-r blade changes sign by (-1)^(r(r-1)/2).
REVERSE_SIGN = np.where((GRADES * (GRADES - 1) // 2) % 2 == 1, -1.0, 1.0)
