"""Projection of interpolated multivectors back to the blade manifold (paper eqs. 10-12, section 6).

For an interpolated object X' of one grade (a circle or a point pair that is no longer a
blade), Sigma = -X' ~X' has only a scalar part s and a 4-vector part F, whose square
q = F^2 is a scalar in G(4,1). With beta = [[Sigma]] = sqrt(s^2 - q) and g = s + beta,
the principal square root (eq. 10) is

    sqrt(Sigma) = m0 + m4,   m0 = sqrt(g / 2),   m4 = F / sqrt(2 g),

and since (m0 + m4)(m0 - m4) = m0^2 - m4^2 = beta, the projector of eqs. 11-12 is its inverse

    S = (m0 - m4) / beta,    X = S X'   (so that X^2 = S^2 Sigma = 1).

The derivative dS/dalpha follows by the chain rule through s, F, q, beta, g; the printed
eq. 30 has a sign slip (d(1/f) = -f'/f^2), which this form avoids; tests compare it with
central differences. The projection exists only where beta > 0 and g > 0; ``margin`` measures
how far each sample is from that boundary, relative to the size of the interpolant.
When Sigma has no 4-vector part for any interpolant of the controls (co-circular point pairs,
paper section 7.3), ``project_scalar`` gives the same result without the 4-vector square root.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cgamesh.geometry.algebra import products
from cgamesh.geometry.algebra.layout import GRADES

_FOUR_VECTOR = GRADES == 4
# Controls whose symmetric 4-vector products stay below this (relative) take ``project_scalar``.
FOUR_VECTOR_RTOL = 1e-10


@dataclass(frozen=True)
class Projection:
    """blades (A, 32) = S X'; derivatives (A, 32) = d(S X')/d alpha; margin (A,)."""

    blades: np.ndarray
    derivatives: np.ndarray
    margin: np.ndarray


def project(interpolant: np.ndarray, derivative: np.ndarray, grade: int, size: np.ndarray) -> Projection:
    """Project X' (A, 32) of one grade onto blades, with the derivative of the projection.

    derivative: dX'/dalpha (A, 32). size: (A,) an upper bound of |X'| for unit controls (the
    basis weights' absolute sum), so the margin is comparable between samples and curves.
    Samples whose margin is not positive get NaN blades: callers must check the margin.
    """
    g_ = (grade,)
    reversed_interpolant = products.reverse(interpolant)
    sigma = -products.geometric(interpolant, reversed_interpolant, g_, g_, (0, 4))
    d_sigma = -(
        products.geometric(derivative, reversed_interpolant, g_, g_, (0, 4))
        + products.geometric(interpolant, products.reverse(derivative), g_, g_, (0, 4))
    )
    s, ds = sigma[:, 0], d_sigma[:, 0]
    four, d_four = sigma * _FOUR_VECTOR, d_sigma * _FOUR_VECTOR
    q = products.geometric(four, four, (4,), (4,), (0,))[:, 0]
    dq = 2.0 * products.geometric(four, d_four, (4,), (4,), (0,))[:, 0]  # 4-vectors commute here

    with np.errstate(invalid="ignore", divide="ignore"):
        beta = np.sqrt(s * s - q)
        g = s + beta
        d_beta = (s * ds - 0.5 * dq) / beta
        d_g = ds + d_beta
        m0 = np.sqrt(0.5 * g)
        d_m0 = d_g / (4.0 * m0)
        root_two_g = np.sqrt(2.0 * g)
        m4 = four / root_two_g[:, None]
        d_m4 = d_four / root_two_g[:, None] - four * (d_g / (2.0 * g * root_two_g))[:, None]

        projector = -m4 / beta[:, None]
        projector[:, 0] = m0 / beta
        d_projector = -(d_m4 / beta[:, None] - m4 * (d_beta / beta**2)[:, None])
        d_projector[:, 0] = d_m0 / beta - m0 * d_beta / beta**2

    blades = products.geometric(projector, interpolant, (0, 4), g_, g_)
    derivatives = products.geometric(d_projector, interpolant, (0, 4), g_, g_) + products.geometric(
        projector, derivative, (0, 4), g_, g_
    )
    return Projection(blades, derivatives, _margin(beta, g, size))


def project_without_derivatives(interpolant: np.ndarray, grade: int, size: np.ndarray,
                                scalar: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """(blades, margin) of ``project`` (``project_scalar`` when ``scalar``), bit for bit the same
    arithmetic, without the derivatives: for readers that need only the objects (a tolerance
    plan reads thousands), at about a third of the products."""
    g_ = (grade,)
    reversed_interpolant = products.reverse(interpolant)
    if scalar:
        s = -products.geometric(interpolant, reversed_interpolant, g_, g_, (0,))[:, 0]
        with np.errstate(invalid="ignore", divide="ignore"):
            blades = interpolant / np.sqrt(s)[:, None]
        return blades, np.nan_to_num(s / np.square(size), nan=-1.0)
    sigma = -products.geometric(interpolant, reversed_interpolant, g_, g_, (0, 4))
    s = sigma[:, 0]
    four = sigma * _FOUR_VECTOR
    q = products.geometric(four, four, (4,), (4,), (0,))[:, 0]
    with np.errstate(invalid="ignore", divide="ignore"):
        beta = np.sqrt(s * s - q)
        g = s + beta
        m0 = np.sqrt(0.5 * g)
        m4 = four / np.sqrt(2.0 * g)[:, None]
        projector = -m4 / beta[:, None]
        projector[:, 0] = m0 / beta
    return products.geometric(projector, interpolant, (0, 4), g_, g_), _margin(beta, g, size)


def project_blades(interpolant: np.ndarray, grade: int, scalar: bool = False) -> np.ndarray:
    """The blades S X' (A, 32) of ``project`` (``project_scalar`` when ``scalar``) without their
    derivatives, for dense scans; NaN where the projection does not exist (no warning)."""
    g_ = (grade,)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        if scalar:
            s = -products.geometric(interpolant, products.reverse(interpolant), g_, g_, (0,))[:, 0]
            return interpolant / np.sqrt(s)[:, None]
        sigma = -products.geometric(interpolant, products.reverse(interpolant), g_, g_, (0, 4))
        s, four = sigma[:, 0], sigma * _FOUR_VECTOR
        q = products.geometric(four, four, (4,), (4,), (0,))[:, 0]
        beta = np.sqrt(s * s - q)
        g = s + beta
        projector = -four / (np.sqrt(2.0 * g) * beta)[:, None]
        projector[:, 0] = np.sqrt(0.5 * g) / beta
        return products.geometric(projector, interpolant, (0, 4), g_, g_)


def margin(interpolant: np.ndarray, grade: int, size: np.ndarray, scalar: bool = False) -> np.ndarray:
    """The ``Projection.margin`` (A,) of ``project``, or of ``project_scalar`` when ``scalar``,
    without the projection itself: for dense scans."""
    g_ = (grade,)
    grades_out = (0,) if scalar else (0, 4)
    sigma = -products.geometric(interpolant, products.reverse(interpolant), g_, g_, grades_out)
    s = sigma[:, 0]
    if scalar:
        return np.nan_to_num(s / np.square(size), nan=-1.0)
    four = sigma * _FOUR_VECTOR
    q = products.geometric(four, four, (4,), (4,), (0,))[:, 0]
    with np.errstate(invalid="ignore"):
        beta = np.sqrt(s * s - q)
    return _margin(beta, s + beta, size)


def _margin(beta: np.ndarray, g: np.ndarray, size: np.ndarray) -> np.ndarray:
    """min(beta, g) relative to |X'|^2, and -1 where it is NaN (no real square root)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.nan_to_num(np.minimum(beta, g) / np.square(size), nan=-1.0)


def four_vector_free(controls: np.ndarray, grade: int, rtol: float = FOUR_VECTOR_RTOL) -> bool:
    """Whether Sigma = -X' ~X' is a pure scalar for every interpolant X' of the controls (n, 32).

    <Sigma>_4 = -sum_ij w_i w_j <X_i ~X_j>_4, so it vanishes for all weights exactly when
    <X_i ~X_j + X_j ~X_i>_4 = 0 for every pair: for point pairs that is P_i ^ P_j = 0, all
    end points on one circle (paper section 7.3). Relative to |X_i| |X_j| (coefficient norms).
    """
    g_ = (grade,)
    cross = products.geometric(controls[:, None], products.reverse(controls)[None], g_, g_, (4,))
    symmetric = np.abs(cross + np.swapaxes(cross, 0, 1)).max(axis=-1)
    norms = np.linalg.norm(controls, axis=-1)
    return bool(np.all(symmetric <= rtol * np.outer(norms, norms)))


def project_scalar(interpolant: np.ndarray, derivative: np.ndarray, grade: int,
                   size: np.ndarray) -> Projection:
    """``project`` when Sigma = s is a scalar (``four_vector_free`` controls; paper section 7.3).

    Then S = 1 / sqrt(s): X = X' / sqrt(s) and dX/dalpha = (dX' - X ds / (2 sqrt(s))) / sqrt(s),
    with ds = -2 <dX' ~X'>_0; no square root of a 4-vector. The margin is s / size^2, as in
    ``project`` (where beta = s and g = 2 s), and negative where X' squares to a negative number.
    """
    g_ = (grade,)
    reversed_interpolant = products.reverse(interpolant)
    s = -products.geometric(interpolant, reversed_interpolant, g_, g_, (0,))[:, 0]
    ds = -2.0 * products.geometric(derivative, reversed_interpolant, g_, g_, (0,))[:, 0]
    with np.errstate(invalid="ignore", divide="ignore"):
        root = np.sqrt(s)
        blades = interpolant / root[:, None]
        derivatives = (derivative - blades * (0.5 * ds / root)[:, None]) / root[:, None]
    return Projection(blades, derivatives, np.nan_to_num(s / np.square(size), nan=-1.0))
