"""Tolerance-driven tessellation: meshes within a distance of the true surface, from a priori bounds.

A tolerance is the largest distance the mesh may stray from the true surface, over triangle
interiors (file units). ``cgamesh.meshing.tolerance.tolerance_plan`` chooses the count around (across a
ribbon) and the ring parameters from bounds of the surface's derivatives, with the split of
the tolerance between chords around and spacing along that needs the fewest vertices; the mesh
is then made once, by the ordinary mesher, on those rings. Nothing is measured: the mesh's
``max_deviation`` is the plan's bound, a proven upper bound of the deviation (docs/tolerance.md),
which cgamesh.meshing.tolerance.deviation and the tests' independent measure check.
"""

from __future__ import annotations

from dataclasses import replace

from cgamesh.geometry.surface import EvolvedSurface
from cgamesh.meshing.circles import (DISTINCT_RING_FRACTION, distinct_rings, kept_rings, mesh_circle_surface,
                                     read_rings)
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.meshing.ribbons import mesh_ribbon_surface
from cgamesh.meshing.tolerance.tolerance_plan import PreparedPlan, TolerancePlan


def _plan(surface: EvolvedSurface, tolerance: float, kind: str, closed: bool,
          prepared: PreparedPlan | None) -> TolerancePlan:
    """The rings of ``prepared`` (the plan a budget priced: planned once), or planned here."""
    if prepared is None:
        surface.check_projection_exists()
        prepared = PreparedPlan(surface, tolerance, kind, closed)
    return prepared.place()


def mesh_to_tolerance(surface: EvolvedSurface, tolerance: float, caps: bool = False,
                      closed: bool = False, tangents: bool = False,
                      prepared: PreparedPlan | None = None) -> SurfaceMesh:
    """The mesh of a circle surface whose deviation from it is at most ``tolerance``.

    Its ``max_deviation`` holds the plan's upper bound of the deviation (<= tolerance).
    Caps are exact flat discs and add nothing to it. ``prepared``: the plan already made for
    this surface and tolerance (by the resource budget, which checked its projection).
    """
    plan = _plan(surface, tolerance, "circles", closed, prepared)
    t, bound = plan.t, plan.bound
    rings = read_rings(surface, t)  # read once: for the distinct check and for the mesher
    distinct = distinct_rings(rings.centre, rings.normal, rings.radius, surface.frame.scale, surface.name)
    if not distinct.all():
        # Rings that would coincide in float32 (nearly identical controls) are left out of the
        # mesh written. Each lay within 2 DISTINCT_RING_FRACTION of the surface's size of a ring
        # kept before it, so the mesh moved by at most that: the bound grows by it.
        t, rings = t[distinct], kept_rings(rings, distinct)
        bound += 2.0 * DISTINCT_RING_FRACTION * surface.frame.scale
    mesh = mesh_circle_surface(surface, plan.around, t=t, caps=caps, closed=closed, with_tangents=tangents,
                               rings=rings)
    return replace(mesh, max_deviation=bound)


def ribbon_to_tolerance(surface: EvolvedSurface, tolerance: float, closed: bool = False,
                        prepared: PreparedPlan | None = None) -> SurfaceMesh:
    """The mesh of a point-pair surface within ``tolerance`` of it; ``max_deviation`` as above."""
    plan = _plan(surface, tolerance, "point_pairs", closed, prepared)
    mesh = mesh_ribbon_surface(surface, plan.around, t=plan.t, closed=closed)
    return replace(mesh, max_deviation=plan.bound)
