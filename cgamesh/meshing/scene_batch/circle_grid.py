"""Many circle surfaces of one shape of work meshed as one set of arrays.

A group shares its sampler (samplers.py: the curve or motion kind, control count, parameters,
closed), its rings along and vertices around: its S surfaces' K rings each are S K rows, and
every step of ``circles.mesh_circle_surface`` that works ring by ring (the circles and their
rates, read out in each surface's frame, transported frames, the normal field's trigonometric
fits, fold detection on suspicious rings with the rings a step before and after them, vertices,
normals, tangents, UVs, faces and their winding) runs once over all of them, with the same
operations on every row, so each surface's mesh is the per-surface mesher's, bit for bit.
Steps along a surface's rings (the rotation scan, running lengths, cumulative signs, the
outward test) run along a surface axis.

What the per-surface mesher does only for rare surfaces is not batched: a surface whose scan
is not surely clear (an error, or a line to refine), a circle through infinity at a ring,
rings within DISTINCT_RING_FRACTION of each other, a ring that stands still, nearby rings with
no circle, or an outward sum too near zero to trust is reported as not meshed (None), and the
caller meshes it alone.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cgamesh.geometry.algebra.layout import grade_indices
from cgamesh.geometry.algebra import products
from cgamesh.geometry.objects import circle_euclidean
from cgamesh.geometry.surface import carried_velocity
from cgamesh.meshing import normals as normal_field
from cgamesh.meshing.circles import (DISTINCT_RING_FRACTION, FOLD_AGREEMENT, NEAR_ZERO_FRACTION,
                                     OUTWARD_TRUST, STATIONARY_FRACTION, STATIONARY_OFFSET, _grid_weld, _wound_grid,
                                     _add_cap, drop_zero_area, frame_values, ring_steps, turned_pairs)
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.meshing.ring_frames import close_loops, transported_axes

# An outward estimate or sum this close (relative) to its decision threshold is recomputed the
# per-surface way, whose summation order may differ from the batched one in the last bits.
_DECISION_MARGIN = 1e-9


@dataclass(frozen=True)
class _SurfaceRings:
    """One surface's rings (K, 3), (K, 3), (K,) as circles._add_cap reads them."""

    centre: np.ndarray
    normal: np.ndarray
    radius: np.ndarray


def _ring_fields(centre, normal, radius, omega, u, v, row_origin, row_scale):
    """circles.RingNormals.of for rings (R,) of many surfaces (each row's frame origin (R, 3) and
    scale (R,)): the sample points and radial directions (R, 7, 3), velocities, normal samples,
    speeds (R,), and the (zeta, rho) and normal fits (R, 7, 2), (R, 7, 3)."""
    points, radial = normal_field.sample_points(centre, radius, u, v)
    local = (points - row_origin[:, None, :]) / row_scale[:, None, None]
    omega_rows = np.moveaxis(omega[..., grade_indices(2)], -1, 0)  # as CircleRings.velocity takes them
    velocity = (row_scale[:, None, None] * carried_velocity(omega_rows, local)) / row_scale[:, None, None]
    zeta_rho = normal_field.frame_coordinates(velocity, radial, normal)
    sampled = normal_field.normal_samples(zeta_rho, radial, normal)
    speed = np.linalg.norm(velocity, axis=-1).max(axis=1)
    return points, radial, velocity, sampled, speed, normal_field.fit(zeta_rho), normal_field.fit(sampled)


