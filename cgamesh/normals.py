"""Analytic vertex normals of evolved circle surfaces (paper section 5.2, eqs. 17-25).

At a point x = c + r e_r(theta) of the circle C(t), the surface is spanned by the circle's
tangent t(theta) = n x e_r (the line L_C of eq. 17) and the velocity x' of the point carried
by the evolution, X' = X . (C dC/dt) (eqs. 19-20; the line L_T of eq. 22). Their cross
product is the normal line of eq. 25. Writing x' = rho e_r + tau t + zeta n,

    N = t x x' = zeta e_r - rho n,

so the normal has coordinates (zeta, rho) in the circle's own (e_r, -n) frame. The velocity
field of a conformal motion is quadratic in x, so zeta is a trigonometric polynomial of
degree 2 in theta, rho and N of degree 3: seven samples per ring determine them exactly,
and each vertex then costs a row of one matrix product instead of conformal algebra.

Continuity. N passes through zero where the parametrisation folds (circles crossing their
neighbours along an envelope, or all sharing a point): there the raw normal reverses. The
field is kept continuous by flipping its sign across such folds (``continuous_signs``);
exactly at a zero the direction is the limit along the circle, dN/dtheta.
"""

from __future__ import annotations

import numpy as np

TRIG_DEGREE = 3
TERMS = 2 * TRIG_DEGREE + 1
SAMPLE_ANGLES = 2.0 * np.pi * np.arange(TERMS) / TERMS
# Below this fraction of the ring's largest velocity, N is treated as zero.
ZERO_FRACTION = 1e-8
# A reversal of (zeta, rho) is a fold when the sine of the angle between its derivatives
# along theta and along t is below this (exactly 0 on a fold, order 1 at a pinch point).
FOLD_SINE = 0.25


def trig_basis(theta: np.ndarray) -> np.ndarray:
    """[1, cos t, sin t, cos 2t, sin 2t, cos 3t, sin 3t] at angles theta (M,) -> (M, 7)."""
    theta = np.asarray(theta, dtype=np.float64)[:, None]
    m = np.arange(1, TRIG_DEGREE + 1)
    columns = np.empty((theta.shape[0], TERMS))
    columns[:, 0] = 1.0
    columns[:, 1::2] = np.cos(m * theta)
    columns[:, 2::2] = np.sin(m * theta)
    return columns


def trig_basis_derivative(theta: np.ndarray) -> np.ndarray:
    """d/dtheta of ``trig_basis`` (M, 7)."""
    theta = np.asarray(theta, dtype=np.float64)[:, None]
    m = np.arange(1, TRIG_DEGREE + 1)
    columns = np.zeros((theta.shape[0], TERMS))
    columns[:, 1::2] = -m * np.sin(m * theta)
    columns[:, 2::2] = m * np.cos(m * theta)
    return columns


_FIT = np.linalg.inv(trig_basis(SAMPLE_ANGLES))  # samples -> coefficients, exact for degree <= 3
# |d/dtheta| of a coefficient's basis function is at most its frequency.
_FREQUENCY = np.concatenate([[0.0], np.repeat(np.arange(1, TRIG_DEGREE + 1), 2)])


def sample_points(centre, radius, u, v) -> tuple[np.ndarray, np.ndarray]:
    """Points (K, 7, 3) at SAMPLE_ANGLES on each ring, and the radial unit vectors there."""
    radial = (np.cos(SAMPLE_ANGLES)[None, :, None] * u[:, None, :]
              + np.sin(SAMPLE_ANGLES)[None, :, None] * v[:, None, :])
    return centre[:, None, :] + radius[:, None, None] * radial, radial


def fit(samples: np.ndarray) -> np.ndarray:
    """Trigonometric coefficients (K, 7, C) of functions sampled at SAMPLE_ANGLES (K, 7, C)."""
    return np.einsum("as,ksc->kac", _FIT, samples)


