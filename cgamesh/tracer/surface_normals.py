"""Normals of evolved surfaces at traced hits, derived here from the paper (not from the mesher).

Analytic, circles (section 5.2): at the point X of the circle C = C(t) with C' = dC/dt,

    L_C = (X . C) ^ n_inf            the tangent line of the circle at X   (eq. 17)
    Omega = C C'                     the angular-velocity bivector          (eq. 19)
    X' = X . Omega                   the velocity of X as the circles evolve (eq. 20)
    L_T = X' ^ X ^ n_inf             the tangent line along the evolution   (eq. 22)
    N = <L_T L_C>_2 I5               the normal line                        (eq. 25)

Analytic, point pairs: the surface is the union of the segments between the end points a, b
of P(t), a ruled surface x = a + s (b - a). Section 7.2 takes L_C = P ^ n_inf (the ruling,
exact) and the same L_T, but X . Omega moves an interior point of the segment along a circle
through the moving end points, off the ruled surface; the velocity that stays on it is
(1 - s) a' + s b', with a', b' the end points' velocities from A . Omega, B . Omega. So here
L_T is the line through X along that velocity, and N = <L_T L_C>_2 I5 as before.

Numerical second opinion: the curve cut on the surface by the plane through x across the
circle (normal to L_C), followed through the neighbouring objects C(t +- h) (each plane-circle
meet is a point pair, eq. 5; the point nearer x is kept); for point pairs the points at the
same fraction s of the neighbouring segments. Its central difference is a tangent along the
evolution; crossed with the circle's tangent (the ruling) it gives the normal.
"""

from __future__ import annotations

import numpy as np

from cgamesh.geometry.algebra.conformal import EUCLIDEAN, N_INF, up, weight
from cgamesh.geometry.objects import point_pair_endpoints
from cgamesh.tracer import cga

# Parameter step of the numerical normal (per unit of the curve parameter t).
NUMERICAL_STEP = 1e-5


def _normal_from_lines(tangent_evolution: np.ndarray, tangent_object: np.ndarray) -> np.ndarray:
    """Unit directions (K, 3) of N = <L_T L_C>_2 I5 (eq. 25); zero where N vanishes."""
    bivector = cga.product(tangent_evolution, tangent_object, (3,), (3,), (2,))
    normal_line = cga.product(bivector, cga.I5, (2,), (5,), (3,))
    d = normal_line[..., cga.LINE_DIRECTION]
    size = np.linalg.norm(d, axis=-1, keepdims=True)
    return np.where(size > 0.0, d / np.where(size > 0.0, size, 1.0), 0.0)


def euclidean_velocity(points: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """dx/dt (K, 3) of points x (K, 3) carried by X' = X . Omega (eq. 20), Omega (K, 32).

    X' changes the weight of X at the rate w' = -X' . n_inf, so x' = X'_E - w' x.
    """
    moved = cga.inner(up(points), omega, (1,), (2,))
    return moved[..., EUCLIDEAN] - weight(moved)[..., None] * points


def circle_normals(blades: np.ndarray, derivatives: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Unit normals (K, 3) at points (K, 3) on circles C (K, 32) with dC/dt (K, 32) (eqs. 17-25)."""
    x = up(points)
    tangent_circle = cga.outer(cga.inner(x, blades, (1,), (3,)), N_INF, (2,), (1,))
    omega = cga.product(blades, derivatives, (3,), (3,), (2,))
    velocity = cga.inner(x, omega, (1,), (2,))
    tangent_evolution = cga.outer(cga.outer(velocity, x, (1,), (1,)), N_INF, (2,), (1,))
    return _normal_from_lines(tangent_evolution, tangent_circle)


def pair_fractions(blades: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """End points a, b (K, 3) of point pairs (eq. 5) and the fraction s (K,) of points along a -> b."""
    a, b = point_pair_endpoints(blades)
    d = b - a
    s = np.einsum("ki,ki->k", points - a, d) / np.einsum("ki,ki->k", d, d)
    return a, b, s


def pair_normals(blades: np.ndarray, derivatives: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Unit normals (K, 3) of the ruled surface at points (K, 3) on the segments of pairs P (K, 32)."""
    a, b, s = pair_fractions(blades, points)
    omega = cga.product(blades, derivatives, (2,), (2,), (2,))
    velocity = ((1.0 - s)[:, None] * euclidean_velocity(a, omega) + s[:, None] * euclidean_velocity(b, omega))
    x = up(points)
    v = np.zeros_like(x)
    v[..., EUCLIDEAN] = velocity
    tangent_evolution = cga.outer(cga.outer(x, v, (1,), (1,)), N_INF, (2,), (1,))
    ruling = cga.outer(blades, N_INF, (2,), (1,))
    return _normal_from_lines(tangent_evolution, ruling)


def numerical_normals(sample, grade: int, t: np.ndarray, points: np.ndarray, end: float,
                      side: float = 0.0) -> np.ndarray:
    """Normals (K, 3) at points (K, 3) of parameters t (K,) from the neighbouring objects.

    ``sample(t) -> Projection`` gives the objects (blades) at parameters t in [0, end]; all in
    the same (local) frame as ``points``. ``side``: 0 for central differences, -1 or +1 for
    one-sided ones from below or above t (at a segment joint where the surface stops, e.g. a
    Kochanek-Bartels spline of tension 1, the two sheets meeting there may have different
    normals, and a central difference would average them).
    """
    low = t if side > 0.0 else np.maximum(t - NUMERICAL_STEP, 0.0)
    high = t if side < 0.0 else np.minimum(t + NUMERICAL_STEP, end)
    here = sample(t).blades
    near = sample(np.concatenate([low, high])).blades
    count = len(t)
    if grade == 2:
        a, b, s = pair_fractions(here, points)
        ends = point_pair_endpoints(near)
        moved = ends[0] + np.concatenate([s, s])[:, None] * (ends[1] - ends[0])
        tangent = (moved[count:] - moved[:count]) / (high - low)[:, None]
        normal = np.cross(b - a, tangent)
    else:
        x = up(points)
        circle_tangent = cga.outer(cga.inner(x, here, (1,), (3,)), N_INF, (2,), (1,))
        tau = cga.line_direction(circle_tangent)
        cut = cga.plane(points, tau)
        both_cuts = np.concatenate([cut, cut])
        a, b, _ = cga.split_point_pair(cga.meet(both_cuts, near, 4, 3))
        both_points = np.concatenate([points, points])
        nearer = np.where((np.linalg.norm(a - both_points, axis=1) <= np.linalg.norm(b - both_points, axis=1))[:, None],
                          a, b)
        tangent = (nearer[count:] - nearer[:count]) / (high - low)[:, None]
        normal = np.cross(tau, tangent)
    size = np.linalg.norm(normal, axis=1, keepdims=True)
    return normal / np.where(size > 0.0, size, 1.0)
