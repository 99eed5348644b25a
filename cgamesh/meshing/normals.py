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

from cgamesh.geometry.algebra.stable_rows import rows_times

TRIG_DEGREE = 3
TERMS = 2 * TRIG_DEGREE + 1
SAMPLE_ANGLES = 2.0 * np.pi * np.arange(TERMS) / TERMS
# Below this fraction of the ring's largest velocity, N is treated as zero.
ZERO_FRACTION = 1e-8
# A reversal of (zeta, rho) is a fold when the sine of the angle between its derivatives
# along theta and along t, where it comes closest to zero, is below this (0 on a fold).
FOLD_SINE = 1e-2
# A zero whose derivative along t is below this fraction of its derivative along theta does
# not move with t (``fold_sines``).
STILL_FRACTION = 1e-6


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


# Block size (in float64 values) of per-vertex temporaries: about 1 MB, within a core's L2 cache.
_SCRATCH_VALUES = 1 << 17
_FIT = np.linalg.inv(trig_basis(SAMPLE_ANGLES))  # samples -> coefficients, exact for degree <= 3
# zeta = x' . n is of degree 2 in theta (module docstring). Rounding noise in the sampled
# velocities gives its seven samples a spurious degree-3 part; times e_r (degree 1) that is of
# degree 4, which seven samples alias back onto degree 3, so the fitted N would leave the
# circle's normal plane (span of e_r and n) between the samples where N is small. Projecting
# the samples onto degree <= 2 (zeroing the cos 3t, sin 3t coefficients) keeps N in that plane
# at every angle, and changes nothing when the samples are exact.
_ZETA_DEGREE_2 = trig_basis(SAMPLE_ANGLES) @ np.diag([1.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0]) @ _FIT


def sample_points(centre, radius, u, v) -> tuple[np.ndarray, np.ndarray]:
    """Points (K, 7, 3) at SAMPLE_ANGLES on each ring, and the radial unit vectors there."""
    radial = (np.cos(SAMPLE_ANGLES)[None, :, None] * u[:, None, :]
              + np.sin(SAMPLE_ANGLES)[None, :, None] * v[:, None, :])
    return centre[:, None, :] + radius[:, None, None] * radial, radial


def fit(samples: np.ndarray) -> np.ndarray:
    """Trigonometric coefficients (K, 7, C) of functions sampled at SAMPLE_ANGLES (K, 7, C)."""
    return _FIT @ samples


