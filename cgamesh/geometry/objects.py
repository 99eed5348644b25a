"""Control objects: circles (3-blades) and point pairs (2-blades), batched as (..., 32) arrays.

Construction follows the scene format exactly: a circle {center, normal, radius} is A^B^D of
three points on it in counter-clockwise order seen from the tip of ``normal``; {through} is
A^B^D in the given order; a point pair {a, b} is up(a)^up(b). Objects are normalised to
square to +1. Call these in a LocalFrame (see cgamesh.geometry.frame): the read-outs lose precision
with the square of the distance from the origin.
"""

from __future__ import annotations

import numpy as np

from cgamesh.geometry.algebra import products
from cgamesh.geometry.algebra.conformal import EUCLIDEAN, N_INF, down, up
from cgamesh.errors import DegenerateGeometryError, NonFiniteInputError

CIRCLE_GRADE = 3
POINT_PAIR_GRADE = 2
# End points closer than this fraction of their distance from the origin coincide (as the scene loader).
COINCIDENT_RTOL = 1e-12
_SCALAR = np.zeros(32)
_SCALAR[0] = 1.0


def perpendicular_unit(n: np.ndarray) -> np.ndarray:
    """A unit vector perpendicular to each unit vector n (..., 3), chosen continuously per axis."""
    n = np.asarray(n, dtype=np.float64)
    # Cross with the coordinate axis least aligned with n, so the result is never tiny.
    axis = np.zeros_like(n)
    np.put_along_axis(axis, np.argmin(np.abs(n), axis=-1)[..., None], 1.0, axis=-1)
    u = np.cross(n, axis)
    return u / np.linalg.norm(u, axis=-1, keepdims=True)


def circle_from_center_normal_radius(center, normal, radius) -> np.ndarray:
    """Normalised circles (..., 32) from centres (..., 3), normals (..., 3) and radii (...)."""
    center = np.asarray(center, dtype=np.float64)
    normal = np.asarray(normal, dtype=np.float64)
    radius = np.asarray(radius, dtype=np.float64)[..., None]
    # A normal is a direction: divided by its largest component first, any finite non-zero one
    # (1e-300 or 1e300 long) has a length that neither underflows nor overflows.
    n = normal / np.abs(normal).max(axis=-1, keepdims=True)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    u = perpendicular_unit(n)
    v = np.cross(n, u)  # (u, v, n) right-handed: u -> v is counter-clockwise about n
    return circle_through(center + radius * u, center + radius * v, center - radius * u)


def circle_through(a, b, d) -> np.ndarray:
    """Normalised circles up(a)^up(b)^up(d) (..., 32) through three points (..., 3) each."""
    blade = products.outer(products.outer(up(a), up(b), (1,), (1,)), up(d), (2,), (1,))
    return normalise(blade, CIRCLE_GRADE)


def point_pair(a, b) -> np.ndarray:
    """Normalised point pairs up(a)^up(b) (..., 32) from end points a, b (..., 3), finite and distinct."""
    a, b = np.broadcast_arrays(np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64))
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        raise NonFiniteInputError("point pair end points must be finite, got NaN or infinity")
    gap = np.linalg.norm(a - b, axis=-1)
    reach = np.maximum(np.linalg.norm(a, axis=-1), np.linalg.norm(b, axis=-1))
    if np.any(gap <= COINCIDENT_RTOL * reach):
        i = np.unravel_index(np.argmin(gap - COINCIDENT_RTOL * reach), np.shape(gap))
        raise DegenerateGeometryError(
            f"point pair end points must differ, got a = {a[i].tolist()} and b = {b[i].tolist()}"
        )
    return normalise(products.outer(up(a), up(b), (1,), (1,)), POINT_PAIR_GRADE)


def square(blade, grade: int) -> np.ndarray:
    """The scalar X^2 of blades X (..., 32) of one grade."""
    return products.geometric(blade, blade, (grade,), (grade,), (0,))[..., 0]


def normalise(blade, grade: int) -> np.ndarray:
    """X / sqrt(X^2) for blades of one grade whose square is positive (real circles, pairs)."""
    sq = square(blade, grade)
    if not np.all(sq > 0.0):
        raise DegenerateGeometryError(
            f"a grade-{grade} blade does not square to a positive number (got {sq.min():.3g}): "
            "it is not a real circle or point pair"
        )
    return blade / np.sqrt(sq)[..., None]


def align_orientations(blades: np.ndarray, grade: int) -> np.ndarray:
    """Negate control i+1 where <C_i C_{i+1}>_0 < 0, so consecutive controls agree.

    blades: (n, 32). The decisions cascade (negating C_i flips the sign of its product
    with C_{i+1}), so the sign of control i is the product of the disagreements before it.
    """
    agreement = products.geometric(blades[:-1], blades[1:], (grade,), (grade,), (0,))[..., 0]
    flips = np.where(agreement < 0.0, -1.0, 1.0)
    signs = np.concatenate([[1.0], np.cumprod(flips)])
    return blades * signs[:, None]


def circle_euclidean(circles) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centre (..., 3), unit normal (..., 3) and radius (...) of circles (..., 32).

    centre = down(C n_inf C); the plane C ^ n_inf has dual n + d n_inf, and the circle's
    right-handed normal is minus its Euclidean part; r^2 = -C^2 / (C ^ n_inf)^2.
    """
    circles = np.asarray(circles, dtype=np.float64)
    plane = products.outer(circles, N_INF, (3,), (1,))
    centre_point = products.geometric(
        products.geometric(circles, N_INF, (3,), (1,), (2, 4)), circles, (2, 4), (3,), (1,)
    )
    plane_dual = products.dual(plane)
    normal = -plane_dual[..., EUCLIDEAN]
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    radius_sq = -square(circles, 3) / square(plane, 4)
    return down(centre_point), normal, np.sqrt(radius_sq)


def point_pair_endpoints(pairs) -> tuple[np.ndarray, np.ndarray]:
    """The end points (a, b) (..., 3) of point pairs P = up(a)^up(b) (..., 32) (paper eq. 5).

    a ~ (1 - P / sqrt(P^2)) (P . n_inf), b ~ (1 + P / sqrt(P^2)) (P . n_inf).
    """
    pairs = np.asarray(pairs, dtype=np.float64)
    unit = pairs / np.sqrt(square(pairs, 2))[..., None]
    direction = products.inner(pairs, N_INF, (2,), (1,))
    a = products.geometric(_SCALAR - unit, direction, (0, 2), (1,), (1,))
    b = products.geometric(_SCALAR + unit, direction, (0, 2), (1,), (1,))
    return down(a), down(b)
