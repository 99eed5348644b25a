"""Rings, normals, UVs and faces of many motor tubes at once (meshing.circles, batched).

For every chain of ``ChainMotions`` the rings sit where the per-chain mesher puts them
(``np.linspace(0, spans, along)``, reproduced with linspace's own arithmetic), are read out of
the same circle blades (``motor_surface.circle_blades``, ``objects.circle_euclidean``) in the
chain's local frame, carried by the same TRS rotations (a segmented Hillis-Steele scan whose
products per ring are those of the per-chain scan), and get the same trigonometric normal
field (``circles.RingNormals``, ``normals.unit_normals``), outward choice, faces and UVs.
What the per-chain mesher repairs one chain at a time (stationary rings, folds, vanishing
normals, an outward sum too close to zero to trust its estimate) marks the chain ``fallback``:
the caller meshes it through the per-chain path.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cgamesh.meshing import normals as normal_field
from cgamesh.meshing.batch_pass.circle_rows import CircleRows
from cgamesh.meshing.batch_pass.motions import ChainMotions
from cgamesh.meshing.ring_frames import transported_axes
from cgamesh.meshing.circles import (DISTINCT_RING_FRACTION, FOLD_AGREEMENT, NEAR_ZERO_FRACTION, OUTWARD_TRUST, STATIONARY_FRACTION,
                                     RingNormals, fold_screen, frame_values, ring_steps, turned_pairs)


@dataclass(frozen=True)
class _RingFrames:
    """Each ring's working-frame scale, shaped (K, 1, 1) to divide a (K, n, 3) velocity, as
    ``RingNormals.of`` divides by one surface's ``frame.scale``."""

    scale: np.ndarray


@dataclass(frozen=True)
class _BladeRings:
    """Circles of many rings in world units (what ``RingNormals.of`` reads): the circles read out of the circle blades, as the per-chain path reads them
    (``CircleRings``: centre, normal and radius from C, velocity X . (C dC/dt)), a frame per ring."""

    centre: np.ndarray
    normal: np.ndarray
    radius: np.ndarray
    omega: np.ndarray  # (10, K) bivector rows (circle_rows)
    origin: np.ndarray
    scale: np.ndarray

    @classmethod
    def of(cls, state, origin, scale) -> "_BladeRings":
        circles = CircleRows.of(state)
        centre, normal, radius = circles.euclidean()
        return cls(origin + scale[:, None] * centre, normal, scale * radius, circles.omega(), origin, scale)

    @property
    def frame(self) -> _RingFrames:
        return _RingFrames(self.scale[:, None, None])

    def velocity(self, points: np.ndarray) -> np.ndarray:
        from cgamesh.geometry.surface import carried_velocity

        scale = self.scale[:, None, None]
        local = np.subtract(points, self.origin[:, None, :])
        local /= scale
        velocity = carried_velocity(self.omega, local)
        velocity *= scale  # in place: the same products as scale * velocity
        return velocity


@dataclass(frozen=True)
class TubeArrays:
    """The tubes of the chains not marked ``fallback``, chain after chain.

    positions, normals (V, 3); uvs (V, 2); faces (F, 3) int32, indices local to each chain, in
    (F / (2 around)) rows of 2 around triangles, one row per pair of consecutive rings;
    ring_chain (R,), ring_local (R,) the chain of each kept ring and its index within its chain
    (a ring's around + 1 vertices are consecutive); face_counts (C,) triangles per chain;
    uv_lengths (C, 2) per chain (circumference, length); fallback (C,) chains left to the
    per-chain path (they have no vertices here).
    """

    positions: np.ndarray
    normals: np.ndarray
    uvs: np.ndarray
    faces: np.ndarray
    ring_chain: np.ndarray
    ring_local: np.ndarray
    face_counts: np.ndarray
    uv_lengths: np.ndarray
    fallback: np.ndarray


