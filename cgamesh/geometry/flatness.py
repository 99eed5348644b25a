"""Where an interpolated object turns into a line (circles) or a flat point (point pairs).

Blade interpolation between controls of opposite orientation (``align: false``) can pass
through a circle through infinity, the line C with C ^ n_inf = 0, and a point pair through
a flat point x ^ n_inf (one end point at infinity), with P . n_inf = 0. The projection
exists there (its margin stays large), so the surface is unbounded without any other check
noticing.

The measure is the carrier's Euclidean part m(t): for a circle normalised to C^2 = 1 the
dual of its plane C ^ n_inf is m + d n_inf, so (C ^ n_inf)^2 = -|m|^2 and m is the unit
normal over the radius; for a point pair, P . n_inf = (b - a) / (|b - a|^2 / 2) + ...
n_inf. (C ^ n_inf)^2 itself is sign-definite and only touches 0 (quadratically) at a line,
so the crossing is read on m, which passes through 0 linearly and changes sign: the signed
flatness m(t) . m(t_k) turns negative between consecutive scan samples. The normal may also
flip that fast without a line (an interpolant passing near one), so each flip is refined to
the closest approach of m to 0 in its interval, and refused when the object there reaches
past ``LINE_REACH`` times the surface's bounding radius (the working frame's unit) or m
vanishes to rounding.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from cgamesh.geometry.algebra import products
from cgamesh.geometry.algebra.conformal import EUCLIDEAN, N_INF

# An interpolated circle's radius (a point pair's length) past this many bounding radii of the
# surface, where its orientation flips, is taken for a line (a flat point): the surface runs off
# towards infinity there. Controls lie in the unit ball of the working frame.
LINE_REACH = 1e3
# Past this reach (bounding radii) the closest approach is a line to rounding: m vanished to float64's
# epsilon of its size at the controls (about 1).
UNBOUNDED_REACH = 1e12
# Refinement of a flip: samples per round, and rounds (each shrinks the interval 8-fold).
_REFINE_SAMPLES = 17
_REFINE_ROUNDS = 14


def _carrier_map(grade: int) -> np.ndarray:
    """The (32, 3) matrix of the linear map X -> m of ``carrier_part``, from the basis blades."""
    basis = np.eye(32)
    if grade == 3:
        return -products.dual(products.outer(basis, N_INF, (3,), (1,)))[:, EUCLIDEAN]
    return products.inner(basis, N_INF, (2,), (1,))[:, EUCLIDEAN]


_CARRIER_MAPS = {3: _carrier_map(3), 2: _carrier_map(2)}


def carrier_part(blades: np.ndarray, grade: int) -> np.ndarray:
    """m (..., 3): for circles (grade 3) the normal over the radius, the Euclidean part of the dual
    of C ^ n_inf; for point pairs (grade 2) the Euclidean part of P . n_inf, (b - a) over half the
    squared length. Zero for a line or a flat point; blades normalised to square to 1. Linear in
    the blade: one matrix product."""
    return blades @ _CARRIER_MAPS[grade]


def reach(m: np.ndarray, grade: int) -> np.ndarray:
    """How far the object of carrier part m (..., 3) reaches: radius 1/|m|, or length 2/|m|."""
    with np.errstate(divide="ignore"):
        return (1.0 if grade == 3 else 2.0) / np.linalg.norm(m, axis=-1)


def find_line(t: np.ndarray, blades: np.ndarray, grade: int,
              blades_at: Callable[[np.ndarray], np.ndarray]) -> tuple[float, float, float, float] | None:
    """The first place where the interpolated object turns into a line (a flat point), or None.

    t (A,): increasing scan parameters; blades (A, 32): the projected objects there;
    blades_at(t): the projected objects at other parameters (for the refinement). Returns
    (t_before, t_after, t_line, reach) for the scan interval of the first crossing, the
    parameter of the closest approach in it and the object's reach there (inf on a line).
    """
    m = carrier_part(blades, grade)
    signed = np.einsum("ac,ac->a", m[:-1], m[1:])
    flips = np.flatnonzero(~(signed > 0.0))  # a sign change, or m = 0 (NaN included) on a sample
    if flips.size == 0:
        return None
    lo, hi = t[flips].copy(), t[flips + 1].copy()
    best_t, best_norm = lo.copy(), np.full(len(lo), np.inf)
    for _ in range(_REFINE_ROUNDS):
        grid = lo[:, None] + (hi - lo)[:, None] * np.linspace(0.0, 1.0, _REFINE_SAMPLES)
        with np.errstate(invalid="ignore", over="ignore"):  # NaN blades where no projection exists
            norms = np.linalg.norm(carrier_part(blades_at(grid.ravel()), grade), axis=-1).reshape(grid.shape)
        norms = np.where(np.isfinite(norms), norms, np.inf)
        k = np.argmin(norms, axis=1)
        rows = np.arange(len(lo))
        better = norms[rows, k] < best_norm
        best_t[better], best_norm[better] = grid[rows, k][better], norms[rows, k][better]
        step = (hi - lo) / (_REFINE_SAMPLES - 1)
        lo, hi = np.maximum(lo, grid[rows, k] - step), np.minimum(hi, grid[rows, k] + step)
    reaches = reach(best_norm[:, None] * np.array([1.0, 0.0, 0.0]), grade)
    lines = np.flatnonzero(reaches > LINE_REACH)
    if lines.size == 0:
        return None
    first = lines[0]
    return float(t[flips[first]]), float(t[flips[first] + 1]), float(best_t[first]), float(reaches[first])
