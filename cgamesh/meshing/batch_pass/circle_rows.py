"""Circle blades of many rings read out blade-major: the per-chain readout's arithmetic, bit for bit.

The per-chain path reads each ring out of its normalised circle blade C and dC/dt
(``motor_surface.circle_blades`` / ``circle_blade_rates``, ``objects.circle_euclidean``,
``CircleRings``: Omega = C dC/dt), as (K, 32) multivectors. Here the same products are formed
on blade-major rows: a grade-r operand is the (blades, K) array of the coefficients it can
carry, each blade a contiguous row, and every product sums its non-zero terms in the order
the batched products do (``products.product_terms``), so every value is the same float. What
changes is the work around the products: no (K, 32) arrays, no gathers of their columns, and
the sphere, plane and blade computed once for both C and dC/dt. ``tests/test_batched.py``
holds the two readouts to the same bits.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from cgamesh.geometry.algebra import products
from cgamesh.geometry.algebra.conformal import N_INF
from cgamesh.geometry.algebra.layout import BLADE_COUNT, grade_indices

_VECTOR = grade_indices(1)
_N_INF = N_INF[_VECTOR][:, None]  # n_inf's vector coefficients, a column against (5, K) rows
_N_INF_BLADES = products.Blades(int(b) for b in np.flatnonzero(N_INF))  # e4, e5
_N_INF_ROWS = N_INF[list(_N_INF_BLADES)][:, None]


@lru_cache(maxsize=None)
def _dual_map(grade: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``products.dual`` on grade-``grade`` rows: (source row, factor) per result blade, and the
    result blades (grade 5 - grade): result = source * (-1 * factor) + 0.0, as the signed gather
    of a product with the one-blade I^-1."""
    source, factor = products._single_blade_columns(
        "geometric", products._selection(products.ALL_GRADES), products._selection((5,)),
        products._selection(products.ALL_GRADES))
    admitted = grade_indices(grade)
    result = grade_indices(5 - grade)
    return np.searchsorted(admitted, source[result]), factor[result], result


def _dual(rows: np.ndarray, grade: int) -> np.ndarray:
    """Dual rows (grade 5 - grade) of grade-``grade`` rows, the bits of ``products.dual``."""
    source, factor, _ = _dual_map(grade)
    return rows[source] * (products.PSEUDOSCALAR_INVERSE[-1] * factor)[:, None] + 0.0


def _square(rows: np.ndarray, grade: int) -> np.ndarray:
    """The scalar X^2 (K,) of grade-``grade`` rows (``objects.square``)."""
    return products.row_product("geometric", rows, rows, (grade,), (grade,), (0,))[1][0]


def _vector_rows(x: np.ndarray, n_inf_part: np.ndarray) -> np.ndarray:
    """Rows (5, K) of vector(x) + s n_inf, elementwise as the (K, 32) sum forms them."""
    rows = np.zeros((5, len(x)))
    rows[:3] = x.T
    rows += n_inf_part[None, :] * _N_INF
    return rows


@dataclass(frozen=True)
class CircleRows:
    """Normalised circles C (10, K) and dC/dt (10, K) as trivector rows (layout order)."""

    blades: np.ndarray
    rates: np.ndarray

    @classmethod
    def of(cls, state) -> "CircleRows":
        """``circle_blades(state)`` and ``circle_blade_rates(state)``, sharing their common work."""
        c, n, r = state.centre, state.normal, state.radius
        dc, dn, dr = state.d_centre, state.d_normal, state.d_radius
        # _dual_circles: S = up(c) - r^2 n_inf / 2, P = n + (n . c) n_inf and their rates
        half_square = 0.5 * np.einsum("...i,...i->...", c, c)
        sphere = np.zeros((5, len(c)))
        sphere[:3] = c.T
        sphere[3] = half_square - 0.5
        sphere[4] = half_square + 0.5
        sphere -= (0.5 * r * r)[None, :] * _N_INF
        d_sphere = _vector_rows(dc, np.einsum("ai,ai->a", c, dc) - r * dr)
        plane = _vector_rows(n, np.einsum("ai,ai->a", n, c))
        d_plane = _vector_rows(dn, np.einsum("ai,ai->a", dn, c) + np.einsum("ai,ai->a", n, dc))
        one = (1,)
        raw = _dual(products.row_product("outer", sphere, plane, one, one, products.ALL_GRADES)[1], 2)
        d_raw = _dual(products.row_product("outer", d_sphere, plane, one, one, products.ALL_GRADES)[1]
                      + products.row_product("outer", sphere, d_plane, one, one, products.ALL_GRADES)[1], 2)
        size_sq = _square(raw, 3)
        size = np.sqrt(size_sq)
        blades = raw / size[None, :]
        half_d_size_sq = products.row_product("geometric", raw, d_raw, (3,), (3,), (0,))[1][0]
        rates = d_raw / size[None, :] - raw * (half_d_size_sq / (size_sq * size))[None, :]
        return cls(blades, rates)

    def euclidean(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``objects.circle_euclidean``: centre (K, 3), unit normal (K, 3), radius (K,)."""
        circles = self.blades
        # n_inf carries e4 and e5 only: the terms of its zero coefficients, and those of the
        # blades the product with it never makes, are exact zeros, which a sum from zero of
        # finite terms does not feel: the same rows from fewer terms
        plane = products.row_product("outer", circles, _N_INF_ROWS, (3,), _N_INF_BLADES, products.ALL_GRADES)[1]  # grade 4
        blades_out, moved = products.row_product("geometric", circles, _N_INF_ROWS, (3,), _N_INF_BLADES, (2, 4))
        _, point = products.row_product("geometric", moved, circles, products.Blades(int(b) for b in blades_out),
                                        (3,), (1,))
        # (K, 3) arrays laid out as the per-chain readout's column gathers lay them out, (3, K) in
        # memory: numpy's einsum sums a row in an order that depends on the layout
        normal = (-_dual(plane, 4)[:3]).T
        normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
        radius_sq = -_square(circles, 3) / _square(plane, 4)
        centre = (point[:3] / (point[4] - point[3])[None, :]).T  # conformal.down
        return centre, normal, np.sqrt(radius_sq)

    def omega(self) -> np.ndarray:
        """Omega = C dC/dt as bivector rows (10, K) (``CircleRings.omega``'s bivector part)."""
        return products.row_product("geometric", self.blades, self.rates, (3,), (3,), (2,))[1]

    def as_multivectors(self) -> tuple[np.ndarray, np.ndarray]:
        """C and dC/dt as (K, 32) multivectors (for tests)."""
        out = []
        for rows in (self.blades, self.rates):
            full = np.zeros((rows.shape[1], BLADE_COUNT))
            full[:, grade_indices(3)] = rows.T
            out.append(full)
        return out[0], out[1]
