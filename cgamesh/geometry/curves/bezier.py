"""Bezier curves of any order and their rational form (paper sections 8.4 and 8.5)."""

from __future__ import annotations

from dataclasses import dataclass
from math import comb, lgamma

import numpy as np

from cgamesh.geometry.curves import CurveBasis


# Up to this order the binomial coefficients and the powers are exact enough as they are;
# beyond it C(N, i) overflows float64 (near N = 1030) while alpha^i (1 - alpha)^(N - i)
# underflows, so the product is formed from logarithms instead.
DIRECT_ORDER = 60


def bernstein(order: int, alpha: np.ndarray) -> np.ndarray:
    """Bernstein polynomials b_{i,N}(alpha), shape (A, N + 1), for any order N."""
    alpha = np.asarray(alpha, dtype=np.float64)[:, None]
    i = np.arange(order + 1)
    if order <= DIRECT_ORDER:
        coefficients = np.array([comb(order, k) for k in i], dtype=np.float64)
        return coefficients * alpha**i * (1.0 - alpha) ** (order - i)
    log_coefficients = np.array([lgamma(order + 1) - lgamma(k + 1) - lgamma(order - k + 1) for k in i])
    with np.errstate(divide="ignore", invalid="ignore"):
        log_a, log_b = np.log(alpha), np.log1p(-alpha)
        # i log(alpha) with i = 0 is 0 even at alpha = 0 (0^0 = 1), likewise for 1 - alpha.
        powers = np.where(i == 0, 0.0, i * log_a) + np.where(i == order, 0.0, (order - i) * log_b)
    return np.exp(log_coefficients + powers)


def bernstein_derivative(order: int, alpha: np.ndarray) -> np.ndarray:
    """d b_{i,N} / d alpha = N (b_{i-1,N-1} - b_{i,N-1}), shape (A, N + 1)."""
    if order == 0:
        return np.zeros((len(alpha), 1))
    lower = bernstein(order - 1, alpha)
    padded = np.pad(lower, ((0, 0), (1, 1)))
    return order * (padded[:, :-1] - padded[:, 1:])


@dataclass(frozen=True)
class Bezier:
    """One Bezier curve of order N = control_count - 1 over alpha in [0, 1]."""

    control_count: int
    segment_count: int = 1

    def basis(self, t: np.ndarray) -> CurveBasis:
        t = np.asarray(t, dtype=np.float64)
        order = self.control_count - 1
        indices = np.broadcast_to(np.arange(self.control_count), (len(t), self.control_count))
        return CurveBasis(indices, bernstein(order, t), bernstein_derivative(order, t))


@dataclass(frozen=True)
class RationalBezier:
    """C' = sum b_i w_i C_i / sum b_j w_j (eq. 32 for the derivative); weights > 0."""

    weights: tuple[float, ...]
    segment_count: int = 1

    @property
    def control_count(self) -> int:
        return len(self.weights)

    def basis(self, t: np.ndarray) -> CurveBasis:
        t = np.asarray(t, dtype=np.float64)
        order = self.control_count - 1
        w = np.asarray(self.weights, dtype=np.float64)
        w = w / w.max()  # the curve is unchanged by a common factor; 1e300 weights stay finite
        rational, d_rational = rational_weights(bernstein(order, t), bernstein_derivative(order, t), w)
        indices = np.broadcast_to(np.arange(self.control_count), rational.shape)
        return CurveBasis(indices, rational, d_rational)


def rational_weights(b: np.ndarray, db: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """b_i w_i / sum b_j w_j (A, n) and its d/dalpha, from the Bernstein basis b, db (A, n) and
    the weights w, (n,) or one row per parameter (A, n), divided by their largest."""
    # row sums, not b @ w: BLAS's matrix-vector kernel sums a lone row, or a few, in another
    # order than many, and a curve's basis must not depend on how many parameters it is given
    denominator = (b * w).sum(axis=1)
    d_denominator = (db * w).sum(axis=1)
    rational = b * w / denominator[:, None]
    # Quotient rule of eq. 32, written per basis function.
    return rational, (db * w - rational * d_denominator[:, None]) / denominator[:, None]
