"""Tolerance-driven tessellation of circle surfaces: meet a distance budget with few vertices.

A tolerance is the largest distance the mesh may stray from the true surface, over triangle
interiors (file units). Two things make it stray: each ring's polygon cuts inside its circle
(the sagitta r (1 - cos(pi / M)) of its chords), and between rings the triangles cut across the
surface's curvature along t. So

- ``around`` is the fewest vertices whose chords on the largest circle sag less than a share of
  the tolerance;
- the rings are chosen from a dense set of candidates (every segment split evenly), each as far
  from the previous one as it can be while no candidate ring between them lies further than
  the other share from the chords joining the two rings' vertices, so rings gather where the
  surface bends and thin out where it is straight;
- the result is measured (cgamesh.meshing.deviation) and, if it misses, the budgets shrink in
  proportion and the choice is made again.

Ribbons are straight across, so they need no budget for chords across; but the triangles of a
twisting ribbon cut its saddle-shaped quads, which either more rulings or more vertices across
cure: ``ribbon_to_tolerance`` prices each vertex count across and meshes the cheapest.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from cgamesh.meshing.deviation import CIRCLES, SEGMENTS, circle_read_out, grid_deviation, segment_read_out
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.meshing.circles import DISTINCT_RING_FRACTION, distinct_rings, mesh_circle_surface, transported_frames
from cgamesh.meshing.ribbons import mesh_ribbon_surface
from cgamesh.geometry.surface import EvolvedSurface

AROUND_SHARE = 0.5  # of the tolerance, for the chords around each circle
ALONG_SHARE = 0.5  # for the chords between rings
CANDIDATES_PER_SEGMENT = 256
MAX_ATTEMPTS = 6
BALANCING_STEPS = 10


def around_for_tolerance(max_radius: float, budget: float) -> int:
    """Fewest vertices (>= 3) around a circle of this radius whose chords sag at most ``budget``."""
    if budget >= max_radius:
        return 3
    return max(3, math.ceil(math.pi / math.acos(1.0 - budget / max_radius)))


def select_rings(t: np.ndarray, points: np.ndarray, budget: float, keep: np.ndarray) -> np.ndarray:
    """Indices of the candidate rings to keep, ascending: the fewest for the budget.

    t (D,) candidate parameters; points (D, M, 3) each candidate ring's vertices (carried by the
    same TRS stepping, so column j follows one path); keep (D,) bool: rings that must stay
    (segment joints, both ends). Rings i < j may be consecutive when every candidate q between
    them lies within ``budget`` of the chord (1 - l) x_i + l x_j, l = (t_q - t_i) / (t_j - t_i),
    at every column. From each chosen ring the next is the furthest such j (found by doubling,
    then bisection), which for this test gives the fewest rings.
    """
    kept = np.flatnonzero(keep)
    chosen = [0]
    while chosen[-1] < len(t) - 1:
        i = chosen[-1]
        limit = int(kept[np.searchsorted(kept, i, side="right")])  # never step over a kept ring
        good, step = i + 1, 1
        while good < limit and _chord_error(t, points, i, min(i + 2 * step, limit)) <= budget:
            good, step = min(i + 2 * step, limit), 2 * step
        bad = min(i + 2 * step, limit) if good < limit else good + 1
        while bad - good > 1:  # good is feasible, bad is not (or past the limit)
            middle = (good + bad) // 2
            if _chord_error(t, points, i, middle) <= budget:
                good = middle
            else:
                bad = middle
        chosen.append(good)
    return np.array(chosen)


def balanced_rings(t: np.ndarray, points: np.ndarray, budget: float, keep: np.ndarray) -> np.ndarray:
    """``select_rings`` with its rings spread as evenly as their count allows.

    The greedy choice for ``budget`` fixes how many rings are needed; bisection then finds the
    smallest budget that still needs no more, whose choice has the least largest error for that
    count (greedy leaves its slack in the last interval of each segment; this spreads it).
    """
    chosen = select_rings(t, points, budget, keep)
    low, high = 0.0, budget
    for _ in range(BALANCING_STEPS):
        middle = 0.5 * (low + high)
        trial = select_rings(t, points, middle, keep)
        if len(trial) <= len(chosen):
            high, chosen = middle, trial
        else:
            low = middle
    return chosen


def _spread(t: np.ndarray, points: np.ndarray, budget: float, keep: np.ndarray, spread) -> np.ndarray:
    """Ring parameters chosen from candidates t: "greedy" (``select_rings``), "balanced"
    (``balanced_rings``), or an int: that many rings evenly spaced in t."""
    if spread == "greedy":
        return t[select_rings(t, points, budget, keep)]
    if spread == "balanced":
        return t[balanced_rings(t, points, budget, keep)]
    return np.linspace(t[0], t[-1], spread)


def _chord_error(t: np.ndarray, points: np.ndarray, i: int, j: int) -> float:
    """How far the triangles between rings i and j may stray: the largest distance of the
    candidate rings strictly between them from the chords i -> j, or a quarter of the largest
    twist of a quad out of its own plane (its two triangles cut a saddle-shaped quad by that
    much at its centre: twist = x_i,c - x_i,c+1 - x_j,c + x_j,c+1 along the normal of the
    quad's diagonals), whichever is larger."""
    here, right, there, across = points[i, :-1], points[i, 1:], points[j, :-1], points[j, 1:]
    twist = here - right - there + across
    normal = np.cross(across - here, there - right)
    normal /= np.maximum(np.linalg.norm(normal, axis=-1, keepdims=True), np.finfo(float).tiny)
    error = 0.25 * float(np.max(np.abs(np.sum(twist * normal, axis=-1))))
    if j - i < 2:
        return error
    lam = ((t[i + 1:j] - t[i]) / (t[j] - t[i]))[:, None, None]
    chord = (1.0 - lam) * points[i] + lam * points[j]
    return max(error, float(np.sqrt(np.max(np.sum((points[i + 1:j] - chord) ** 2, axis=-1)))))


def _candidates(surface: EvolvedSurface, per_segment: int) -> tuple[np.ndarray, np.ndarray]:
    """Candidate ring parameters (D,) and which must stay (segment joints and both ends)."""
    t = np.linspace(0.0, surface.segment_count, per_segment * surface.segment_count + 1)
    keep = np.zeros(len(t), dtype=bool)
    keep[::per_segment] = True
    return t, keep


def _meet(tolerance: float, along_budget: float, attempt):
    """Run ``attempt(along_budget, per_segment, spread) -> (mesh, achieved, rings)`` until the
    measured deviation meets the tolerance, shrinking the budget in proportion to the miss (and
    making the candidates finer when the chosen rings are already as close as candidates can
    be); the rings that meet it are then spread out again (see ``_spread``) and the spread with
    the least measured deviation is kept.

    Returns (mesh with max_deviation set, met).
    """
    per_segment = CANDIDATES_PER_SEGMENT
    mesh = None
    for _ in range(MAX_ATTEMPTS):
        mesh, achieved, rings = attempt(along_budget, per_segment, "greedy")
        mesh = replace(mesh, max_deviation=achieved)
        if achieved <= tolerance:
            # Two more spreads of as many rings: balanced, and even in t (a surface that bends
            # alike everywhere is best served evenly); the least deviation wins.
            for spread in ("balanced", len(rings)):
                other, other_achieved, _ = attempt(along_budget, per_segment, spread)
                if other_achieved < mesh.max_deviation:
                    mesh = replace(other, max_deviation=other_achieved)
            return mesh, True
        along_budget *= max(0.25, 0.9 * tolerance / achieved)
        if np.any(np.diff(rings) <= 1.0001 / per_segment):  # candidates 1 / per_segment apart
            per_segment *= 4
    return mesh, False


def mesh_to_tolerance(surface: EvolvedSurface, tolerance: float, caps: bool = False,
                      closed: bool = False, tangents: bool = False) -> SurfaceMesh:
    """The mesh of a circle surface whose deviation from it is at most ``tolerance``.

    Its ``max_deviation`` holds the measured figure. After MAX_ATTEMPTS without meeting the
    budget the finest mesh made is returned with its (honest) measured deviation.
    """
    surface.check_projection_exists()
    around_share = [AROUND_SHARE * tolerance]

    def attempt(along_budget, per_segment, spread):
        t, keep = _candidates(surface, per_segment)
        centre, normal, radius = circle_read_out(surface, t)
        around = around_for_tolerance(float(radius.max()), around_share[0])
        u, v = transported_frames(normal, closed, t)
        theta = 2.0 * np.pi * np.arange(around + 1) / around  # the seam column closes the last quad
        points = (centre[:, None, :] + radius[:, None, None]
                  * (np.cos(theta)[None, :, None] * u[:, None, :] + np.sin(theta)[None, :, None] * v[:, None, :]))
        rings = _spread(t, points, along_budget, keep, spread)
        mesh = mesh_circle_surface(surface, around, t=rings, caps=caps, closed=closed, with_tangents=tangents)
        grid = mesh.positions[: len(rings) * (around + 1)].reshape(len(rings), around + 1, 3)
        achieved = grid_deviation(surface, rings, grid, CIRCLES).max
        distinct = distinct_rings(*circle_read_out(surface, rings), surface.frame.scale, surface.name)
        if not distinct.all():
            # Rings that would coincide in float32 (nearly identical controls) are left out of
            # the mesh written. Each lay within 2 DISTINCT_RING_FRACTION of the surface's size
            # of a ring kept before it, so the mesh moved by at most that: the figure grows by it.
            mesh = mesh_circle_surface(surface, around, t=rings[distinct], caps=caps, closed=closed,
                                       with_tangents=tangents)
            achieved += 2.0 * DISTINCT_RING_FRACTION * surface.frame.scale
        # The next attempt, if any, tightens both shares alike.
        if spread == "greedy" and achieved > tolerance:
            around_share[0] *= max(0.25, 0.9 * tolerance / achieved)
        return mesh, achieved, rings

    return _meet(tolerance, ALONG_SHARE * tolerance, attempt)[0]


# Vertices across a ribbon tried in turn: the rulings are straight, so 2 is exact across, but a
# twisting ribbon's triangles cut its saddle-shaped quads, which more vertices across also cure.
RIBBON_ACROSS = (2, 3, 5, 9, 17, 33, 65)


def ribbon_to_tolerance(surface: EvolvedSurface, tolerance: float, closed: bool = False) -> SurfaceMesh:
    """The mesh of a point-pair surface within ``tolerance`` of it, with few vertices.

    Each count of vertices across (RIBBON_ACROSS) is priced by the rulings ``select_rings``
    would choose for it on the first candidates; counts are then meshed and measured as for
    circles, cheapest first (those whose choice the candidates' spacing limits last), and the
    first that meets the tolerance is kept. If none does, the closest mesh is returned with its
    (honest) measured deviation.
    """
    surface.check_projection_exists()

    def points_for(across, per_segment):
        t, keep = _candidates(surface, per_segment)
        a, b = segment_read_out(surface, t)
        s = np.linspace(0.0, 1.0, across)
        return t, keep, a[:, None, :] + s[None, :, None] * (b - a)[:, None, :]

    prices = []
    for across in RIBBON_ACROSS:
        t, keep, points = points_for(across, CANDIDATES_PER_SEGMENT)
        rulings = len(select_rings(t, points, tolerance, keep))
        saturated = rulings == len(t)  # every candidate chosen: the true count may be far larger
        prices.append((saturated, across * rulings, across))

    fallback = None
    for _, _, across in sorted(prices):

        def attempt(along_budget, per_segment, spread, across=across):
            t, keep, points = points_for(across, per_segment)
            rings = _spread(t, points, along_budget, keep, spread)
            mesh = mesh_ribbon_surface(surface, across, t=rings, closed=closed)
            grid = mesh.positions.reshape(len(rings), across, 3)
            return mesh, grid_deviation(surface, rings, grid, SEGMENTS).max, rings

        mesh, met = _meet(tolerance, tolerance, attempt)
        if met:
            return mesh
        if fallback is None or mesh.max_deviation < fallback.max_deviation:
            fallback = mesh
    return fallback
