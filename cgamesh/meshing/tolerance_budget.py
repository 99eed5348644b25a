"""What a tolerance run will cost, estimated a priori, and the floor under a tolerance.

Priced before ``tessellation`` starts, so that a tolerance far below the surface's size is
refused in one line instead of growing until memory runs out (cgamesh.budget).

- Floor: a tolerance below TOLERANCE_FLOOR times the surface's bounding radius (the radius of
  the ball its controls' circles or end points fit in), or below FLOAT_SPACING_FACTOR float64
  spacings of its coordinates, asks for more than float64 vertices can show; it is refused.
- Around a circle: the closed form of the chord sag, r (1 - cos(pi / M)) <= the around share,
  on the largest circle (``tessellation.around_for_tolerance``). Across a ribbon: each count
  the tessellation may try (``RIBBON_ACROSS``), the cheapest kept.
- Along: the surface is sampled on a coarse (t, column) grid; between rings Delta t apart a
  column's chord sags |x_tt| Delta t^2 / 8 and a quad twists out of its plane by
  |x_t,col . n| Delta t (col) (its triangles cut it by a quarter of that); each share of the
  budget gives the largest Delta t per sample interval, and the rings needed are the sum of
  h / Delta t over the intervals, times ALONG_SAFETY (the sampling sees curvature only to
  its resolution).
- Memory: estimated vertices times TOLERANCE_PER_VERTEX, the measured peak of whole runs per
  vertex of this estimate (it covers the candidates' rings, the deviation measure's samples
  against fine members, the tries that do not meet the budget, and a ring choice that takes
  more vertices than the estimate), plus the candidate rings the ring choice allocates.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cgamesh.geometry.surface import EvolvedSurface
from cgamesh.meshing.circles import transported_frames
from cgamesh.meshing.deviation import circle_read_out, segment_read_out
from cgamesh.meshing.tessellation import (ALONG_SHARE, AROUND_SHARE, CANDIDATES_PER_SEGMENT, RIBBON_ACROSS,
                                          around_for_tolerance)

TOLERANCE_FLOOR = 1e-7  # of the surface's bounding radius
FLOAT_SPACING_FACTOR = 64  # float64 spacings (of the largest coordinate) a tolerance must exceed
SAMPLES_PER_SEGMENT = 64
COLUMNS = 16
ALONG_SAFETY = 2.0
# Peak bytes (tracemalloc) of whole tolerance runs on the examples at 1e-3 and 1e-4 of their
# size, per vertex of this module's estimate: circles up to about 3.5 KB, ribbons up to about
# 200 KB (their ring choice takes up to 5 times the estimated vertices), with a margin.
TOLERANCE_PER_VERTEX = {"circles": 8 * 2**10, "point_pairs": 256 * 2**10}
CANDIDATE_COPIES = 16  # the candidate grid and the ring choice's temporaries of its size
RUN_OVERHEAD = 8 * 2**20  # per run, whatever its size: the dense scans, the measure's tables


@dataclass(frozen=True)
class ToleranceCost:
    around: int  # vertices around (or across) each ring
    along: int  # rings (rulings), estimated
    bytes: int  # peak memory, estimated

    @property
    def vertices(self) -> int:
        return (self.around + 1) * self.along


def size_of(surface: EvolvedSurface) -> tuple[float, float]:
    """(bounding radius, largest coordinate magnitude) of the surface's controls, file units."""
    radius = float(surface.frame.scale)
    return radius, float(np.max(np.abs(surface.frame.origin))) + radius


def tolerance_floor(surface: EvolvedSurface) -> float:
    """The least tolerance this surface can be meshed to (see the module doc)."""
    radius, extent = size_of(surface)
    return max(TOLERANCE_FLOOR * radius, FLOAT_SPACING_FACTOR * float(np.spacing(extent)))


def estimate(surface: EvolvedSurface, tolerance: float, closed: bool = False) -> ToleranceCost:
    """The a priori size and memory of meshing ``surface`` to ``tolerance`` (see the module doc)."""
    segments = surface.segment_count
    t = np.linspace(0.0, segments, SAMPLES_PER_SEGMENT * segments + 1)
    if surface.grade == 3:
        centre, normal, radius = circle_read_out(surface, t)
        around = around_for_tolerance(float(radius.max()), AROUND_SHARE * tolerance)
        u, v = transported_frames(normal, closed, t)
        theta = 2.0 * np.pi * np.arange(COLUMNS + 1) / COLUMNS
        grid = centre[:, None] + radius[:, None, None] * (np.cos(theta)[None, :, None] * u[:, None]
                                                          + np.sin(theta)[None, :, None] * v[:, None])
        along = _rings(t, grid, ALONG_SHARE * tolerance, COLUMNS / around, segments)
        kind = "circles"
    else:
        a, b = segment_read_out(surface, t)
        grid = np.stack([a, b], axis=1)  # straight across: the two edges carry all the bending
        # Each count across the tessellation may try, priced; the cheapest is the estimate.
        around, along = min(((n, _rings(t, grid, tolerance, 1.0 / (n - 1), segments)) for n in RIBBON_ACROSS),
                            key=lambda pair: pair[0] * pair[1])
        around -= 1  # ToleranceCost counts around + 1 per ring
        kind = "point_pairs"
    vertices = (around + 1) * along
    per_segment = CANDIDATES_PER_SEGMENT
    for _ in range(5):  # the ring choice makes its candidates finer while chosen rings are adjacent
        if per_segment * segments >= 2 * along:
            break
        per_segment *= 4
    candidates = (per_segment * segments + 1) * (around + 2) * 3 * 8 * CANDIDATE_COPIES
    return ToleranceCost(around, along, TOLERANCE_PER_VERTEX[kind] * vertices + candidates + RUN_OVERHEAD)


def _rings(t: np.ndarray, grid: np.ndarray, budget: float, column_ratio: float, segments: int) -> int:
    """Rings for ``budget`` from a sampled grid (T, C, 3); ``column_ratio``: the mesh's column
    spacing over the grid's (quads twist in proportion to their width)."""
    h = np.diff(t)
    # |x_tt| per sample interval: second differences, each interval taking the larger of its ends.
    second = np.linalg.norm(grid[2:] - 2.0 * grid[1:-1] + grid[:-2], axis=-1).max(axis=1) / h[1:] ** 2
    second = np.concatenate([second[:1], second, second[-1:]]) if second.size else np.zeros(2)
    curvature = np.maximum(second[:-1], second[1:])
    # Twist per unit t of a grid quad: (x_i,c - x_i,c+1 - x_j,c + x_j,c+1) . n / h.
    here, right, there, across = grid[:-1, :-1], grid[:-1, 1:], grid[1:, :-1], grid[1:, 1:]
    normal = np.cross(across - here, there - right)
    normal /= np.maximum(np.linalg.norm(normal, axis=-1, keepdims=True), np.finfo(float).tiny)
    twist = np.abs(np.sum((here - right - there + across) * normal, axis=-1)).max(axis=1) / h
    sag_rings = h * np.sqrt(curvature / (8.0 * budget))
    twist_rings = h * twist * column_ratio / (4.0 * budget)
    total = float(np.sum(np.maximum(sag_rings, twist_rings)))
    if not math.isfinite(total):
        total = float("inf")
    return int(min(ALONG_SAFETY * total, 1e30)) + segments + 1
