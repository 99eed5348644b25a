"""The sampled root finder of section 5.1.1, on values sampled at fixed parameters.

Given f (N, K) at parameters p (K,) for N rays (f = (C v L)^2 for circles, L v P for point
pairs), the paper's algorithm records where f changes sign between neighbouring samples and
solves a quadratic through three samples around each change. A ray that only touches the
surface (a grazing double root) makes f touch zero without changing sign, which this misses;
so local extrema of |f| between samples of one sign are also fitted with the quadratic
through them, and where that parabola crosses zero its two roots are reported too.

``dip_pairs`` serves a caller that polishes every root on the true function and keeps it by
its residual (motor surfaces). There a dip is the place of two roots (or a double root) closer
together than the samples, and the parabola through three samples finds them only roughly:
f's cubic term over a step of 1/64 of a segment is enough to lift the parabola's extremum off
zero, or to put both its roots on the same side of the true pair. A ray along a tube's normal
(``verify`` casts one through every vertex) lies nearly in that ring's plane and meets the
tube twice within a small fraction of a step, once at the vertex and once across the ring, so
every vertex is such a pair. The dip is therefore reported as a pair of starting points (the
parabola's two roots, or its extremum twice where it does not cross zero) for the caller to
converge on both roots.
"""

from __future__ import annotations

import numpy as np