def frame_coordinates(velocity: np.ndarray, radial: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """(zeta, rho) (K, 7, 2): velocity (K, 7, 3) along the circle's normal and along e_r."""
    zeta = rows_times(np.einsum("ksi,ki->ks", velocity, normal), _ZETA_DEGREE_2.T)
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


def unit_normals(coefficients: np.ndarray, theta: np.ndarray, speed: np.ndarray, near_fraction: float
                 ) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray]]:
    """The normal field of trig coefficients (K, 7, 3) at angles theta (M,), made unit.

    Returns unit (K, M, 3) = N / |N|; smallest (K,), each ring's least |N|; and near, the
    (ring, column) indices where |N| is at most ``near_fraction`` of the ring's speed (K,).
    Where N vanishes (ZERO_FRACTION of the speed) its direction is the limit along the
    circle, N ~ (theta - theta0) dN/dtheta, and |dN/dtheta| counts as its size. The signs
    that make the field continuous are applied later.

    Computed a block of rings at a time, one component after another (numpy's loops over
    contiguous rows are several times faster than over a last axis of 3), in scratch buffers
    that stay within a core's cache: mesh-sized temporaries would cost more in fresh pages
    than the arithmetic. Only the final scaling writes the interleaved (x, y, z) output.
    """
    rings, columns = coefficients.shape[0], len(theta)
    basis = np.ascontiguousarray(trig_basis(theta).T)  # (7, M)
    by_component = np.ascontiguousarray(np.moveaxis(coefficients, -1, 0))  # (3, K, 7)
    unit = np.empty((rings, columns, 3))
    smallest = np.empty(rings)
    near_rings, near_columns = [], []
    block = max(1, min(rings, _SCRATCH_VALUES // (3 * columns)))  # no larger than the rings to fill
    planes, squares, scratch = np.empty((3, block, columns)), np.empty((3, block, columns)), np.empty((block, columns))
    for start in range(0, rings, block):
        stop = min(rings, start + block)
        count = stop - start
        values, lengths = planes[:, :count], scratch[:count]
        for component in range(3):
            if count > 1:
                np.matmul(by_component[component, start:stop], basis, out=values[component])
            else:  # a lone ring summed as in a block of several (stable_rows)
                values[component] = rows_times(by_component[component, start:stop], basis)
        np.sum(np.square(values, out=squares[:, :count]), axis=0, out=lengths)
        np.sqrt(lengths, out=lengths)
        lengths.min(axis=1, out=smallest[start:stop])
        close = np.flatnonzero(smallest[start:stop] <= near_fraction * speed[start:stop])
        if close.size:
            ring, column = np.nonzero(lengths[close] <= near_fraction * speed[start + close, None])
            near_rings.append(start + close[ring])
            near_columns.append(column)
            _limit_at_zeros(values, lengths, close, coefficients[start:stop], theta, speed[start:stop])
            smallest[start:stop] = lengths.min(axis=1)
        # |N| = 0 that survives the limit (N and dN/dtheta both zero: a ring that stands still, a
        # cusp) is among the ``near`` returned; its unit stays zero for the caller to replace.
        np.divide(1.0, lengths, out=lengths, where=lengths > 0.0)
        for component in range(3):
            np.multiply(values[component], lengths, out=unit[start:stop, :, component])
    near = (np.concatenate(near_rings), np.concatenate(near_columns)) if near_rings else (
        np.empty(0, np.intp), np.empty(0, np.intp))
    return unit, smallest, near


def _limit_at_zeros(values, lengths, rows, coefficients, theta, speed) -> None:
    """Where |N| (lengths (R, M)) of the given rows vanishes, N and |N| become dN/dtheta and its size."""
    ring, column = np.nonzero(lengths[rows] <= ZERO_FRACTION * speed[rows, None])
    if ring.size:
        ring = rows[ring]
        limit = np.einsum("za,zac->cz", trig_basis_derivative(theta[column]), coefficients[ring])
        values[:, ring, column] = limit
        lengths[ring, column] = np.linalg.norm(limit, axis=0)


def derivative_bound(coefficients: np.ndarray) -> np.ndarray:
    """(K,) an upper bound of |dN/dtheta| over the whole ring, from coefficients (K, 7, C).

    Harmonic k contributes k (b_k cos k theta - a_k sin k theta), a_k and b_k its cos and sin
    coefficient rows: the matrix [a_k b_k] applied to a unit vector, so its length is at most
    k times that matrix's largest singular value, sqrt of the largest eigenvalue of the Gram
    matrix [[a.a, a.b], [a.b, b.b]], in closed form. The bound is the sum over harmonics (the
    triangle inequality). Against |a_k| + |b_k| it is up to twice as tight: a ring whose field
    just turns (a circle moving across its plane: a_1, b_1 orthogonal, of one length) gets
    exactly |dN/dtheta|, so at 8 around its smallest |N| clears one column step instead of
    flagging every ring (circles.fold_screen). The factor 1 + 1e-9 covers the rounding of the
    closed form.
    """
    bound = np.zeros(coefficients.shape[0])
    for k in range(1, TRIG_DEGREE + 1):
        a, b = coefficients[:, 2 * k - 1, :], coefficients[:, 2 * k, :]
        aa, bb, ab = np.einsum("kc,kc->k", a, a), np.einsum("kc,kc->k", b, b), np.einsum("kc,kc->k", a, b)
        bound += k * np.sqrt(0.5 * (aa + bb + np.sqrt((aa - bb) ** 2 + 4.0 * ab * ab)))
    return bound * (1.0 + 1e-9)


def fold_sines(at: np.ndarray, before: np.ndarray, after: np.ndarray, dt: np.ndarray,
               low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """How far from a fold each reversal of (zeta, rho) along a ring is: the sine (Z,) between
    the field's derivatives along theta and along t where it comes closest to zero.

    at, before, after: (Z, 7, 2) coefficients of the ring with the reversal and of the rings a
    small step dt (Z,) before and after it (carried by the same TRS stepping); low, high (Z,):
    the two columns' angles. Where the surface folds back, (zeta, rho) = lambda d with lambda
    changing sign along a curve, so both derivatives are parallel to d there: the sine is 0.
    A ring passing near an isolated zero (a pinch point, where the field only turns quickly)
    shows the same reversal between two columns, but the Jacobian there is regular.
    """
    fraction = np.linspace(0.0, 1.0, 33)
    angles = low[:, None] + fraction[None, :] * (high - low)[:, None]  # (Z, 33)
    values = np.einsum("zsa,zac->zsc", trig_basis(angles.ravel()).reshape(angles.shape + (TERMS,)), at)
    closest = angles[np.arange(len(angles)), np.argmin(np.einsum("zsc,zsc->zs", values, values), axis=1)]
    for _ in range(4):  # Gauss-Newton on |v(theta)|^2 down to the point nearest zero
        value = np.einsum("za,zac->zc", trig_basis(closest), at)
        slope = np.einsum("za,zac->zc", trig_basis_derivative(closest), at)
        closest = np.clip(closest - np.einsum("zc,zc->z", value, slope)
                          / np.maximum(np.einsum("zc,zc->z", slope, slope), np.finfo(float).tiny), low, high)
    basis = trig_basis(closest)
    along_theta = np.einsum("za,zac->zc", trig_basis_derivative(closest), at)
    along_t = (np.einsum("za,zac->zc", basis, after) - np.einsum("za,zac->zc", basis, before)) / dt[:, None]
    det = along_theta[:, 0] * along_t[:, 1] - along_theta[:, 1] * along_t[:, 0]
    theta_length, t_length = np.linalg.norm(along_theta, axis=1), np.linalg.norm(along_t, axis=1)
    sine = np.abs(det) / np.maximum(theta_length * t_length, np.finfo(float).tiny)
    # Where every circle passes through the same point at the same angle (a characteristic
    # point on a column), the zero does not move with t: the derivative along t is rounding
    # noise of no direction. The field is lambda d with lambda changing sign across the line
    # theta = theta0, a fold of the parametrisation: sine 0.
    return np.where(t_length <= STILL_FRACTION * theta_length, 0.0, sine)


def row_lengths(values: np.ndarray) -> np.ndarray:
    """|values| over the last axis (...,), as np.linalg.norm gives it, bit for bit.

    With two or three columns (normal coordinates, velocities, sample normals) the squares are
    summed column by column, in the order np.linalg.norm sums them
    (tests/test_normals_unit_rows.py): its reduction over a short last axis pays a loop per
    row, two to four times the time.
    """
    columns = values.shape[-1]
    if columns > 3:
        return np.linalg.norm(values, axis=-1)
    total = values[..., 0] * values[..., 0]
    for k in range(1, columns):
        total += values[..., k] * values[..., k]
    return np.sqrt(total, out=total)


def unit_rows(values: np.ndarray) -> np.ndarray:
    """values (..., C) scaled to unit length (zeros stay zero)."""
    return values / np.maximum(row_lengths(values), np.finfo(float).tiny)[..., None]


def reversals(values: np.ndarray) -> np.ndarray:
    """(R, M-1) bool: where the field reverses between columns j and j+1 of each ring.

    values: (R, M, 2) normal coordinates (zeta, rho). Neighbouring normals of a smooth field
    differ by small angles, so a negative dot product means the raw field passed near zero.
    """
    return unit_reversals(unit_rows(values))


def unit_reversals(unit: np.ndarray) -> np.ndarray:
    """``reversals`` of values already scaled by ``unit_rows`` (a caller that needs both)."""
    return np.einsum("kmc,kmc->km", unit[:, :-1], unit[:, 1:]) < 0.0


def ring_signs(folds: np.ndarray) -> np.ndarray:
    """Signs (R, M) in {-1, +1} that flip after every fold crossing (R, M-1) along each ring."""
    parity = np.concatenate([np.zeros((len(folds), 1), dtype=np.int64), np.cumsum(folds, axis=1)], axis=1)
    return 1.0 - 2.0 * (parity % 2)