def frame_coordinates(velocity: np.ndarray, radial: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """(zeta, rho) (K, 7, 2): velocity (K, 7, 3) along the circle's normal and along e_r."""
    zeta = np.einsum("ksi,ki->ks", velocity, normal)
    rho = np.einsum("ksi,ksi->ks", velocity, radial)
    return np.stack([zeta, rho], axis=-1)


def normal_samples(zeta_rho: np.ndarray, radial: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """N = zeta e_r - rho n (K, 7, 3) at the sample angles."""
    return zeta_rho[..., 0:1] * radial - zeta_rho[..., 1:2] * normal[:, None, :]


def expand(coefficients: np.ndarray, basis: np.ndarray) -> np.ndarray:
    """Values (K, M, C) of trig polynomials (K, B, C) at the M rows of ``basis`` (M, B).

    Written as one matrix product straight into the (K, M, C) layout: the right factor is
    basis (x) identity(C), so no transposed copy of the result is ever made.
    """
    k, b, c = coefficients.shape
    m = basis.shape[0]
    spread = np.einsum("mb,cd->bcmd", basis, np.eye(c)).reshape(b * c, m * c)
    return (coefficients.reshape(k, b * c) @ spread).reshape(k, m, c)


def derivative_bound(coefficients: np.ndarray) -> np.ndarray:
    """(K,) an upper bound of |dN/dtheta| over the whole ring, from coefficients (K, 7, C)."""
    return np.linalg.norm(coefficients, axis=-1) @ _FREQUENCY


def _fold_crossings(values: np.ndarray, candidates: np.ndarray, before: np.ndarray,
                    after: np.ndarray) -> np.ndarray:
    """Which sign reversals between columns j and j+1 of a ring cross a fold (R, M-1) bool.

    values (R, M, 2); before/after (R,): the rows holding each row's neighbouring rings.
    Where the surface folds back, (zeta, rho) = lambda d with lambda changing sign along a
    curve: its derivatives across and along the rings are both parallel to d, so the
    Jacobian of (zeta, rho) over (t, theta) is singular there. A ring passing close by an
    isolated zero (a pinch point of the surface, where the field only turns quickly) shows
    the same reversal between two samples, but there the Jacobian is regular and the raw
    field is the continuous one: such reversals are not folds.
    """
    row, column = np.nonzero(candidates)
    d_theta = values[row, column + 1] - values[row, column]
    mid = 0.5 * (values[:, :-1] + values[:, 1:])
    d_alpha = mid[after[row], column] - mid[before[row], column]
    det = d_theta[:, 0] * d_alpha[:, 1] - d_theta[:, 1] * d_alpha[:, 0]
    scale = np.maximum(np.einsum("zc,zc->z", d_theta, d_theta), np.einsum("zc,zc->z", d_alpha, d_alpha))
    folds = np.zeros_like(candidates)
    folds[row, column] = np.abs(det) <= FOLD_SINE * scale
    return folds


def unit_rows(values: np.ndarray) -> np.ndarray:
    """values (..., C) scaled to unit length (zeros stay zero)."""
    size = np.linalg.norm(values, axis=-1, keepdims=True)
    return values / np.maximum(size, np.finfo(float).tiny)


def ring_signs(values: np.ndarray, before: np.ndarray, after: np.ndarray) -> np.ndarray:
    """Signs (R, M) in {-1, +1} making each ring's field continuous along theta.

    values: (R, M, 2) normal coordinates (zeta, rho) in each ring's frame; before/after (R,)
    the rows of the neighbouring rings (for ``_fold_crossings``). Neighbouring normals of a
    smooth field differ by small angles, so a negative dot product between neighbours that
    is confirmed as a fold means the raw field passed through zero and reversed.
    """
    unit = unit_rows(values)
    reversed_ = np.einsum("kmc,kmc->km", unit[:, :-1], unit[:, 1:]) < 0.0
    if np.any(reversed_):
        reversed_ = _fold_crossings(values, reversed_, before, after)
    parity = np.concatenate([np.zeros((len(values), 1), dtype=np.int64), np.cumsum(reversed_, axis=1)], axis=1)
    return 1.0 - 2.0 * (parity % 2)
