"""The conformal model: n_inf, n_0, the embedding up(x) and its inverse down(X).

Conventions of the scene format (and clifford.g3c): n_inf = e4 + e5, n_0 = (e5 - e4) / 2,
up(x) = x + x^2 n_inf / 2 + n_0 (paper eq. 1).
"""

from __future__ import annotations

import numpy as np

from cgamesh.geometry.algebra.layout import BLADE_COUNT, blade_index

E1, E2, E3, E4, E5 = (blade_index(f"e{i}") for i in range(1, 6))
EUCLIDEAN = np.array([E1, E2, E3])

N_INF = np.zeros(BLADE_COUNT)
N_INF[[E4, E5]] = 1.0
N_0 = np.zeros(BLADE_COUNT)
N_0[E4], N_0[E5] = -0.5, 0.5


def vector(x) -> np.ndarray:
    """Euclidean vectors (..., 3) as grade-1 multivectors (..., 32)."""
    x = np.asarray(x, dtype=np.float64)
    out = np.zeros(x.shape[:-1] + (BLADE_COUNT,))
    out[..., E1:E3 + 1] = x  # e1, e2, e3 are consecutive blades (tests/test_normals_unit_rows.py): a slice, not a gather
    return out


def up(x) -> np.ndarray:
    """Conformal points up(x) = x + x^2 n_inf / 2 + n_0 for x of shape (..., 3)."""
    x = np.asarray(x, dtype=np.float64)
    half_square = 0.5 * np.einsum("...i,...i->...", x, x)
    out = vector(x)
    # x^2/2 n_inf + n_0: e4 gets x^2/2 - 1/2, e5 gets x^2/2 + 1/2.
    out[..., E4] = half_square - 0.5
    out[..., E5] = half_square + 0.5
    return out


def weight(X) -> np.ndarray:
    """-X . n_inf, the factor by which a conformal point is scaled (1 for up(x))."""
    X = np.asarray(X)
    # X . n_inf = X4 * 1 + X5 * (-1) with e5^2 = -1.
    return X[..., E5] - X[..., E4]


def down(X) -> np.ndarray:
    """Euclidean points (..., 3) of conformal points X (..., 32), any non-zero weight."""
    X = np.asarray(X)
    return X[..., EUCLIDEAN] / weight(X)[..., None]