def _quadratic(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(a, b, c) of q(h) = a h^2 + b h + c through three points (M, 3) with h = x - x[:, 1]."""
    h0, h2 = x[:, 0] - x[:, 1], x[:, 2] - x[:, 1]
    d0, d2 = y[:, 0] - y[:, 1], y[:, 2] - y[:, 1]
    det = h0 * h2 * (h0 - h2)
    a = (d0 * h2 - d2 * h0) / det
    b = (d2 * h0 * h0 - d0 * h2 * h2) / det
    return a, b, y[:, 1]


def _quadratic_roots(a, b, c) -> tuple[np.ndarray, np.ndarray]:
    """Both real roots of a h^2 + b h + c (NaN where complex); the linear root when a is ~0."""
    disc = b * b - 4.0 * a * c
    with np.errstate(divide="ignore", invalid="ignore"):
        root = np.sqrt(disc)
        q = -0.5 * (b + np.where(b >= 0.0, root, -root))
        r1 = q / a
        r2 = c / q
        linear = np.abs(a) * 1e12 <= np.abs(b)
        r1 = np.where(linear, -c / b, r1)
        r2 = np.where(linear, np.nan, r2)
    return r1, r2


def _dips(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(row, k) of every interior local minimum of |f| at sample k + 1 between samples of its sign."""
    left, mid, right = values[:, :-2], values[:, 1:-1], values[:, 2:]
    same = (left * mid > 0.0) & (mid * right > 0.0)
    return np.nonzero(same & (np.abs(mid) <= np.abs(left)) & (np.abs(mid) < np.abs(right)))


def dip_pairs(values: np.ndarray, params: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Starting points of the root pairs at the dips of sampled functions: (row (D,), first (D,),
    second (D,)) for values (N, K) at params (K,).

    At every interior local minimum of |f| between samples of one sign, and at a first or last
    sample where |f| is least (the three samples there of one sign), the parabola q through
    the three samples gives its two roots where it crosses zero, else its extremum twice (a
    pair that q only nearly touches: f may still cross, or touch, zero there), each clipped to
    the three samples' range. The caller polishes both and keeps what the residual accepts (a
    near miss of the ray then costs two rejected candidates).
    """
    count = values.shape[1]
    if count < 3:
        return np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0)
    row, k = _dips(values)
    # |f| least at a first or last sample: the pair may lie between it and its neighbour, inside
    # this segment (the dip continues past the segment's end, where these samples stop)
    start = np.flatnonzero((values[:, 0] * values[:, 1] > 0.0) & (values[:, 1] * values[:, 2] > 0.0)
                           & (np.abs(values[:, 0]) < np.abs(values[:, 1])))
    end = np.flatnonzero((values[:, -1] * values[:, -2] > 0.0) & (values[:, -2] * values[:, -3] > 0.0)
                         & (np.abs(values[:, -1]) < np.abs(values[:, -2])))
    row = np.concatenate([row, start, end])
    k = np.concatenate([k, np.zeros(start.size, dtype=k.dtype), np.full(end.size, count - 3, dtype=k.dtype)])
    cols = k[:, None] + np.arange(3)
    x, y = params[cols], values[row[:, None], cols]
    a, b, c = _quadratic(x, y)
    r1, r2 = _quadratic_roots(a, b, c)
    with np.errstate(divide="ignore", invalid="ignore"):
        vertex = np.where(a != 0.0, -b / (2.0 * a), 0.0)
    real = np.isfinite(r1) & np.isfinite(r2)
    lo, hi = x[:, 0] - x[:, 1], x[:, 2] - x[:, 1]
    first = np.clip(np.where(real, r1, vertex), lo, hi)
    second = np.clip(np.where(real, r2, vertex), lo, hi)
    return row, x[:, 1] + first, x[:, 1] + second


def sign_change_roots(values: np.ndarray, params: np.ndarray,
                      grazing: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Roots of sampled functions: (row index (R,), parameter (R,)) for values (N, K) at params (K,).

    Each sign change between samples k and k+1 gives one root, from the quadratic through
    samples k-1..k+1 or k..k+2; a sample that is exactly zero is a root itself. With
    ``grazing``, each interior local minimum of |f| whose quadratic dips through zero gives
    its two roots within the three samples.
    """
    count = values.shape[1]
    rows_out, params_out = [], []
    zero_row, zero_col = np.nonzero(values == 0.0)
    rows_out.append(zero_row)
    params_out.append(params[zero_col])

    row, k = np.nonzero(values[:, :-1] * values[:, 1:] < 0.0)
    if row.size and count >= 3:
        start = np.clip(k - 1, 0, count - 3)
        # Prefer the triple whose third sample lies on the side of the smaller |f|.
        forward = (k + 2 < count) & ((k == 0) | (np.abs(values[row, np.minimum(k + 2, count - 1)])
                                                  <= np.abs(values[row, np.maximum(k - 1, 0)])))
        start = np.where(forward, np.minimum(k, count - 3), start)
        cols = start[:, None] + np.arange(3)
        x, y = params[cols], values[row[:, None], cols]
        a, b, c = _quadratic(x, y)
        r1, r2 = _quadratic_roots(a, b, c)
        lo, hi = params[k] - x[:, 1], params[k + 1] - x[:, 1]
        pick = np.where((r1 >= lo) & (r1 <= hi), r1, np.where((r2 >= lo) & (r2 <= hi), r2, np.nan))
        # Rounding can push the root just outside its interval: fall back to the secant.
        secant = lo + (hi - lo) * values[row, k] / (values[row, k] - values[row, k + 1])
        rows_out.append(row)
        params_out.append(x[:, 1] + np.where(np.isnan(pick), secant, pick))
    elif row.size:
        rows_out.append(row)
        params_out.append(params[k] + (params[k + 1] - params[k]) * values[row, k] / (values[row, k] - values[row, k + 1]))

    if grazing and count >= 3:
        row, k = _dips(values)
        if row.size:
            cols = k[:, None] + np.arange(3)
            x, y = params[cols], values[row[:, None], cols]
            a, b, c = _quadratic(x, y)
            r1, r2 = _quadratic_roots(a, b, c)
            lo, hi = x[:, 0] - x[:, 1], x[:, 2] - x[:, 1]
            for r in (r1, r2):
                ok = (r >= lo) & (r <= hi)
                rows_out.append(row[ok])
                params_out.append(x[ok, 1] + r[ok])
    return np.concatenate(rows_out).astype(np.int64), np.concatenate(params_out)
