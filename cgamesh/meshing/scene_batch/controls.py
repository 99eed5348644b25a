"""The control blades of many blade-circle surfaces at once, as ``construction.build_surface`` makes them.

For every surface: its working frame (``LocalFrame.enclosing`` of its circle points and
radii), its circle controls normalised in that frame, and, with ``align``, their orientations
made to agree; all as arrays over every control of every surface. A surface whose controls
``build_surface`` would refuse (a circle that does not square to a positive number, every
control the same circle), or would change (a linear curve dropping a repeated control), or
whose interpolants are four-vector free (``project_scalar``), is marked ``ok = False``: the
per-surface path builds it (and names its error).

Every number is made by the same operations as ``build_surface`` makes it, row by row, so
the blades are the same bits (cgamesh.geometry.algebra.products computes a row alone as in a
batch).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cgamesh.geometry import objects
from cgamesh.geometry.algebra import products
from cgamesh.geometry.algebra.conformal import up
from cgamesh.geometry.construction import SAME_CONTROL_RTOL, circumcircle
from cgamesh.geometry.projection import FOUR_VECTOR_RTOL

_GRADE = (objects.CIRCLE_GRADE,)


@dataclass(frozen=True)
class BladeControls:
    """controls (S, n, 32) in each surface's frame; origin (S, 3) and scale (S,) of the frames
    (world = origin + scale * local); ok (S,) bool: the batched path may mesh the surface."""

    controls: np.ndarray
    origin: np.ndarray
    scale: np.ndarray
    ok: np.ndarray


def build_blade_controls(specs, n: int) -> BladeControls:
    """The blades of blade-circle ``specs``, each of ``n`` controls."""
    count = len(specs)
    centre = np.empty((count * n, 3))
    normal = np.empty((count * n, 3))
    radius = np.empty(count * n)
    points, reach, first = [], [], [0]
    for s, spec in enumerate(specs):
        for c, control in enumerate(spec.controls):
            row = s * n + c
            if control.through is not None:
                # as construction._circle_points and _circle_blade: the circumcircle, its points
                # and centre in the frame
                middle, unit, r = circumcircle(control.through)
                centre[row], normal[row], radius[row] = middle, unit, r
                points.extend([*control.through, middle])
                reach.extend([0.0, 0.0, 0.0, r])
            else:
                centre[row], normal[row], radius[row] = control.center, control.normal, control.radius
                points.append(control.center)
                reach.append(control.radius)
        first.append(len(points))
    points = np.array(points, dtype=np.float64)
    reach = np.array(reach, dtype=np.float64)
    starts = np.array(first[:-1])
    # LocalFrame.enclosing, per surface (minima and maxima are exact in any order)
    origin = 0.5 * (np.minimum.reduceat(points, starts, axis=0) + np.maximum.reduceat(points, starts, axis=0))
    sizes = np.diff(first)
    reach = np.linalg.norm(points - np.repeat(origin, sizes, axis=0), axis=1) + reach
    scale = np.maximum.reduceat(reach, starts)
    scale = np.where(scale > 0.0, scale, 1.0)

    row_origin, row_scale = np.repeat(origin, n, axis=0), np.repeat(scale, n)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        blades, positive = _circles(row_origin, row_scale, centre, normal, radius)
    ok = positive.reshape(count, n).all(axis=1) & np.isfinite(blades).reshape(count, -1).all(axis=1)
    blades = np.where(np.isfinite(blades), blades, 0.0).reshape(count, n, 32)

    align = np.array([spec.align for spec in specs])
    if align.any():
        agreement = products.geometric(blades[:, :-1].reshape(-1, 32), blades[:, 1:].reshape(-1, 32),
                                       _GRADE, _GRADE, (0,))[:, 0].reshape(count, n - 1)
        flips = np.where(agreement < 0.0, -1.0, 1.0)
        signs = np.concatenate([np.ones((count, 1)), np.cumprod(flips, axis=1)], axis=1)
        blades = np.where(align[:, None, None], blades * signs[:, :, None], blades)

    size = np.maximum(np.abs(blades[:, 1:]).max(axis=2), np.abs(blades[:, :-1]).max(axis=2))
    same = np.abs(blades[:, 1:] - blades[:, :-1]).max(axis=2) <= SAME_CONTROL_RTOL * size
    linear = np.array([spec.curve == "linear" for spec in specs])
    ok &= ~same.all(axis=1) & ~(linear & same.any(axis=1))
    ok &= ~_four_vector_free(blades)
    return BladeControls(blades, origin, scale, ok)


def _circles(origin, scale, centre, normal, radius):
    """objects.circle_from_center_normal_radius(frame.to_local(centre), normal, radius / scale),
    row by row, and whether each squares to a positive number (``objects.normalise`` refuses it)."""
    local = (centre - origin) / scale[:, None]
    r = (radius / scale)[:, None]
    n = normal / np.abs(normal).max(axis=-1, keepdims=True)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    u = objects.perpendicular_unit(n)
    v = np.cross(n, u)
    blade = products.outer(products.outer(up(local + r * u), up(local + r * v), (1,), (1,)), up(local - r * u),
                           (2,), (1,))
    square = objects.square(blade, objects.CIRCLE_GRADE)
    return blade / np.sqrt(square)[..., None], square > 0.0


def _four_vector_free(blades: np.ndarray) -> np.ndarray:
    """projection.four_vector_free of each surface's controls (S, n, 32) -> (S,) bool."""
    count, n, _ = blades.shape
    left = np.repeat(blades, n, axis=1).reshape(-1, 32)
    right = np.tile(products.reverse(blades), (1, n, 1)).reshape(-1, 32)
    cross = products.geometric(left, right, _GRADE, _GRADE, (4,)).reshape(count, n, n, 32)
    symmetric = np.abs(cross + np.swapaxes(cross, 1, 2)).max(axis=-1)
    norms = np.linalg.norm(blades, axis=-1)
    return np.all(symmetric <= FOUR_VECTOR_RTOL * (norms[:, :, None] * norms[:, None, :]), axis=(1, 2))
