"""Analytic vertex normals of evolved circle surfaces (paper section 5.2, eqs. 17-25).

At a point x = c + r e_r(theta) of the circle C(t), the surface is spanned by the circle's
tangent t(theta) = n x e_r (the line L_C of eq. 17) and the velocity x' of the point carried
by the evolution, X' = X . (C dC/dt) (eqs. 19-20; the line L_T of eq. 22). Their cross
product is the normal line of eq. 25. Writing x' = rho e_r + tau t + zeta n,

    t x x' = zeta e_r - rho n,

so the normal has coordinates (zeta, rho) in the circle's own (e_r, -n) frame. Because the
velocity field of a conformal motion is quadratic in x, zeta is a trigonometric polynomial
of degree 2 in theta and rho of degree 3: seven samples per ring determine both exactly,
and every vertex then costs one small matrix product instead of conformal algebra.

Continuity. (zeta, rho) passes through zero where the parametrisation folds (the circles
cross their neighbours, or share a point): there the raw normal reverses. The normal field
is kept continuous by flipping its sign across such crossings (``continuous_signs``), and
exactly at a zero the direction is the limit along the circle, (zeta', rho').
"""

from __future__ import annotations

import numpy as np

TRIG_DEGREE = 3
SAMPLE_ANGLES = 2.0 * np.pi * np.arange(2 * TRIG_DEGREE + 1) / (2 * TRIG_DEGREE + 1)
# Below this fraction of the ring's largest velocity, (zeta, rho) is treated as zero.
ZERO_FRACTION = 1e-8
# A reversal of (zeta, rho) is a fold when the sine of the angle between its derivatives
# along theta and along t is below this (exactly 0 on a fold, order 1 at a pinch point).
FOLD_SINE = 0.25


def trig_basis(theta: np.ndarray) -> np.ndarray:
    """[1, cos t, sin t, cos 2t, sin 2t, cos 3t, sin 3t] at angles theta (M,) -> (M, 7)."""
    theta = np.asarray(theta, dtype=np.float64)[:, None]
    m = np.arange(1, TRIG_DEGREE + 1)
    columns = np.empty((theta.shape[0], 2 * TRIG_DEGREE + 1))
    columns[:, 0] = 1.0
    columns[:, 1::2] = np.cos(m * theta)
    columns[:, 2::2] = np.sin(m * theta)
    return columns


def trig_basis_derivative(theta: np.ndarray) -> np.ndarray:
    """d/dtheta of ``trig_basis`` (M, 7)."""
    theta = np.asarray(theta, dtype=np.float64)[:, None]
    m = np.arange(1, TRIG_DEGREE + 1)
    columns = np.zeros((theta.shape[0], 2 * TRIG_DEGREE + 1))
    columns[:, 1::2] = -m * np.sin(m * theta)
    columns[:, 2::2] = m * np.cos(m * theta)
    return columns


_FIT = np.linalg.inv(trig_basis(SAMPLE_ANGLES))  # samples -> coefficients, exact for degree <= 3


def sample_points(centre, radius, u, v) -> tuple[np.ndarray, np.ndarray]:
    """Points (K, 7, 3) at SAMPLE_ANGLES on each ring, and the radial unit vectors there."""
    radial = np.cos(SAMPLE_ANGLES)[None, :, None] * u[:, None, :] + np.sin(SAMPLE_ANGLES)[None, :, None] * v[:, None, :]
    return centre[:, None, :] + radius[:, None, None] * radial, radial


def normal_coefficients(velocity: np.ndarray, radial: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Trigonometric coefficients (K, 7, 2) of (zeta, rho) from velocities at SAMPLE_ANGLES.

    velocity, radial: (K, 7, 3); normal: (K, 3).
    """
    zeta = np.einsum("ksi,ki->ks", velocity, normal)
    rho = np.einsum("ksi,ksi->ks", velocity, radial)
    return np.einsum("as,ksc->kac", _FIT, np.stack([zeta, rho], axis=-1))


def evaluate(coefficients: np.ndarray, theta: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """(zeta, rho) (K, M, 2) at angles theta (M,), zeros replaced by their limit along the circle.

    scale: (K,) the ring's velocity size; |(zeta, rho)| below ZERO_FRACTION * scale counts as
    a zero of the field, where the direction of d/dtheta (zeta, rho) is used instead (sign
    continuity is restored afterwards by ``continuous_signs``).
    """
    values = np.matmul(trig_basis(theta)[None], coefficients)
    size = np.hypot(values[..., 0], values[..., 1])
    zero = size <= ZERO_FRACTION * scale[:, None]
    if np.any(zero):
        ring, column = np.nonzero(zero)
        slope = np.einsum("za,zac->zc", trig_basis_derivative(theta[column]), coefficients[ring])
        values[ring, column] = slope
    return values


def _fold_crossings(values: np.ndarray, candidates: np.ndarray) -> np.ndarray:
    """Which sign reversals between columns j and j+1 of a ring cross a fold (K, M-1) bool.

    Where the surface folds back (circles crossing their neighbours along an envelope, or
    all sharing a point), (zeta, rho) = lambda d with lambda changing sign along a curve:
    its derivatives across and along the rings are both parallel to d, so the Jacobian of
    (zeta, rho) over (t, theta) is singular there. A ring passing close by an isolated zero
    (a pinch point of the surface, where the field only turns quickly) shows the same
    reversal between two samples, but there the Jacobian is regular and the raw field is
    the continuous one: such reversals are not folds.
    """
    ring, column = np.nonzero(candidates)
    d_theta = values[ring, column + 1] - values[ring, column]
    mid = 0.5 * (values[:, :-1] + values[:, 1:])
    before = np.maximum(ring - 1, 0)
    after = np.minimum(ring + 1, len(values) - 1)
    d_alpha = mid[after, column] - mid[before, column]
    det = d_theta[:, 0] * d_alpha[:, 1] - d_theta[:, 1] * d_alpha[:, 0]
    scale = np.maximum(np.einsum("zc,zc->z", d_theta, d_theta), np.einsum("zc,zc->z", d_alpha, d_alpha))
    folds = np.zeros_like(candidates)
    folds[ring, column] = np.abs(det) <= FOLD_SINE * scale
    return folds


def continuous_signs(values: np.ndarray) -> np.ndarray:
    """Signs (K, M) in {-1, +1} that make the normal field continuous over the (t, theta) grid.

    values: (K, M, 2) normal coordinates (zeta, rho) in each ring's frame. Neighbouring
    normals of a smooth field differ by small angles, so a negative dot product between
    neighbours that ``_fold_crossings`` confirms as a fold means the raw field passed through
    zero and reversed. Within a ring the reversals are counted along theta; between rings
    the whole ring is flipped when most of its columns disagree with the previous ring's.
    """
    unit = values / np.maximum(np.hypot(values[..., 0], values[..., 1]), np.finfo(float).tiny)[..., None]
    reversed_ = np.einsum("kmc,kmc->km", unit[:, :-1], unit[:, 1:]) < 0.0
    if np.any(reversed_):
        reversed_ = _fold_crossings(values, reversed_)
    parity = np.concatenate([np.zeros((len(values), 1), dtype=np.int64), np.cumsum(reversed_, axis=1)], axis=1)
    signs = 1.0 - 2.0 * (parity % 2)
    signed = unit * signs[..., None]
    agreement = np.einsum("kmc,kmc->k", signed[:-1], signed[1:])
    ring_parity = np.concatenate([[0], np.cumsum(agreement < 0.0)]) % 2
    return signs * (1.0 - 2.0 * ring_parity)[:, None]
