"""Real roots in [-1, 1] of batches of polynomials given by their values at Chebyshev points.

A polynomial of degree n is fixed by its values at the n + 1 Chebyshev points of the first
kind u_m = cos(pi (m + 1/2) / (n + 1)); a fixed matrix turns the values into the
coefficients of the Chebyshev series sum_k c_k T_k(u), and the roots are the eigenvalues of
the colleague matrix (the companion matrix of the Chebyshev basis), computed for a whole
batch by one ``np.linalg.eigvals`` on stacked matrices. In the Chebyshev basis the roots
inside [-1, 1] are well conditioned, unlike the monomial basis at degree 36.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

# Leading coefficients below this fraction of a row's largest are negligible (trimmed when
# every row agrees, else raised to it: the roots in [-1, 1] move by about this much).
LEADING_RTOL = 1e-13
# Eigenvalues further than this from the real axis are complex roots (nearer: a cluster of real
# roots split by rounding, whose real parts callers refine).
IMAGINARY_TOL = 1e-2
# Real parts this far outside [-1, 1] are still returned (a root at an end, moved by rounding).
EDGE_SLACK = 1e-6


@lru_cache(maxsize=None)
def nodes(degree: int) -> np.ndarray:
    """The degree + 1 Chebyshev points of the first kind, (degree + 1,), decreasing."""
    m = np.arange(degree + 1)
    return np.cos(np.pi * (m + 0.5) / (degree + 1))


@lru_cache(maxsize=None)
def fit_matrix(degree: int) -> np.ndarray:
    """(n + 1, n + 1) matrix F with coefficients = values @ F.T for values at ``nodes(n)``."""
    count = degree + 1
    k = np.arange(count)[:, None]
    m = np.arange(count)[None, :]
    matrix = (2.0 / count) * np.cos(np.pi * k * (m + 0.5) / count)
    matrix[0] *= 0.5
    return matrix


@lru_cache(maxsize=None)
def _colleague_base(degree: int) -> tuple[np.ndarray, np.ndarray]:
    """The constant part (n, n) of the scaled colleague matrix and its last-column scale (n,)."""
    base = np.zeros((degree, degree))
    off = np.full(degree - 1, 0.5)
    if degree > 1:
        off[0] = np.sqrt(0.5)
        base[np.arange(degree - 1), np.arange(1, degree)] = off
        base[np.arange(1, degree), np.arange(degree - 1)] = off
    scale = np.array([1.0] + [np.sqrt(0.5)] * (degree - 1))
    return base, 0.5 * scale / scale[-1]


def coefficients(values: np.ndarray) -> np.ndarray:
    """Chebyshev coefficients (N, n + 1) of polynomials given by values (N, n + 1) at ``nodes(n)``."""
    return values @ fit_matrix(values.shape[1] - 1).T


def roots(coefs: np.ndarray) -> np.ndarray:
    """Real roots in [-1, 1] (N, n) of Chebyshev series (N, n + 1); NaN marks no root.

    Coefficients whose size is negligible in every row are dropped; a row whose leading
    coefficient is still negligible has it raised to LEADING_RTOL of its largest (a root at
    infinity moves in from infinity, the roots in [-1, 1] barely move). Rows that vanish
    identically have no roots. Near-real eigenvalues (|Im| <= IMAGINARY_TOL: a double root
    split by rounding) are kept with their real part; callers polish and check them.
    """
    coefs = np.asarray(coefs, dtype=np.float64)
    count = coefs.shape[0]
    size = np.abs(coefs).max(axis=1)
    negligible = np.abs(coefs) <= LEADING_RTOL * size[:, None]
    degree = coefs.shape[1] - 1
    while degree > 0 and np.all(negligible[:, degree]):
        degree -= 1
    if degree == 0 or count == 0:
        return np.full((count, max(degree, 1)), np.nan)
    coefs = coefs[:, : degree + 1].copy()
    lead = coefs[:, degree]
    floor = LEADING_RTOL * size
    coefs[:, degree] = np.where(np.abs(lead) < floor, np.where(lead < 0.0, -floor, floor), lead)
    if degree == 1:
        eig = (-coefs[:, 0] / coefs[:, 1])[:, None].astype(complex)
    else:
        base, scale = _colleague_base(degree)
        matrices = np.broadcast_to(base, (count, degree, degree)).copy()
        with np.errstate(divide="ignore", invalid="ignore"):
            matrices[:, :, -1] -= coefs[:, :-1] / coefs[:, -1:] * scale
        dead = ~(size > 0.0)
        matrices[dead] = 0.0
        eig = np.linalg.eigvals(matrices)
        eig[dead] = np.nan
    real = eig.real
    keep = (np.abs(eig.imag) <= IMAGINARY_TOL) & (np.abs(real) <= 1.0 + EDGE_SLACK)
    return np.where(keep, np.clip(real, -1.0, 1.0), np.nan)


def evaluate(coefs: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Values and derivatives (R,) of Chebyshev series (R, n + 1) at points u (R,).

    By the recurrences T_{k+1} = 2u T_k - T_{k-1}, U_{k+1} = 2u U_k - U_{k-1}, with
    d T_k / du = k U_{k-1}.
    """
    degree = coefs.shape[1] - 1
    t_prev, t_cur = np.ones_like(u), u.copy()
    u_prev, u_cur = np.zeros_like(u), np.ones_like(u)  # U_{-1}, U_0
    value = coefs[:, 0] + (coefs[:, 1] * u if degree >= 1 else 0.0)
    derivative = coefs[:, 1] * u_cur if degree >= 1 else np.zeros_like(u)
    for k in range(2, degree + 1):
        t_prev, t_cur = t_cur, 2.0 * u * t_cur - t_prev
        u_prev, u_cur = u_cur, 2.0 * u * u_cur - u_prev
        value = value + coefs[:, k] * t_cur
        derivative = derivative + k * coefs[:, k] * u_cur
    return value, derivative


def polish(coefs: np.ndarray, u: np.ndarray, steps: int = 2) -> np.ndarray:
    """Newton steps on the series (R, n + 1) from roots u (R,), kept inside [-1, 1]."""
    for _ in range(steps):
        value, derivative = evaluate(coefs, u)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = np.where(derivative != 0.0, value / derivative, 0.0)
        u = np.clip(u - np.clip(np.nan_to_num(step), -1e-3, 1e-3), -1.0, 1.0)
    return u


def shifted_nodes(degree: int, shift: float) -> tuple[np.ndarray, np.ndarray]:
    """degree + 1 points cos(pi (m + 1/2 + shift) / (degree + 1)) and the matrix F turning values
    there into Chebyshev coefficients (coefficients = values @ F.T); shift 0 gives ``nodes``."""
    if shift == 0.0:
        return nodes(degree), fit_matrix(degree)
    m = np.arange(degree + 1)
    points = np.cos(np.pi * (m + 0.5 + shift) / (degree + 1))
    basis = np.cos(np.arange(degree + 1)[None, :] * np.arccos(points)[:, None])  # T_k(points), (M, k)
    return points, np.linalg.inv(basis)
