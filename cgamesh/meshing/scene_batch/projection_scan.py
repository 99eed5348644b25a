"""The projection scan of many blade-circle surfaces, from products of their controls alone.

``EvolvedSurface.check_projection_exists`` samples a surface 128 times a segment (several
times its rings) and, at every sample, projects the interpolant X' = sum_a w_a C_a: it forms
Sigma = -X' ~X' (margin) and the projected blade S X', whose carrier part m must not flip
between samples (geometry/flatness.py). The scan only decides (the mesh uses none of its
numbers), so here it is taken from the controls' pairwise products instead of per sample:

    Sigma(t) = -sum_ab w_a w_b <C_a ~C_b>_{0,4}          (s and the 4-vector F),
    m(t) ~ g carrier(X') - carrier(<F X'>_3)              (S X' times sqrt(2 g) beta > 0),

with carrier(X') = sum_a w_a carrier(C_a) and carrier(<F X'>_3) = sum_i F_i sum_a w_a
carrier(<E_i C_a>_3) over the five 4-blades E_i: small tables per surface, then a few
multiply-adds per sample. The sums are in another order than the per-surface scan's, so a
surface is passed only when its decision is sure by a wide margin: every margin at least
SURE_MARGIN (a hundred times MIN_MARGIN; the rounding of beta there is below 1e-9), every pair
of consecutive m clearly less than a quarter turn apart (their dot product above an error
bound of each). Anything closer is left to the per-surface scan, which decides it exactly.
"""

from __future__ import annotations

import numpy as np

from cgamesh.geometry.algebra import products
from cgamesh.geometry.algebra.layout import BLADE_COUNT, grade_indices
from cgamesh.geometry import flatness
from cgamesh.geometry.flatness import carrier_part
from cgamesh.geometry.projection import margin, project_blades
from cgamesh.geometry.surface import MIN_MARGIN, SCAN_SAMPLES_PER_SEGMENT

SURE_MARGIN = 100.0 * MIN_MARGIN
# Relative error allowed for each m, of the size of its terms (float64 rounding of a few
# dozen terms is below 1e-14).
M_ERROR = 1e-12
_CIRCLE = (3,)
_FOURS = grade_indices(4)
_SIGMA = np.concatenate([[0], _FOURS])  # the blades of Sigma: scalar, then the 4-vector
# F^2 = sum_i eta_i F_i^2 (basis 4-blades are orthogonal): eta_i = E_i^2
_ETA = np.array([products.geometric(np.eye(BLADE_COUNT)[i], np.eye(BLADE_COUNT)[i], (4,), (4,), (0,))[0]
                 for i in _FOURS])
# Samples (surfaces times scan samples) per pass.
PASS_SAMPLES = 65536


def scan_parameters(curve, t: np.ndarray) -> np.ndarray:
    """The parameters check_projection_exists(sampled=t) scans: t itself where it is fine enough."""
    if len(t) > 1 and np.max(np.diff(t)) <= 1.0 / SCAN_SAMPLES_PER_SEGMENT:
        return t
    segments = curve.segment_count
    return np.linspace(0.0, segments, SCAN_SAMPLES_PER_SEGMENT * segments + 1)


