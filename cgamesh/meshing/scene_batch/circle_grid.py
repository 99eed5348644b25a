"""Many circle surfaces of one shape of work read as rows of rings and meshed together.

A group shares its sampler (samplers.py: the curve or motion kind, control count, parameters,
closed), its rings along and vertices around: its S surfaces' K rings each are S K rows of the
one circle mesher (cgamesh.meshing.circles.mesh_rings), read out of the sampler's circle blades
in each surface's frame as an evolved surface reads its own, so each surface's mesh is the one
it has meshed alone.

A surface whose projection scan is not surely clear (an error, or a line to refine), that has
no circle at one of its rings, or whose rings a step away from a repair could not be read, is
reported as not meshed (None): the caller meshes it alone, where its own reader refines its scan
or names what is wrong.
"""

from __future__ import annotations

import numpy as np

from cgamesh.geometry.algebra import products
from cgamesh.geometry.algebra.layout import grade_indices
from cgamesh.geometry.objects import circle_euclidean
from cgamesh.meshing.circles import CircleSurfaces, mesh_rings
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.meshing.ring_rows import RingRows, SurfaceRows


def _rows_at(sampler, origin: np.ndarray, scale: np.ndarray, surface: np.ndarray, t: np.ndarray
             ) -> tuple[RingRows, np.ndarray]:
    """The circles of rows (surface (R,) of the sampler, parameter t (R,)) in world units, each in
    its own surface's frame (``CircleRings.from_projection``), and whether each has one."""
    blades, derivatives, exists = sampler.at(surface, t)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        local_centre, normal, local_radius = circle_euclidean(blades)
        row_origin, row_scale = origin[surface], scale[surface]
        omega = products.geometric(blades, derivatives, (3,), (3,), (2,))
        rings = RingRows(row_origin + row_scale[:, None] * local_centre, normal, row_scale * local_radius,
                         np.moveaxis(omega[..., grade_indices(2)], -1, 0), row_origin, row_scale, t)
    return rings, exists & np.isfinite(normal).all(axis=1)


def mesh_circle_group(names, sampler, origin: np.ndarray, scale: np.ndarray, closed: bool, around: int,
                      along: int, tangents: bool, caps: np.ndarray | None = None) -> list[SurfaceMesh | None]:
    """The meshes of ``mesh_circle_surface(surface, around, along, caps=caps, closed=closed,
    with_tangents=tangents, distinct=True)`` for the S surfaces of one group (``sampler``, see
    samplers.py; their frames origin (S, 3), scale (S,); caps (S,) bool or None for none), or None
    for a surface left to be meshed alone (module doc)."""
    count = len(origin)
    caps = np.zeros(count, dtype=bool) if caps is None else caps
    t = np.linspace(0.0, sampler.segment_count, along)
    rings, exists = _rows_at(sampler, origin, scale, np.repeat(np.arange(count), along), np.tile(t, count))
    fit = np.flatnonzero(sampler.scan_ok(t) & exists.reshape(count, along).all(axis=1))
    results: list[SurfaceMesh | None] = [None] * count
    if fit.size == 0:
        return results
    if fit.size < count:
        rings = rings.take((fit[:, None] * along + np.arange(along)).ravel())

    def resample(surface: np.ndarray, at: np.ndarray) -> tuple[RingRows, np.ndarray]:
        return _rows_at(sampler, origin, scale, fit[surface], at)

    surfaces = CircleSurfaces(tuple(names[s] for s in fit), np.full(fit.size, float(sampler.segment_count)),
                              np.full(fit.size, closed), caps[fit], resample)
    meshes = mesh_rings(rings, SurfaceRows.of_counts(np.full(fit.size, along)), surfaces, around, tangents,
                        distinct=True)
    for k in np.flatnonzero(meshes.meshed):
        results[fit[k]] = meshes.surface_mesh(int(k))
    return results
