"""Many blade-interpolated point-pair surfaces (ribbons) of one shape of work sampled as one set of arrays.

A group shares its curve (kind, control count, parameters), closed, vertices across and rulings
along. Each surface is built as the per-surface path builds it (``build_surface``); the
projection scan of ``check_projection_exists`` runs on all of them at once
(``projection_scan.exactly_projectable``, which decides as it does, bit for bit); then the
interpolants of every ruling of every surface, their projections (section 6), end points
(eq. 5) and end-point velocities (eqs. 19-20) are computed once over all S K rows, with the
operations ``EvolvedSurface.sample`` and ``ribbons.PairRings.from_projection`` apply to each
row (products.geometric and inner compute a row alone as in a batch; everything else is
row-wise), so the rings are the same bits. The rest of ``ribbons.mesh_ribbon_surface`` (normals, their continuity, faces, UVs) runs
per surface on its slice of the rings.

Left to the per-surface path (None): a surface whose build or scan fails (its error is named
there), whose interpolants are four-vector free (the scalar projection), whose sampled margin
is below MIN_MARGIN or whose end points leave the finite (``sample`` refuses those), and any
surface whose mesher raises (a ruling that stands still, for instance).
"""

from __future__ import annotations

import numpy as np

from cgamesh.errors import CgameshError
from cgamesh.geometry.algebra import products
from cgamesh.geometry.algebra.conformal import EUCLIDEAN, up, weight
from cgamesh.geometry.objects import point_pair_endpoints
from cgamesh.geometry.projection import project
from cgamesh.geometry.surface import MIN_MARGIN, SCAN_SAMPLES_PER_SEGMENT
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.meshing.ribbons import PairRings, mesh_ribbon_surface
from cgamesh.meshing.scene_batch.projection_scan import exactly_projectable


def _pair_rings(blades, derivatives, row_origin, row_scale):
    """PairRings.from_projection of rows (R,), each in its own surface's frame: a, b, da, db (R, 3)."""
    a, b = point_pair_endpoints(blades)
    ends = np.stack([a, b], axis=1)
    omega = products.geometric(blades, derivatives, (2,), (2,), (2,))
    moved = products.inner(up(ends), omega[:, None, :], (1,), (2,))
    velocity = row_scale[:, None, None] * (moved[..., EUCLIDEAN] - weight(moved)[..., None] * ends)
    return (row_origin + row_scale[:, None] * a, row_origin + row_scale[:, None] * b,
            velocity[:, 0], velocity[:, 1])


def mesh_ribbon_group(surfaces, around: int, along: int, closed: bool) -> list[SurfaceMesh | None]:
    """The meshes of ``mesh_ribbon_surface(surface, around, along, closed=closed)`` for built
    point-pair surfaces sharing one curve, or None for a surface left to the per-surface path."""
    count = len(surfaces)
    results: list[SurfaceMesh | None] = [None] * count
    # the scalar projection (four-vector free interpolants) is left to the per-surface path
    fit = np.array([s for s, surface in enumerate(surfaces) if not surface.four_vector_free], dtype=np.intp)
    if fit.size == 0:
        return results
    curve = surfaces[fit[0]].curve
    controls = np.stack([surfaces[s].controls for s in fit])  # (F, n, 32)
    # check_projection_exists() on its own dense grid, as mesh_ribbon_surface calls it, decided
    # bit for bit for all surfaces at once; a surface it refuses is meshed alone (which names why)
    dense = np.linspace(0.0, curve.segment_count, SCAN_SAMPLES_PER_SEGMENT * curve.segment_count + 1)
    scanned = exactly_projectable(curve, dense, controls, grade=2)
    fit, controls = fit[scanned], controls[scanned]
    if fit.size == 0:
        return results
    t = np.linspace(0.0, curve.segment_count, along)
    n = controls.shape[1]
    basis = curve.basis(t)
    rows = np.repeat(np.arange(len(fit)), along)
    # Basis.evaluate of every surface: the same weights on each surface's controls
    picked = controls.reshape(-1, 32)[np.tile(basis.indices, (len(fit), 1)) + (rows * n)[:, None]]
    weights = np.tile(basis.weights, (len(fit), 1))
    rates = np.tile(basis.derivatives, (len(fit), 1))
    interpolant = np.einsum("ak,akm->am", weights, picked)
    derivative = np.einsum("ak,akm->am", rates, picked)
    row_origin = np.array([surfaces[s].frame.origin for s in fit], dtype=np.float64)[rows]
    row_scale = np.array([surfaces[s].frame.scale for s in fit], dtype=np.float64)[rows]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        projection = project(interpolant, derivative, 2, np.tile(basis.weight_sum(), len(fit)))
        a, b, da, db = _pair_rings(projection.blades, projection.derivatives, row_origin, row_scale)
    good = (projection.margin >= MIN_MARGIN) & np.isfinite(a).all(axis=1) & np.isfinite(b).all(axis=1)
    good &= np.isfinite(da).all(axis=1) & np.isfinite(db).all(axis=1)
    good = good.reshape(len(fit), along).all(axis=1)
    for row, s in enumerate(fit):
        if not good[row]:
            continue
        part = slice(row * along, (row + 1) * along)
        rings = PairRings(a[part], b[part], da[part], db[part])
        try:
            results[s] = mesh_ribbon_surface(surfaces[s], around, along, closed=closed, t=t, rings=rings)
        except CgameshError:
            continue  # meshed again alone, which names the error
    return results