def surely_projectable(curve, t: np.ndarray, controls: np.ndarray, grade: int = 3) -> np.ndarray:
    """(S,) bool: the scan of each surface (controls (S, n, 32)) surely finds no margin below
    MIN_MARGIN and no flip of m, so check_projection_exists(sampled=t) passes without refining.
    ``grade``: 3 for circles, 2 for point pairs (the same algebra: S X' = (g X' - <F X'>) /
    (sqrt(2 g) beta) for a blade of either grade)."""
    blade = (grade,)
    count, n, _ = controls.shape
    scan = scan_parameters(curve, t)
    basis = curve.basis(scan)
    index, weights = basis.indices, basis.weights  # (A, k)
    size = basis.weight_sum()
    flat = controls.reshape(-1, BLADE_COUNT)
    left = np.repeat(controls, n, axis=1).reshape(-1, BLADE_COUNT)
    right = np.tile(products.reverse(controls), (1, n, 1)).reshape(-1, BLADE_COUNT)
    pairs = products.geometric(left, right, blade, blade, (0, 4))[:, _SIGMA].reshape(count, n, n, 6)
    carriers = carrier_part(flat, grade).reshape(count, n, 3)
    fours = np.zeros((5, BLADE_COUNT))
    fours[np.arange(5), _FOURS] = 1.0
    turned = products.geometric(np.repeat(fours[None], len(flat), axis=0).reshape(-1, BLADE_COUNT),
                                np.repeat(flat, 5, axis=0), (4,), blade, blade)
    turned = carrier_part(turned, grade).reshape(count, n, 5, 3)
    # Samples sharing their controls (a segment of a spline, all of a Bezier curve) take their sums
    # as one matrix product: weights (A', k) or their pairwise products (A', k k) times the tables.
    patterns, which = np.unique(index, axis=0, return_inverse=True)
    ok = np.empty(count, dtype=bool)
    per_pass = max(1, PASS_SAMPLES // len(scan))
    k = index.shape[1]
    for start in range(0, count, per_pass):
        stop = min(count, start + per_pass)
        part = stop - start
        sigma = np.empty((len(scan), part, 6))
        plain = np.empty((len(scan), part, 3))
        mixed = np.empty((len(scan), part, 5, 3))
        for p, pattern in enumerate(patterns):
            rows = np.flatnonzero(which.ravel() == p)
            w = weights[rows]
            both = (w[:, :, None] * w[:, None, :]).reshape(len(rows), k * k)
            table = pairs[start:stop][:, pattern[:, None], pattern[None, :]]  # (S, k, k, 6)
            sigma[rows] = -(both @ np.moveaxis(table, 0, 2).reshape(k * k, part * 6)).reshape(len(rows), part, 6)
            plain[rows] = (w @ np.moveaxis(carriers[start:stop][:, pattern], 0, 1).reshape(k, part * 3)
                           ).reshape(len(rows), part, 3)
            mixed[rows] = (w @ np.moveaxis(turned[start:stop][:, pattern], 0, 1).reshape(k, part * 15)
                           ).reshape(len(rows), part, 5, 3)
        sigma, plain, mixed = (np.moveaxis(x, 0, 1) for x in (sigma, plain, mixed))
        s, four = sigma[..., 0], sigma[..., 1:]
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            beta = np.sqrt(s * s - four**2 @ _ETA)
            g = s + beta
            margin = np.minimum(beta, g) / np.square(size)
        sure = np.all(margin >= SURE_MARGIN, axis=1)
        first = g[..., None] * plain
        second = np.einsum("sai,saic->sac", four, mixed)
        m = first - second
        error = M_ERROR * (np.linalg.norm(first, axis=-1) + np.linalg.norm(second, axis=-1))
        length = np.linalg.norm(m, axis=-1)
        signed = np.einsum("sac,sac->sa", m[:, :-1], m[:, 1:])
        bound = length[:, :-1] * error[:, 1:] + length[:, 1:] * error[:, :-1] + error[:, :-1] * error[:, 1:]
        ok[start:stop] = sure & np.all(signed > bound, axis=1)
    return ok


def exactly_projectable(curve, t: np.ndarray, controls: np.ndarray, grade: int = 3) -> np.ndarray:
    """(S,) bool: check_projection_exists(sampled=t) passes, decided as it decides, bit for bit,
    for surfaces the quick scan could not vouch for (``surely_projectable`` False): the margins
    and projected blades at every scan sample, and each flip of the carrier between samples
    refined (flatness.find_line's search, every flip of every surface at once) to whether the
    object there reaches past LINE_REACH (a line: the per-surface path refuses the surface).
    ``grade``: 3 for circles, 2 for point pairs (a flat point in place of a line); controls
    whose interpolants are four-vector free (``project_scalar``) are not for this scan."""
    count, n, _ = controls.shape
    scan = scan_parameters(curve, t)
    samples = len(scan)
    basis = curve.basis(scan)
    flat = controls.reshape(-1, BLADE_COUNT)
    picked = flat[(basis.indices[None] + (np.arange(count) * n)[:, None, None]).reshape(count * samples, -1)]
    weights = np.broadcast_to(basis.weights, (count,) + basis.weights.shape).reshape(count * samples, -1)
    values = np.einsum("ak,akm->am", weights, picked)
    margins = margin(values, grade, np.tile(basis.weight_sum(), count)).reshape(count, samples)
    ok = np.all(margins >= MIN_MARGIN, axis=1)
    with np.errstate(invalid="ignore", over="ignore"):  # NaN blades of surfaces whose margins failed
        m = carrier_part(project_blades(values, grade), grade).reshape(count, samples, 3)
    lows, highs, owners = [], [], []
    for s in np.flatnonzero(ok):  # each surface's own (A - 1, 3) sums, as find_line takes them
        flips = np.flatnonzero(~(np.einsum("ac,ac->a", m[s, :-1], m[s, 1:]) > 0.0))
        lows.append(scan[flips])
        highs.append(scan[flips + 1])
        owners.append(np.full(len(flips), s))
    if not lows or sum(len(low) for low in lows) == 0:
        return ok
    lo, hi, owner = np.concatenate(lows), np.concatenate(highs), np.concatenate(owners)

    def norms_at(grid):
        at = grid.ravel()
        where = curve.basis(at)
        chosen = np.repeat(owner, grid.shape[1])
        rows = flat[where.indices + (chosen * n)[:, None]]
        with np.errstate(invalid="ignore", over="ignore"):
            blades = project_blades(np.einsum("ak,akm->am", where.weights, rows), grade)
            return np.linalg.norm(carrier_part(blades, grade), axis=-1).reshape(grid.shape)

    best_norm = np.full(len(lo), np.inf)
    rows = np.arange(len(lo))
    for _ in range(flatness._REFINE_ROUNDS):  # flatness.find_line's search, step for step
        grid = lo[:, None] + (hi - lo)[:, None] * np.linspace(0.0, 1.0, flatness._REFINE_SAMPLES)
        norms = norms_at(grid)
        norms = np.where(np.isfinite(norms), norms, np.inf)
        k = np.argmin(norms, axis=1)
        better = norms[rows, k] < best_norm
        best_norm[better] = norms[rows, k][better]
        step = (hi - lo) / (flatness._REFINE_SAMPLES - 1)
        lo, hi = np.maximum(lo, grid[rows, k] - step), np.minimum(hi, grid[rows, k] + step)
    line = flatness.reach(best_norm[:, None] * np.array([1.0, 0.0, 0.0]), grade) > flatness.LINE_REACH
    ok[owner[line]] = False
    return ok
