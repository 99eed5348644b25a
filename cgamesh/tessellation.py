"""Tolerance-driven tessellation of circle surfaces: meet a distance budget with few vertices.

A tolerance is the largest distance the mesh may stray from the true surface, over triangle
interiors (file units). Two things make it stray: each ring's polygon cuts inside its circle
(the sagitta r (1 - cos(pi / M)) of its chords), and between rings the triangles cut across the
surface's curvature along t. So

- ``around`` is the fewest vertices whose chords on the largest circle sag less than a share of
  the tolerance;
- the rings are chosen from a dense set of candidates (every segment split evenly) by
  bisection: an interval between two chosen rings is split while some candidate ring inside it
  lies further than the other share from the chords joining the two rings' vertices, so rings
  gather where the surface bends and thin out where it is straight;
- the result is measured (cgamesh.deviation) and, if it misses, the budgets shrink in
  proportion and the choice is made again.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from cgamesh.deviation import circle_grid_deviation, circle_read_out
from cgamesh.mesh import SurfaceMesh
from cgamesh.meshing import mesh_circle_surface, transported_frames
from cgamesh.surface import EvolvedSurface

AROUND_SHARE = 0.5  # of the tolerance, for the chords around each circle
ALONG_SHARE = 0.5  # for the chords between rings
CANDIDATES_PER_SEGMENT = 256
MAX_ATTEMPTS = 6


def around_for_tolerance(max_radius: float, budget: float) -> int:
    """Fewest vertices (>= 3) around a circle of this radius whose chords sag at most ``budget``."""
    if budget >= max_radius:
        return 3
    return max(3, math.ceil(math.pi / math.acos(1.0 - budget / max_radius)))


def select_rings(t: np.ndarray, points: np.ndarray, budget: float, keep: np.ndarray) -> np.ndarray:
    """Indices of the candidate rings to keep, ascending.

    t (D,) candidate parameters; points (D, M, 3) each candidate ring's vertices (carried by the
    same TRS stepping, so column j follows one path); keep (D,) bool: rings that must stay
    (segment joints, both ends). An interval between kept rings i < j is split at its middle
    candidate while a candidate q inside it lies further than ``budget`` from the chord
    (1 - l) x_i + l x_j, l = (t_q - t_i) / (t_j - t_i), at some column.
    """
    chosen = np.flatnonzero(keep)
    candidates = np.arange(len(t))
    while True:
        right = np.searchsorted(chosen, candidates, side="right").clip(1, len(chosen) - 1)
        i, j = chosen[right - 1], chosen[right]
        lam = ((t - t[i]) / (t[j] - t[i]))[:, None, None]
        chord = (1.0 - lam) * points[i] + lam * points[j]
        error = np.linalg.norm(points - chord, axis=-1).max(axis=1)
        failing = np.unique(right[(error > budget) & (j - i > 1)])
        if failing.size == 0:
            return chosen
        chosen = np.union1d(chosen, (chosen[failing - 1] + chosen[failing]) // 2)


def mesh_to_tolerance(surface: EvolvedSurface, tolerance: float, caps: bool = False,
                      closed: bool = False) -> SurfaceMesh:
    """The mesh of a circle surface whose deviation from it is at most ``tolerance``.

    Its ``max_deviation`` holds the measured figure. Raises nothing for a missed budget: after
    MAX_ATTEMPTS the finest mesh made is returned with its (honest) measured deviation.
    """
    surface.check_projection_exists()
    segments = surface.segment_count
    candidates = CANDIDATES_PER_SEGMENT
    around_budget, along_budget = AROUND_SHARE * tolerance, ALONG_SHARE * tolerance
    mesh = None
    for _ in range(MAX_ATTEMPTS):
        t = np.linspace(0.0, segments, candidates * segments + 1)
        centre, normal, radius = circle_read_out(surface, t)
        around = around_for_tolerance(float(radius.max()), around_budget)
        u, v = transported_frames(normal, closed, t)
        theta = 2.0 * np.pi * np.arange(around) / around
        points = (centre[:, None, :] + radius[:, None, None]
                  * (np.cos(theta)[None, :, None] * u[:, None, :] + np.sin(theta)[None, :, None] * v[:, None, :]))
        keep = np.zeros(len(t), dtype=bool)
        keep[::candidates] = True
        rings = t[select_rings(t, points, along_budget, keep)]
        mesh = mesh_circle_surface(surface, around, t=rings, caps=caps, closed=closed)
        grid = mesh.positions[: len(rings) * (around + 1)].reshape(len(rings), around + 1, 3)
        achieved = circle_grid_deviation(surface, rings, grid).max
        mesh = replace(mesh, max_deviation=achieved)
        if achieved <= tolerance:
            return mesh
        shrink = max(0.25, 0.9 * tolerance / achieved)
        around_budget *= shrink
        along_budget *= shrink
        if np.any(np.diff(rings) <= np.diff(t)[0] * 1.0001):
            candidates *= 4
    return mesh
