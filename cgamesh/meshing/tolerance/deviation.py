"""How far a grid mesh strays from the true evolved surface, over triangle interiors.

For each quad of the (t, theta) grid between rings k and k+1 the measure samples its triangles
at their centroids and the midpoints of their edges (where the chord of a ring and the rungs
between rings sag furthest), and takes each sample's distance to the surface as its distance
to the nearest member of the surface's family (circles C(t), or the segments of point pairs
P(t)) with t in [t_k, t_k+1]: that distance is exact and closed-form, and the nearest t is
found on a fine grid of members, then refined by a parabola and evaluated on the exact member
there. Every figure is the distance to a curve lying on the surface, so it never
underestimates the true distance.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from cgamesh.geometry.objects import circle_euclidean, point_pair_endpoints
from cgamesh.geometry.surface import EvolvedSurface

# Members per ring interval on which each sample's nearest member is looked for.
FINE_MEMBERS = 17
# Samples get the exact refinement in batches of this many, the largest first.
REFINE_BATCH = 4096
# Sample-to-member distances computed at once (a block of ring intervals).
DISTANCES_PER_BLOCK = 1 << 18


@dataclass(frozen=True)
class Deviation:
    """max, p99 and mean distance of the samples (file units), and how many were taken."""

    max: float
    p99: float
    mean: float
    samples: int


def circle_distance(points: np.ndarray, centre: np.ndarray, normal: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """Distances (...) of points (..., 3) from circles given by centre, unit normal (..., 3), radius (...)."""
    offset = points - centre
    dx, dy, dz = offset[..., 0], offset[..., 1], offset[..., 2]
    height = dx * normal[..., 0] + dy * normal[..., 1] + dz * normal[..., 2]
    in_plane = np.sqrt(np.maximum(dx * dx + dy * dy + dz * dz - height * height, 0.0))
    return np.sqrt(height * height + (in_plane - radius) ** 2)


def segment_distance(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distances (...) of points (..., 3) from the segments from a to b (..., 3)."""
    along = b - a
    offset = points - a
    fraction = np.clip(np.einsum("...i,...i->...", offset, along) / np.einsum("...i,...i->...", along, along), 0.0, 1.0)
    return np.linalg.norm(offset - fraction[..., None] * along, axis=-1)


def circle_read_out(surface: EvolvedSurface, t: np.ndarray):
    """World centre (A, 3), unit normal (A, 3) and radius (A,) of the circles C(t)."""
    centre, normal, radius = circle_euclidean(surface.sample_blades(t))
    return surface.frame.to_world(centre), normal, surface.frame.scale * radius


def segment_read_out(surface: EvolvedSurface, t: np.ndarray):
    """World end points a, b (A, 3) of the point pairs P(t) (paper eq. 5)."""
    a, b = point_pair_endpoints(surface.sample_blades(t))
    return surface.frame.to_world(a), surface.frame.to_world(b)


@dataclass(frozen=True)
class Family:
    """The curves a surface is the union of: how to read them at t, and distances to them."""

    read_out: Callable
    distance: Callable


CIRCLES = Family(circle_read_out, circle_distance)
SEGMENTS = Family(segment_read_out, segment_distance)


def grid_samples(grid: np.ndarray) -> np.ndarray:
    """Sample points (K-1, 6 (M-1), 3) in the triangles between consecutive rings of grid (K, M, 3).

    Per quad: both triangles' centroids and the midpoints of its two ring edges, its rung and
    its diagonal (a ring edge shared by two intervals is sampled in both).
    """
    here, right = grid[:-1, :-1], grid[:-1, 1:]
    below, across = grid[1:, :-1], grid[1:, 1:]
    return np.concatenate([
        (here + right + below) / 3.0,
        (right + across + below) / 3.0,
        0.5 * (here + right),
        0.5 * (below + across),
        0.5 * (right + below),
        0.5 * (here + below),
    ], axis=1)


def grid_deviation(surface: EvolvedSurface, t: np.ndarray, grid: np.ndarray, family: Family = CIRCLES) -> Deviation:
    """Deviation of a grid mesh (K, M, 3) on rings at parameters t (K,) from its surface."""
    samples = grid_samples(grid)  # (K-1, Q, 3)
    fraction = np.linspace(0.0, 1.0, FINE_MEMBERS)
    fine_t = t[:-1, None] + fraction[None, :] * np.diff(t)[:, None]  # (K-1, F)
    members = [m.reshape(fine_t.shape + m.shape[1:]) for m in family.read_out(surface, fine_t.ravel())]
    intervals, per_interval = samples.shape[:2]
    # Distances to the fine members, a block of intervals at a time (kept in cache, not a
    # (K-1, Q, F) array of hundreds of MB); kept per sample: the nearest member, its distance
    # and the distances on either side of it (for the parabola below).
    nearest = np.empty(intervals * per_interval, dtype=np.intp)
    best = np.empty(intervals * per_interval)
    beside = np.empty((intervals * per_interval, 3))
    block = max(1, DISTANCES_PER_BLOCK // (per_interval * FINE_MEMBERS))
    for first in range(0, intervals, block):
        part = slice(first, first + block)
        distance = family.distance(samples[part, :, None, :], *(m[part, None] for m in members))  # (B, Q, F)
        flat = distance.reshape(-1, FINE_MEMBERS)
        rows = slice(first * per_interval, first * per_interval + len(flat))
        nearest[rows] = np.argmin(flat, axis=1)
        best[rows] = flat[np.arange(len(flat)), nearest[rows]]
        inner = np.clip(nearest[rows], 1, FINE_MEMBERS - 2)
        beside[rows] = np.take_along_axis(flat, np.stack([inner - 1, inner, inner + 1], axis=-1), axis=1)

    # A parabola through the squared distances around the nearest fine member points at a
    # better t; the exact member there can only lower the (still exact) bound. Only samples
    # that could be the largest need it: batches of the largest are refined until the largest
    # of all has been.
    refined = np.zeros(best.size, dtype=bool)
    points = samples.reshape(-1, 3)
    per_interval = samples.shape[1]
    while not refined[np.argmax(best)]:
        open_ = np.flatnonzero(~refined)
        batch = open_[np.argsort(best[open_])[-REFINE_BATCH:]]
        interval = batch // per_interval
        inner = np.clip(nearest[batch], 1, FINE_MEMBERS - 2)
        d2 = beside[batch] ** 2
        curvature = d2[:, 0] - 2.0 * d2[:, 1] + d2[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            shift = np.where(curvature > 0.0, 0.5 * (d2[:, 0] - d2[:, 2]) / curvature, 0.0)
        shift = np.clip(np.nan_to_num(shift), -1.0, 1.0)
        step = np.diff(t)[interval] / (FINE_MEMBERS - 1)
        better_t = np.clip(fine_t[interval, inner] + shift * step, t[interval], t[interval + 1])
        exact = family.distance(points[batch], *family.read_out(surface, better_t))
        best[batch] = np.minimum(best[batch], exact)
        refined[batch] = True
    return Deviation(float(best.max()), float(np.percentile(best, 99)), float(best.mean()), best.size)