def _circles_at(blades, derivatives, row_origin, row_scale):
    """CircleRings.from_projection, each row in its own surface's frame: centre, normal, radius, omega."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        local_centre, normal, local_radius = circle_euclidean(blades)
        centre = row_origin + row_scale[:, None] * local_centre
        radius = row_scale * local_radius
        omega = products.geometric(blades, derivatives, (3,), (3,), (2,))
    return centre, normal, radius, omega


def _nearby_frames(sampler, surface, t, u, origin, scale):
    """circles._nearby_normals for rows of many surfaces: the (zeta, rho) fits (R, 7, 2) of the rings
    of ``surface`` (R,) at parameters t (R,), their phase carried from axes u (R, 3); and (R,)
    whether they have a circle there (the per-surface sample refuses it otherwise)."""
    blades, derivatives, exists = sampler.at(surface, t)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        row_origin, row_scale = origin[surface], scale[surface]
        centre, normal, radius, omega = _circles_at(blades, derivatives, row_origin, row_scale)
        u = u - np.einsum("ki,ki->k", u, normal)[:, None] * normal
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        fields = _ring_fields(centre, normal, radius, omega, u, np.cross(normal, u), row_origin, row_scale)
    return fields[5], exists


def _distinct(centre, normal, radius, scale) -> np.ndarray:
    """(S,) circles.distinct_rings keeps every ring (centre (S, K, 3), radius (S, K), scale (S,))."""
    return np.all(ring_steps(centre, normal, radius, scale[:, None]) > DISTINCT_RING_FRACTION, axis=1)


def mesh_circle_group(names, sampler, origin: np.ndarray, scale: np.ndarray, closed: bool, around: int,
                      along: int, tangents: bool, caps: np.ndarray | None = None) -> list[SurfaceMesh | None]:
    """The meshes of ``mesh_circle_surface(surface, around, along, caps=caps, closed=closed,
    with_tangents=tangents, distinct=True)`` for the S surfaces of one group (``sampler``, see
    samplers.py; their frames origin (S, 3), scale (S,); caps (S,) bool or None for none), or None
    for a surface left to the per-surface mesher (module doc)."""
    count = len(origin)
    caps = np.zeros(count, dtype=bool) if caps is None else caps
    t = np.linspace(0.0, sampler.segment_count, along)
    ok = sampler.scan_ok(t)
    blades, derivatives, exists = sampler.at(np.repeat(np.arange(count), along), np.tile(t, count))
    ok &= np.all(exists.reshape(count, along), axis=1)
    row_origin = np.repeat(origin, along, axis=0)
    row_scale = np.repeat(scale, along)
    centre, normal, radius, omega = _circles_at(blades, derivatives, row_origin, row_scale)
    ok &= (np.isfinite(centre).all(axis=1) & np.isfinite(radius) & np.isfinite(normal).all(axis=1)).reshape(
        count, along).all(axis=1)
    # Rows of surfaces found unfit are overwritten by a fit surface's (in place: every array keeps
    # the memory layout the per-surface mesher's has, which einsum's order of sums depends on), so
    # nothing below meets their NaNs; their meshes are not kept.
    results: list[SurfaceMesh | None] = [None] * count
    fit = np.flatnonzero(ok)
    if fit.size == 0:
        return results
    unfit = np.flatnonzero(~ok)
    if unfit.size:
        bad = (unfit[:, None] * along + np.arange(along)).ravel()
        donor = np.tile(fit[0] * along + np.arange(along), unfit.size)
        for rows_array in (centre, normal, radius, omega, row_origin, row_scale):
            rows_array[bad] = rows_array[donor]
    by_surface = (count, along)
    fine = ok & _distinct(centre.reshape(by_surface + (3,)), normal.reshape(by_surface + (3,)),
                          radius.reshape(by_surface), scale)

    u, v = transported_axes(normal, np.tile(np.arange(along), count))
    if closed:
        close_loops(u, v, normal, np.tile(t, count), np.arange(count) * along, np.full(count, along))

    points, radial, velocity, sampled, speed, frame, raw = _ring_fields(centre, normal, radius, omega, u, v,
                                                                         row_origin, row_scale)
    fine &= ~np.any((speed <= STATIONARY_FRACTION * radius / row_scale).reshape(by_surface), axis=1)

    theta = 2.0 * np.pi * np.arange(around + 1) / around
    columns = around + 1
    circle_basis = np.stack([np.ones_like(theta), np.cos(theta), np.sin(theta)], axis=1)
    placement = np.stack([centre, radius[:, None] * u, radius[:, None] * v], axis=1)
    positions = normal_field.expand(placement, circle_basis)
    normals, smallest, near_zero = normal_field.unit_normals(raw, theta, speed, NEAR_ZERO_FRACTION)

    # circles._continuous_signs
    suspicious = smallest <= normal_field.derivative_bound(raw) * (theta[1] - theta[0])
    unit_samples = normal_field.unit_rows(sampled).reshape(by_surface + sampled.shape[1:])
    agreement = np.einsum("ksc,ksc->k", np.ascontiguousarray(unit_samples[:, :-1]).reshape((-1,) + sampled.shape[1:]),
                          np.ascontiguousarray(unit_samples[:, 1:]).reshape((-1,) + sampled.shape[1:])
                          ) / sampled.shape[1]
    vertex_signs = np.ones((count * along, columns))
    if np.any(suspicious):
        fine &= _fold_signs(sampler, origin, scale, t, u, frame, speed, theta, suspicious, along, vertex_signs,
                            agreement)
    folds = (agreement < -FOLD_AGREEMENT).reshape(count, along - 1)
    parity = np.concatenate([np.zeros((count, 1), dtype=np.int64), np.cumsum(folds, axis=1)], axis=1) % 2
    signs = vertex_signs.reshape(by_surface + (columns,)) * (1.0 - 2.0 * parity)[..., None]
    turning = suspicious.reshape(by_surface)
    per_vertex = turning.any(axis=1)  # these take the sum over every vertex (one sign per vertex)

    # circles._outward_sum with one sign per ring: the seven-sample estimate, else every vertex
    cosine = frame[..., 0] @ normal_field.trig_basis(normal_field.SAMPLE_ANGLES).T
    with np.errstate(invalid="ignore", divide="ignore"):  # a vanishing sample: only on per-vertex surfaces
        cosine = cosine / np.linalg.norm(sampled, axis=-1)
    mean_cosine = cosine.mean(axis=1).reshape(by_surface) * signs[:, :, 0]
    ring_radius = radius.reshape(by_surface)
    estimate = np.einsum("sk,sk->s", mean_cosine, ring_radius)
    threshold = OUTWARD_TRUST * ring_radius.sum(axis=1)
    trusted = (np.abs(estimate) >= threshold) & ~per_vertex
    unsure = (np.abs(np.abs(estimate) - threshold) <= _DECISION_MARGIN * threshold) & ~per_vertex
    for s in np.flatnonzero(unsure & fine):  # float64 dot's own sums, as the per-surface mesher
        estimate[s] = float(mean_cosine[s] @ ring_radius[s])
        trusted[s] = abs(estimate[s]) >= threshold[s]
    outward = estimate
    if not trusted.all():
        shape = by_surface + (columns,)
        every = np.einsum("kmi,kmi->km", normals, positions - centre[:, None, :]).reshape(shape) * signs
        totals = every.reshape(count, -1).sum(axis=1)
        outward = np.where(trusted, estimate, totals)
    fine &= ~(np.abs(outward) <= _DECISION_MARGIN * threshold)
    signs = np.where(outward[:, None, None] < 0.0, -signs, signs)

    normals *= signs.reshape(-1, columns)[:, :, None]
    tangent_grid = None
    if tangents:
        circle_tangent = normal_field.expand(np.stack([u, v], axis=1),
                                             np.stack([-np.sin(theta), np.cos(theta)], axis=1))
        tangent_grid = np.concatenate(
            [circle_tangent, signs.reshape(-1, columns)[:, :, None]], axis=-1)
        tangent_grid = tangent_grid.reshape(by_surface + (columns, 4))
        tangent_grid[:, :, -1] = tangent_grid[:, :, 0]
        if closed:
            tangent_grid[:, -1] = tangent_grid[:, 0]
    positions = positions.reshape(by_surface + (columns, 3))
    normals = normals.reshape(by_surface + (columns, 3))
    positions[:, :, -1] = positions[:, :, 0]
    normals[:, :, -1] = normals[:, :, 0]
    if closed:
        positions[:, -1] = positions[:, 0]
        normals[:, -1] = normals[:, 0]

    # UVs: arc length along each surface's rings (uv.along_lengths, normalised, mean_along)
    samples = points.reshape(by_surface + points.shape[1:])
    steps = np.linalg.norm(np.diff(samples, axis=1), axis=-1).mean(axis=-1)
    travelled = np.concatenate([np.zeros((count, 1)), np.cumsum(steps, axis=1)], axis=1)
    length = travelled[:, -1]
    moving = length > 0.0
    v_coordinate = np.where(moving[:, None], travelled / np.where(moving, length, 1.0)[:, None],
                            np.linspace(0.0, 1.0, along)[None, :])
    girth = 2.0 * np.pi * ring_radius
    spans = np.ascontiguousarray(0.5 * (girth[:, 1:] + girth[:, :-1]) * np.diff(travelled, axis=1))
    circumference = np.where(moving, spans.sum(axis=1) / np.where(moving, length, 1.0), girth.mean(axis=1))
    u_coordinate = np.linspace(0.0, 1.0, columns)
    uvs = np.empty(by_surface + (columns, 2))
    uvs[..., 0] = u_coordinate
    uvs[..., 1] = v_coordinate[:, :, None]

    faces = _grid_faces(signs, along, columns)
    strips = turning[:, :-1] | turning[:, 1:] | turned_pairs(agreement).reshape(count, along - 1)
    if np.any(strips):
        _orient_strips(faces, positions.reshape(count, -1, 3), normals.reshape(count, -1, 3), strips, around)
    weld = _grid_weld(along, around, closed)
    vertex_count = along * columns
    near_ring = near_zero[0] // along if near_zero[0].size else np.empty(0, np.intp)
    ring_shape = by_surface + (3,)
    for s in np.flatnonzero(fine):
        flat_positions = positions[s].reshape(-1, 3)
        mine = near_ring == s
        surface_faces = faces[s]
        if np.any(mine):
            ring = near_zero[0][mine] - s * along
            surface_faces = drop_zero_area(flat_positions, surface_faces, ring * columns + near_zero[1][mine])
        girth_s = float(circumference[s])
        parts = [flat_positions, normals[s].reshape(-1, 3), uvs[s].reshape(-1, 2), surface_faces,
                 None if tangent_grid is None else tangent_grid[s].reshape(-1, 4),
                 np.broadcast_to([girth_s, float(length[s]) if moving[s] else girth_s], (vertex_count, 2)),
                 weld.copy()]
        if caps[s]:  # the per-surface mesher's discs, on this surface's rings
            rings = _SurfaceRings(centre.reshape(ring_shape)[s], normal.reshape(ring_shape)[s], ring_radius[s])
            surface_u = u.reshape(ring_shape)[s]
            leaving = np.sign(frame[[s * along, s * along + along - 1], 0, 0]) * np.array([-1.0, 1.0])
            leaving[leaving == 0.0] = np.array([-1.0, 1.0])[leaving == 0.0]
            for ring, facing in zip((0, along - 1), leaving):
                parts = _add_cap(*parts, rings, surface_u, ring, columns, around, theta[:-1], facing)
        flat_positions, flat_normals, flat_uvs, surface_faces, flat_tangents, lengths, surface_weld = parts
        results[s] = SurfaceMesh(name=names[s], positions=flat_positions, normals=flat_normals, uvs=flat_uvs,
                                 faces=surface_faces, tangents=flat_tangents, uv_lengths=lengths, weld=surface_weld)
    return results


def _fold_signs(sampler, origin, scale, t, u, frame, speed, theta, suspicious, along, vertex_signs,
                agreement) -> np.ndarray:
    """circles._continuous_signs for the suspicious rings of many surfaces: fills their rows of
    vertex_signs (S K, M) and the agreement (S (K - 1),) of consecutive suspicious rings; returns
    (S,) whether each surface's nearby rings could be sampled (else the per-surface path refuses)."""
    columns = len(theta)
    fine = np.ones(len(origin), dtype=bool)
    near = np.flatnonzero(suspicious)
    values = frame_values(frame[near], theta, speed[near])
    folds = normal_field.reversals(values)
    if np.any(folds):
        row, column = np.nonzero(folds)
        ring = near[row]
        surface, at = ring // along, t[ring % along]
        before_t = np.maximum(at - STATIONARY_OFFSET, 0.0)
        after_t = np.minimum(at + STATIONARY_OFFSET, sampler.segment_count)
        count = len(ring)
        nearby, sampled = _nearby_frames(sampler, np.concatenate([surface, surface]),
                                         np.concatenate([before_t, after_t]), np.concatenate([u[ring], u[ring]]),
                                         origin, scale)
        fine[np.concatenate([surface, surface])[~sampled]] = False
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            sines = normal_field.fold_sines(frame[ring], nearby[:count], nearby[count:], after_t - before_t,
                                            theta[column], theta[column + 1])
        folds[row, column] = sines <= normal_field.FOLD_SINE
    near_signs = normal_field.ring_signs(folds)
    vertex_signs[near] = near_signs
    row_of = np.full(len(suspicious), -1)
    row_of[near] = np.arange(len(near))
    unit = normal_field.unit_rows(values) * near_signs[..., None]
    ring_index = np.arange(len(suspicious) - 1)
    pairs = np.flatnonzero((row_of[:-1] >= 0) & (row_of[1:] >= 0) & (ring_index % along != along - 1))
    agreement[pairs - pairs // along] = np.einsum("kmc,kmc->k", unit[row_of[pairs]], unit[row_of[pairs + 1]]) / columns
    return fine


def _grid_faces(signs: np.ndarray, along: int, columns: int) -> np.ndarray:
    """circles.grid_faces of every surface: signs (S, K, M) -> faces (S, 2 (K-1)(M-1), 3) int32."""
    count = len(signs)
    here, right, below, across = signs[:, :-1, :-1], signs[:, :-1, 1:], signs[:, 1:, :-1], signs[:, 1:, 1:]
    flipped = np.stack([here + right + below < 0.0, right + across + below < 0.0], axis=3)
    majority = 2 * np.count_nonzero(flipped.reshape(count, -1), axis=1) > flipped[0].size
    faces = np.empty((count, along - 1, columns - 1, 2, 3), dtype=np.int32)
    faces[~majority] = _wound_grid(along, columns, flip=False)
    faces[majority] = _wound_grid(along, columns, flip=True)
    minority = np.where(majority[:, None, None, None], ~flipped, flipped)
    if np.any(minority):
        faces[minority] = faces[minority][:, [0, 2, 1]]
    return faces.reshape(count, -1, 3)


def _orient_strips(faces, positions, normals, strip, around) -> None:
    """circles.orient_by_geometry on the triangles of the strips between rings next to a turning
    ring or turned apart, in place: faces (S, F, 3) of positions and normals (S, V, 3); strip
    (S, K - 1) bool."""
    surface, triangle = np.nonzero(np.repeat(strip, 2 * around, axis=1))
    picked = faces[surface, triangle]
    first = positions[surface, picked[:, 0]]
    geometric = np.cross(positions[surface, picked[:, 1]] - first, positions[surface, picked[:, 2]] - first)
    summed = normals[surface, picked[:, 0]] + normals[surface, picked[:, 1]] + normals[surface, picked[:, 2]]
    against = np.einsum("ti,ti->t", geometric, summed) < 0.0
    faces[surface[against], triangle[against]] = picked[against][:, [0, 2, 1]]