def _linspace_parameters(spans: np.ndarray, along: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """t of every ring (``np.linspace(0, spans, along)`` per chain, bit for bit) and its chain."""
    chain = np.repeat(np.arange(len(along)), along)
    first = np.concatenate([[0], np.cumsum(along)[:-1]])
    k = (np.arange(int(along.sum())) - first[chain]).astype(np.float64)
    step = spans.astype(np.float64) / (along - 1)
    t = k * step[chain]
    t[first + along - 1] = spans
    return t, chain


def _coincident_rings(rings: _BladeRings, ring_chain: np.ndarray, chains: int) -> np.ndarray:
    """(C,) chains of which ``circles.distinct_rings`` would leave a ring out, or find none to
    mesh (consecutive rings within DISTINCT_RING_FRACTION of the chain's size, as after a step
    of 1e-7 of the radius): the per-chain path drops those rings or reports the chain. Its
    step, elementwise on the same circles, so the same decision."""
    step = ring_steps(rings.centre, rings.normal, rings.radius, rings.scale)
    close = (ring_chain[1:] == ring_chain[:-1]) & ~(step > DISTINCT_RING_FRACTION)
    return np.bincount(ring_chain[1:][close], minlength=chains) > 0


def _padded_rows(first: np.ndarray, count: np.ndarray):
    """Per-chain rows for row-wise numpy reductions, grouped by length class so
    padding stays under 2x: yields (chains, local index grid (c, L) or -1, rows (c, L))."""
    lengths_class = np.ceil(np.log2(np.maximum(count, 1))).astype(np.int64)
    # the classes present, ascending: np.unique would import numpy.ma (1.3 MB resident) to look for a mask
    for cls in np.flatnonzero(np.bincount(lengths_class)):
        members = np.flatnonzero(lengths_class == cls)
        width = int(count[members].max())
        grid = first[members][:, None] + np.arange(width)[None, :]
        valid = np.arange(width)[None, :] < count[members][:, None]
        yield members, np.where(valid, grid, -1), valid


def mesh_chains(motions: ChainMotions, origin: np.ndarray, scale: np.ndarray, around: int,
                subdivide: int) -> TubeArrays:
    """Tubes of ``around`` vertices per ring and ``subdivide`` rings between nodes for every chain.

    Each ring's circle, axes and normal field (about 900 bytes a ring) are let go as soon as
    the vertices are made from them, before the faces and UVs: a chunk's scratch is then
    mostly its vertices (cgamesh.budget prices the chunk by it).
    """
    nodes = motions.nodes
    chains = len(nodes.count)
    segments = nodes.count - 1
    along = segments * (subdivide + 1) + 1
    fallback = ~motions.certified
    t, ring_chain = _linspace_parameters(segments, along)
    ring_first = np.concatenate([[0], np.cumsum(along)[:-1]])
    ring_local = np.arange(len(t)) - ring_first[ring_chain]
    segment = np.clip(np.floor(t), 0, segments[ring_chain] - 1).astype(np.int64)
    state = motions.evaluate(nodes.span_first[ring_chain] + segment, t - segment)
    # Read out of the circle blades, as the per-chain path does: the motion's own centre,
    # normal and point velocity are cheaper but round differently (normals up to 4e-10 apart
    # where the normal field is nearly degenerate), and this pass reproduces that path.
    rings = _BladeRings.of(state, origin[ring_chain], scale[ring_chain])
    del state, segment

    u, v = transported_axes(rings.normal, ring_local)
    fallback |= _coincident_rings(rings, ring_chain, chains)

    field = RingNormals.of(rings, u, v)
    centre, radius = rings.centre, rings.radius
    del rings  # its bivector rows served the velocities
    stationary = field.speed <= STATIONARY_FRACTION * radius
    fallback |= np.bincount(ring_chain[stationary], minlength=chains) > 0

    theta = 2.0 * np.pi * np.arange(around + 1) / around
    circle_basis = np.stack([np.ones_like(theta), np.cos(theta), np.sin(theta)], axis=1)
    placement = np.stack([centre, radius[:, None] * u, radius[:, None] * v], axis=1)
    del u, v
    positions = normal_field.expand(placement, circle_basis)
    del placement
    normals, smallest, near_zero = normal_field.unit_normals(field.raw, theta, field.speed, NEAR_ZERO_FRACTION)
    fallback |= np.bincount(ring_chain[near_zero[0]], minlength=chains) > 0

    # circles._continuous_signs: only the sign-free case stays here
    suspicious, agreement = fold_screen(field, smallest, theta)
    if np.any(suspicious):
        near = np.flatnonzero(suspicious)
        values = frame_values(field.frame[near], theta, field.speed[near])
        unit = normal_field.unit_rows(values)
        folds = normal_field.unit_reversals(unit)
        fallback |= np.bincount(ring_chain[near[folds.any(axis=1)]], minlength=chains) > 0
        row_of = np.full(len(t), -1)
        row_of[near] = np.arange(len(near))
        pairs = np.flatnonzero((row_of[:-1] >= 0) & (row_of[1:] >= 0))
        agreement[pairs] = np.einsum("kmc,kmc->k", unit[row_of[pairs]], unit[row_of[pairs + 1]]) / len(theta)
        del values, unit
    within = ring_chain[:-1] == ring_chain[1:]
    fallback |= np.bincount(ring_chain[:-1][within & (agreement < -FOLD_AGREEMENT)], minlength=chains) > 0
    examined = np.bincount(ring_chain[suspicious], minlength=chains) > 0

    # circles._outward_sum: the seven-sample estimate, or the sum over every vertex
    cosine = field.frame[..., 0] @ normal_field.trig_basis(normal_field.SAMPLE_ANGLES).T
    sample_lengths = np.linalg.norm(field.sample_normals, axis=-1)
    # the UVs' steps along each chain (uv.along_lengths) from the sample points
    sample_steps = np.linalg.norm(np.diff(field.samples, axis=0), axis=-1).mean(axis=-1)
    del field  # the normal field's coefficients and samples: nothing below reads them
    # a zero sample normal is on a stationary ring, whose chain went to the per-chain path above
    cosine = np.divide(cosine, sample_lengths, out=np.zeros_like(cosine), where=sample_lengths > 0.0)
    estimate = np.bincount(ring_chain, weights=cosine.mean(axis=1) * radius, minlength=chains)
    radius_sum = np.bincount(ring_chain, weights=radius, minlength=chains)
    trusted = ~examined & (np.abs(estimate) >= OUTWARD_TRUST * radius_sum)
    # a sum within rounding of the trust threshold could go either way: the per-chain path decides
    fallback |= ~examined & (np.abs(np.abs(estimate) - OUTWARD_TRUST * radius_sum) <= 1e-9 * radius_sum)
    outward = np.einsum("kmi,kmi->k", normals, positions - centre[:, None, :])
    full = np.bincount(ring_chain, weights=outward, minlength=chains)
    total = np.where(trusted, estimate, full)
    fallback |= np.abs(total) <= 1e-9 * radius_sum * (around + 1)  # a sign too close to call
    flip = total < 0.0
    normals[flip[ring_chain]] *= -1.0

    positions[:, -1] = positions[:, 0]
    normals[:, -1] = normals[:, 0]
    columns = around + 1

    # UVs (uv.along_lengths, normalised, mean_along) per chain, row-wise reductions
    travelled = np.zeros(len(t))
    circumference = np.zeros(chains)
    length = np.zeros(chains)
    ring_circ = 2.0 * np.pi * radius
    for members, grid, valid in _padded_rows(ring_first, along):
        step_rows = np.where(valid[:, 1:], sample_steps[np.maximum(grid[:, 1:], 1) - 1], 0.0)
        cumulative = np.concatenate([np.zeros((len(members), 1)), np.cumsum(step_rows, axis=1)], axis=1)
        travelled[grid[valid]] = cumulative[valid]
        last = cumulative[np.arange(len(members)), along[members] - 1]
        length[members] = last
        travelled_rows = cumulative
        # uv.mean_along: numpy's pairwise sum depends on the row's length, so rows of one length at a time
        for width in np.flatnonzero(np.bincount(along[members])):  # the lengths present, ascending
            same = np.flatnonzero(along[members] == width)
            rows = grid[same, :width]
            c = ring_circ[rows]
            trapezoid = 0.5 * (c[:, 1:] + c[:, :-1]) * np.diff(travelled_rows[same, :width], axis=1)
            circumference[members[same]] = np.sum(trapezoid, axis=1) / np.where(last[same] > 0.0, last[same], 1.0)
    fallback |= ~(length > 0.0)
    v_coordinate = travelled / np.where(length > 0.0, length, 1.0)[ring_chain]

    # vertices of the kept chains, chain after chain (views of the whole grid when every chain is kept)
    keep_ring = ~fallback[ring_chain]
    kept_rings = np.flatnonzero(keep_ring)
    if len(kept_rings) < len(t):
        positions, normals, v_coordinate = positions[kept_rings], normals[kept_rings], v_coordinate[kept_rings]
    uvs = np.empty((len(kept_rings), columns, 2))
    uvs[:, :, 0] = np.linspace(0.0, 1.0, columns)[None, :]
    uvs[:, :, 1] = v_coordinate[:, None]

    # faces: circles._wound_grid per chain, local indices; strips by a turning ring or turned apart by geometry
    pair = np.flatnonzero(keep_ring[:-1] & within)  # ring k and k + 1 of one kept chain
    swap = flip[ring_chain[pair]]
    j = np.arange(columns - 1, dtype=np.int32)
    row = np.empty((columns - 1, 2, 3), dtype=np.int32)
    row[:, 0, 0], row[:, 0, 1], row[:, 0, 2] = j, j + 1, j + columns
    row[:, 1, 0], row[:, 1, 1], row[:, 1, 2] = j + 1, j + columns + 1, j + columns
    row = row.reshape(1, -1, 3)
    faces = np.where(swap[:, None, None], row[:, :, [0, 2, 1]], row)  # (P, 2 (columns-1), 3)
    faces += (ring_local[pair] * columns).astype(np.int32)[:, None, None]
    strip = np.flatnonzero(suspicious[pair] | suspicious[pair + 1] | turned_pairs(agreement)[pair])
    if strip.size:
        # the strip's rings among the kept ones (pairs never span a dropped chain)
        at = np.cumsum(keep_ring) - 1
        _orient_by_geometry(faces, positions, normals, at[pair[strip]], strip, swap[strip])
    face_counts = np.bincount(ring_chain[pair], minlength=chains) * (2 * (columns - 1))
    return TubeArrays(positions.reshape(-1, 3), normals.reshape(-1, 3), uvs.reshape(-1, 2), faces.reshape(-1, 3),
                      ring_chain[kept_rings], ring_local[kept_rings], face_counts,
                      np.stack([circumference, np.where(length > 0.0, length, circumference)], axis=1), fallback)


# Strip pairs oriented by geometry per block: the corner gathers and products of a block stay
# small (about 2 kB a pair at 8 around) however many rings of a chunk turn.
STRIP_BLOCK = 256


def _orient_by_geometry(faces: np.ndarray, positions: np.ndarray, normals: np.ndarray, pair: np.ndarray,
                        rows: np.ndarray, swap: np.ndarray) -> None:
    """Reverses, in place, the triangles of ``faces[rows]`` (rows of the pairs of rings ``pair``,
    ``pair + 1`` of the (R, columns, 3) grids) whose geometric normal points against the sum of
    their vertex normals (``_against_normals``), a block of pairs at a time."""
    for start in range(0, len(rows), STRIP_BLOCK):
        block = slice(start, start + STRIP_BLOCK)
        against = _against_normals(positions, normals, pair[block], swap[block]).reshape(len(rows[block]), -1)
        strip_faces = faces[rows[block]]
        strip_faces[against] = strip_faces[against][:, [0, 2, 1]]
        faces[rows[block]] = strip_faces


def _against_normals(positions: np.ndarray, normals: np.ndarray, pair: np.ndarray, swap: np.ndarray) -> np.ndarray:
    """``circles.orient_by_geometry``'s test on the triangles between rings ``pair`` and
    ``pair + 1`` ((R, columns, 3) grids): (S, columns - 1, 2) True where a triangle's geometric
    normal points against the sum of its vertex normals. The corners come from slices of the
    ring grid instead of gathers by index, each triangle's normals summed in its own corner
    order (``swap``: wound the other way, corners (first, third, second)), so the sums are those
    of orient_by_geometry, bit for bit. A swapped triangle's geometric normal is the other's
    negated, exactly (cross(c, b) = -cross(b, c) in floating point too), so one cross product
    serves both windings and the test flips to > 0: no gathers of rows by winding.
    """
    here, there = positions[pair], positions[pair + 1]
    n_here, n_there = normals[pair], normals[pair + 1]
    # the edge from ring k to ring k + 1 at column j is triangle 0's (third - first) at j and
    # triangle 1's (second - first) at j - 1: one difference serves both
    across = there - here
    # (first, second, third) corner of triangle 0 (j, j + 1, j + columns) and 1 (j + 1, j + columns + 1,
    # j + columns) of each quad: (second - first, third - first), and the normals at the three corners
    corners = [((here[:, 1:] - here[:, :-1], across[:, :-1]), (n_here[:, :-1], n_here[:, 1:], n_there[:, :-1])),
               ((across[:, 1:], there[:, :-1] - here[:, 1:]), (n_here[:, 1:], n_there[:, 1:], n_there[:, :-1]))]
    out = np.empty((len(pair), positions.shape[1] - 1, 2), dtype=bool)
    swapped = swap[:, None, None]
    for kind, ((ab, ac), (a, b, c)) in enumerate(corners):
        geometric = _cross(ab, ac).reshape(-1, 3)
        if not swap.any():  # one winding for every triangle (the usual case): no selection
            summed = (a + b) + c
        elif swap.all():
            summed = (a + c) + b
        else:
            summed = (a + np.where(swapped, c, b)) + np.where(swapped, b, c)
        dot = np.einsum("ti,ti->t", geometric, summed.reshape(-1, 3)).reshape(len(pair), -1)
        if not swap.any():
            np.less(dot, 0.0, out=out[:, :, kind])
        else:
            out[:, :, kind] = np.where(swap[:, None], dot > 0.0, dot < 0.0)
    return out


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.cross(a, b)`` of (..., 3) arrays, its products and differences in its order (so its
    bits), into one C-ordered output without its copies of the operands."""
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    scratch = np.empty(out.shape[:-1])
    for k, (i, j) in enumerate(((1, 2), (2, 0), (0, 1))):  # out_k = a_i b_j - a_j b_i
        np.multiply(a[..., i], b[..., j], out=out[..., k])
        np.multiply(a[..., j], b[..., i], out=scratch)
        np.subtract(out[..., k], scratch, out=out[..., k])
    return out
