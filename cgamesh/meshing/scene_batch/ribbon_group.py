"""Many blade-interpolated point-pair surfaces (ribbons) of one shape of work sampled as one set of arrays.

A group shares its curve (kind, control count, parameters), closed, vertices across and rulings
along. Each surface is built as the per-surface path builds it (``build_surface``); the
projection scan of ``check_projection_exists`` runs on all of them at once (the quick scan
from the controls' products, ``projection_scan.surely_projectable``, then for the surfaces it
cannot vouch for ``exactly_projectable``, which decides as it does, bit for bit); then the
interpolants of every ruling of every surface, their projections (section 6), end points
(eq. 5) and end-point velocities (eqs. 19-20) are computed once over all S K rows, with the
operations ``EvolvedSurface.sample`` and ``ribbons.PairRings.from_projection`` apply to each
row (products.geometric and inner compute a row alone as in a batch; everything else is
row-wise), so the rings are the same bits. Surfaces
whose rulings need none of the ribbon mesher's repairs (``_plain_surfaces``) take their normals,
signs and vertices as one set of arrays too (``_common_meshes``); the others run the rest of
``ribbons.mesh_ribbon_surface`` on their slice of the rings.

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
from cgamesh.meshing import ribbons
from cgamesh.meshing import uv as uv_map
from cgamesh.meshing.circles import drop_zero_area
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.meshing.normals import expand
from cgamesh.meshing.ribbons import PairRings, mesh_ribbon_surface
from cgamesh.meshing.scene_batch.projection_scan import exactly_projectable, surely_projectable


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
    scanned = surely_projectable(curve, dense, controls, grade=2)
    doubtful = np.flatnonzero(~scanned)
    if doubtful.size:
        scanned[doubtful] = exactly_projectable(curve, dense, controls[doubtful], grade=2)
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
    # Rows of surfaces found unfit are overwritten by a fit surface's (in place, keeping every
    # array's layout), so the common steps below meet no NaN; their meshes are not kept.
    if good.any() and not good.all():
        bad = (np.flatnonzero(~good)[:, None] * along + np.arange(along)).ravel()
        donor = np.tile(np.flatnonzero(good)[0] * along + np.arange(along), int(np.count_nonzero(~good)))
        for rows_array in (a, b, da, db):
            rows_array[bad] = rows_array[donor]
    plain = good & _plain_surfaces(a, b, da, db, around, along) if good.any() else good
    names = [surfaces[s].name for s in fit]
    common = _common_meshes(a, b, da, db, around, along, closed, plain, names) if plain.any() else {}
    for row, s in enumerate(fit):
        if not good[row]:
            continue
        if plain[row]:
            results[s] = common[row]
            continue
        part = slice(row * along, (row + 1) * along)
        rings = PairRings(a[part], b[part], da[part], db[part])
        try:
            results[s] = mesh_ribbon_surface(surfaces[s], around, along, closed=closed, t=t, rings=rings)
        except CgameshError:
            continue  # meshed again alone, which names the error
    return results


def _ruling_fields(a, b, da, db):
    """ribbons._ruling_normals' first step on rows (R,): d, N_a, N_b (R, 3), the scale (R,), and
    whether each ruling's normal vanishes everywhere (the mesher's nearby-sample repair)."""
    d = b - a
    n_a, n_b = np.cross(d, da), np.cross(d, db)
    length = np.linalg.norm(d, axis=1)
    scale = length * np.maximum(np.linalg.norm(da, axis=1), np.linalg.norm(db, axis=1))
    flat = np.maximum(np.linalg.norm(n_a, axis=1), np.linalg.norm(n_b, axis=1)) <= ribbons.ZERO_FRACTION * scale
    return d, n_a, n_b, scale, flat


def _plain_surfaces(a, b, da, db, around: int, along: int) -> np.ndarray:
    """(F,) bool: surfaces with no ruling whose normal vanishes everywhere and none along which
    the field may reverse (ribbons._may_reverse): their normals need no repair, fold test or
    winding by geometry, and are meshed as one set of arrays (``_common_meshes``)."""
    _, n_a, n_b, _, flat = _ruling_fields(a, b, da, db)
    s = np.linspace(0.0, 1.0, around)
    suspicious = ribbons._may_reverse(n_a, n_b, s[1] - s[0])
    return ~(flat | suspicious).reshape(-1, along).any(axis=1)


NO_ROWS = np.zeros(0, dtype=np.int64)  # plain surfaces: no ring is examined vertex by vertex


def _common_meshes(a, b, da, db, around: int, along: int, closed: bool, plain: np.ndarray, names) -> dict:
    """mesh_ribbon_surface's meshes of the plain surfaces (``_plain_surfaces``), by row of ``plain``:
    the same steps on all their rulings at once (ribbons._continuous_signs without reversing
    rulings, the documented side, positions, ribbons._unit_normals), then faces and UVs per surface."""
    chosen = np.flatnonzero(plain)
    count = len(chosen)
    rows = (chosen[:, None] * along + np.arange(along)).ravel()
    a, b, da, db = a[rows], b[rows], da[rows], db[rows]
    d, n_a, n_b, scale, _ = _ruling_fields(a, b, da, db)
    s = np.linspace(0.0, 1.0, around)
    samples = ribbons._unit(ribbons._ruling_values(n_a, n_b, ribbons._COMPARE_AT, scale))
    by_surface = samples.reshape((count, along) + samples.shape[1:])
    agreement = np.einsum("kmc,kmc->k", np.ascontiguousarray(by_surface[:, :-1]).reshape((-1,) + samples.shape[1:]),
                          np.ascontiguousarray(by_surface[:, 1:]).reshape((-1,) + samples.shape[1:]))
    reversed_ = (agreement < 0.0).reshape(count, along - 1)
    turned = ribbons.turned_pairs(agreement).reshape(count, along - 1)
    flipped = np.cumsum(np.concatenate([np.zeros((count, 1), dtype=bool), reversed_], axis=1), axis=1) % 2 == 1
    signs = np.where(flipped, -1.0, 1.0)
    # the documented side: the raw field d x dx/dt at most vertices
    signs = np.where((signs.sum(axis=1) * around < 0.0)[:, None], -signs, signs).reshape(-1, 1)
    positions = expand(np.stack([a, d], axis=1), np.stack([np.ones_like(s), s], axis=1))
    normals, size_sq = ribbons._unit_normals(n_a, n_b, s, scale, signs)
    positions = positions.reshape(count, along, around, 3)
    normals = normals.reshape(count, along, around, 3)
    size_sq = size_sq.reshape(count, along, around)
    signs = signs.reshape(count, along, 1)
    ends = np.stack([a, 0.5 * (a + b), b], axis=1).reshape(count, along, 3, 3)
    meshes = {}
    for i, row in enumerate(chosen):
        surface_positions, surface_normals = positions[i], normals[i]
        if closed:  # the last ruling is the first one again: same vertices, same normals
            surface_positions[-1] = surface_positions[0]
            surface_normals[-1] = surface_normals[0] * np.sign(
                np.einsum("mc,mc->", surface_normals[-1], surface_normals[0]) or 1.0)
        flat_positions = surface_positions.reshape(-1, 3)
        faces = ribbons.wound_faces(flat_positions, surface_normals.reshape(-1, 3), signs[i], NO_ROWS, along, around,
                                    turned[i])
        faces = drop_zero_area(flat_positions, faces, np.flatnonzero(size_sq[i] <= ribbons.NEAR_ZERO_FRACTION**2))
        uvs = uv_map.grid_uvs(uv_map.along_coordinates(ends[i]), around)
        meshes[row] = SurfaceMesh(name=names[row], positions=flat_positions, normals=surface_normals.reshape(-1, 3),
                                  uvs=uvs, faces=faces, double_sided=True)
    return meshes
