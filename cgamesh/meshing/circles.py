"""Meshing evolved circle surfaces by TRS-rotor stepping (paper section 11).

The first ring is the unit circle's points carried to C(0) by the TRS rotor Z_0 = T D R_0;
each following ring is the previous one carried by the TRS rotor from C(t_k) to C(t_{k+1}).
Translation and dilation of that rotor are fixed by the two circles' centres and radii; its
rotation R_k is the smallest rotation between their planes, and only the rotations
accumulate (``transported_frames``). So ring k's points are

    x_kj = c_k + r_k (cos theta_j u_k + sin theta_j v_k),   u_k = (R_k ... R_1 R_0) e1,

which is the sandwich Z X ~Z of the composed rotors evaluated as the similarity it is.
Centre and radius are read from C(t_k) itself at every ring, so no error accumulates in
them, and u_k is re-orthogonalised against the exact plane: vertices stay on their circles
to rounding at any step count. The (t, theta) grid is triangulated directly; its seam
column and, for closed loops, its last ring repeat the first bit for bit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cgamesh.meshing import normals as normal_field
from cgamesh.meshing import uv as uv_map
from cgamesh.errors import DegenerateGeometryError
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.meshing.ring_frames import transported_frames
from cgamesh.geometry.surface import CircleRings, EvolvedSurface

# A ring moving slower than this fraction of its radius per unit alpha is stationary (e.g. a
# Kochanek-Bartels control with tension 1): its normals come from just past it.
STATIONARY_FRACTION = 1e-9
STATIONARY_OFFSET = 1e-6
# Triangles next to vertices where the normal field vanishes are checked for zero area.
NEAR_ZERO_FRACTION = 1e-6
# Consecutive rings whose normals agree less than this (mean cosine below minus it) lie on
# the two sides of a fold.
FOLD_AGREEMENT = 0.9
# Consecutive rings whose normals (after any fold's flip) are on average more than a right angle
# apart are too far apart for the field's orientation to tell the winding of the triangles
# between them (the chord need not run along d/dt): those are wound by their own geometry.
TURNED_AGREEMENT = 0.0
# The seven-sample estimate of the outward sum decides its sign when the mean |cosine| between
# normals and radial directions is at least this.
OUTWARD_TRUST = 0.25
# Consecutive rings whose vertices all lie within this fraction of the surface's size of each
# other are one ring (float32, as output files store positions, resolves about 6e-8).
DISTINCT_RING_FRACTION = 1e-6


@dataclass(frozen=True)
class RingNormals:
    """The normal field of each ring as trigonometric polynomials in theta.

    frame: (K, 7, 2) coefficients of (zeta, rho); raw: (K, 7, 3) coefficients of N in world
    axes; speed: (K,) the ring's largest velocity (in the surface's working units, world / frame
    scale); samples: (K, 7, 3) points at the sample
    angles; sample_normals: (K, 7, 3) N there.
    """

    frame: np.ndarray
    raw: np.ndarray
    speed: np.ndarray
    samples: np.ndarray
    sample_normals: np.ndarray

    @classmethod
    def of(cls, rings: CircleRings, u: np.ndarray, v: np.ndarray) -> "RingNormals":
        points, radial = normal_field.sample_points(rings.centre, rings.radius, u, v)
        # In the surface's working units (world / frame scale): a tube 1e-300 or 1e300 across
        # has normals whose squared lengths neither underflow nor overflow.
        velocity = rings.velocity(points)  # a fresh array, divided in place
        velocity /= rings.frame.scale
        zeta_rho = normal_field.frame_coordinates(velocity, radial, rings.normal)
        sampled = normal_field.normal_samples(zeta_rho, radial, rings.normal)
        speed = normal_field.row_lengths(velocity).max(axis=1)
        return cls(normal_field.fit(zeta_rho), normal_field.fit(sampled), speed, points, sampled)

    def replace_rings(self, which: np.ndarray, other: "RingNormals") -> "RingNormals":
        """These normals with the rings ``which`` (bool (K,)) taken from ``other`` (one row each)."""
        fields = {}
        for name in ("frame", "raw", "speed", "sample_normals"):
            mine = getattr(self, name).copy()
            mine[which] = getattr(other, name)
            fields[name] = mine
        return RingNormals(samples=self.samples, **fields)


def _refuse_lines(rings: CircleRings, t: np.ndarray, segment_count: int) -> None:
    """DegenerateGeometryError where an interpolated circle is a line (its centre and radius at
    infinity: blade interpolation between controls of opposite orientation, align false)."""
    line = ~(np.isfinite(rings.centre).all(axis=1) & np.isfinite(rings.radius))
    if np.any(line):
        from cgamesh.geometry.curves import split_parameter

        segment, alpha = split_parameter(t[np.flatnonzero(line)[:1]], segment_count)
        raise DegenerateGeometryError(
            f"the interpolated circle is a line (through infinity) at segment {int(segment[0])}, "
            f"alpha = {float(alpha[0]):.3g}; controls of opposite orientation interpolate through one "
            "(align: true turns them alike)")


def _nearby_normals(surface: EvolvedSurface, t: np.ndarray, u: np.ndarray) -> RingNormals:
    """Normals of the rings at parameters t (R,), their phase carried from axes u (R, 3) nearby."""
    rings = CircleRings.from_projection(surface.sample(t), surface.frame)
    u = u - np.einsum("ki,ki->k", u, rings.normal)[:, None] * rings.normal
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    return RingNormals.of(rings, u, np.cross(rings.normal, u))


def _step_inside(surface: EvolvedSurface, t: np.ndarray, sign: float) -> np.ndarray:
    """t + sign * STATIONARY_OFFSET, or the other way where that would leave the curve."""
    moved = t + sign * STATIONARY_OFFSET
    return np.where((moved >= 0.0) & (moved <= surface.segment_count), moved, t - sign * STATIONARY_OFFSET)


def _ring_normals(surface: EvolvedSurface, t: np.ndarray, rings: CircleRings, u: np.ndarray,
                  v: np.ndarray) -> RingNormals:
    """Normals of every ring; a ring that does not move takes the field from just past it."""
    field = RingNormals.of(rings, u, v)
    stationary = field.speed <= STATIONARY_FRACTION * rings.radius / rings.frame.scale  # both in working units
    if not np.any(stationary):
        return field
    nearby = _nearby_normals(surface, _step_inside(surface, t[stationary], 1.0), u[stationary])
    return field.replace_rings(stationary, nearby)


def _continuous_signs(surface: EvolvedSurface, t: np.ndarray, u: np.ndarray, field: RingNormals,
                      theta: np.ndarray, smallest: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Signs (K, M) making the normal field continuous over the whole (t, theta) grid, which
    rings (K,) bool were examined vertex by vertex (their field may turn fast), and which
    consecutive pairs (K - 1,) bool are turned (``turned_pairs``).

    Only rings whose field can reverse between two columns are examined vertex by vertex:
    elsewhere |N| stays above the most N can change in one column step. A reversal counts
    as a fold (and flips the sign after it) only if ``normal_field.fold_sines`` confirms it,
    from the ring and the same ring a tiny step before and after. Consecutive rings are then
    compared (at the seven sample angles, or at every column where a ring has a reversal) and
    a ring is flipped when its normals are all but opposite to its predecessor's.
    """
    rings, columns = len(smallest), len(theta)
    suspicious, agreement = fold_screen(field, smallest, theta)
    signs = np.ones((rings, columns if np.any(suspicious) else 1))
    if np.any(suspicious):
        near = np.flatnonzero(suspicious)
        values = frame_values(field.frame[near], theta, field.speed[near])
        folds = normal_field.reversals(values)
        if np.any(folds):
            row, column = np.nonzero(folds)
            ring = near[row]
            before_t = np.maximum(t[ring] - STATIONARY_OFFSET, 0.0)
            after_t = np.minimum(t[ring] + STATIONARY_OFFSET, surface.segment_count)
            before, after = _nearby_normals(surface, before_t, u[ring]), _nearby_normals(surface, after_t, u[ring])
            sines = normal_field.fold_sines(field.frame[ring], before.frame, after.frame, after_t - before_t,
                                            theta[column], theta[column + 1])
            folds[row, column] = sines <= normal_field.FOLD_SINE
        signs[near] = normal_field.ring_signs(folds)
        # Pairs of rings next to a reversal are compared at every column.
        row_of = np.full(rings, -1)
        row_of[near] = np.arange(len(near))
        unit = normal_field.unit_rows(values) * signs[near][..., None]
        pairs = np.flatnonzero((row_of[:-1] >= 0) & (row_of[1:] >= 0))
        agreement[pairs] = np.einsum("kmc,kmc->k", unit[row_of[pairs]], unit[row_of[pairs + 1]]) / columns
    # A fold between two rings reverses the field along a line: the rings' normals are then
    # all but opposite. A crease (a joint of a linear or C0 spline) turns them by less, and the
    # field there is simply discontinuous: no flip.
    ring_parity = np.concatenate([[0], np.cumsum(agreement < -FOLD_AGREEMENT)]) % 2
    return signs * (1.0 - 2.0 * ring_parity)[:, None], suspicious, turned_pairs(agreement)


def turned_pairs(agreement: np.ndarray) -> np.ndarray:
    """Consecutive rings (K - 1,) bool whose normals, after a fold's flip (agreement below
    -FOLD_AGREEMENT), still agree less than TURNED_AGREEMENT: the step between them is too
    long for the analytic orientation to wind their triangles (see TURNED_AGREEMENT)."""
    return (agreement < TURNED_AGREEMENT) & (agreement >= -FOLD_AGREEMENT)


def _outward_sum(field: RingNormals, signs: np.ndarray, rings: CircleRings, positions: np.ndarray,
                 normals: np.ndarray) -> float:
    """Sum over vertices of s n . (x - centre) = s r zeta / |N|: positive when the field points out.

    normals: the unit field before the signs (K, 1 or M) are applied. With one sign per ring,
    the seven sample angles estimate each ring's mean of zeta / |N| (a cosine); only when that
    estimate is too near zero to trust its sign (mean |cosine| under OUTWARD_TRUST) is the sum
    taken over every vertex.
    """
    if signs.shape[1] == 1:
        cosine = field.frame[..., 0] @ normal_field.trig_basis(normal_field.SAMPLE_ANGLES).T  # zeta (K, 7)
        cosine = cosine / np.linalg.norm(field.sample_normals, axis=-1)
        estimate = float((cosine.mean(axis=1) * signs[:, 0]) @ rings.radius)
        if abs(estimate) >= OUTWARD_TRUST * rings.radius.sum():
            return estimate
    outward = np.einsum("kmi,kmi->km", normals, positions - rings.centre[:, None, :])
    return float(np.sum(outward * signs))


def fold_screen(field: RingNormals, smallest: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(suspicious (K,): rings whose smallest |N| over the columns is within what |dN/dtheta|
    can change over one column step, so N may vanish between columns; agreement (K - 1,): the
    mean cosine between consecutive rings' normals at the seven sample angles)."""
    suspicious = smallest <= normal_field.derivative_bound(field.raw) * (theta[1] - theta[0])
    unit = normal_field.unit_rows(field.sample_normals)  # each ring's once, for both its pairs
    agreement = np.einsum("ksc,ksc->k", unit[:-1], unit[1:]) / field.sample_normals.shape[1]
    return suspicious, agreement


def frame_values(frame: np.ndarray, theta: np.ndarray, speed: np.ndarray) -> np.ndarray:
    """(zeta, rho) (R, M, 2) at theta, zeros replaced by their limit d/dtheta along the circle."""
    values = normal_field.expand(frame, normal_field.trig_basis(theta))
    zero = np.hypot(values[..., 0], values[..., 1]) <= normal_field.ZERO_FRACTION * speed[:, None]
    if np.any(zero):
        ring, column = np.nonzero(zero)
        values[ring, column] = np.einsum("za,zac->zc", normal_field.trig_basis_derivative(theta[column]),
                                         frame[ring])
    return values


def _apply_signs(normals: np.ndarray, signs: np.ndarray) -> None:
    """normals (K, M, 3) *= signs (K, 1) or (K, M), touching only rings with a negative sign."""
    flipped = np.flatnonzero((signs < 0.0).any(axis=1))
    if flipped.size == len(normals) and signs.shape[1] == 1:  # the whole field turned outward
        np.negative(normals, out=normals)
    elif flipped.size:
        normals[flipped] *= np.broadcast_to(signs, normals.shape[:2])[flipped][..., None]


def grid_faces(rings: int, columns: int, signs: np.ndarray) -> np.ndarray:
    """Triangles (2 (rings-1)(columns-1), 3) int32 of a (rings, columns) vertex grid.

    Quad (k, j) splits into (k,j)(k,j+1)(k+1,j) and (k,j+1)(k+1,j+1)(k+1,j), both wound like
    d/dtheta x d/dt. signs (rings, columns), or broadcastable to it: where the normal field
    is flipped (the sum of a triangle's three vertex signs is negative) the triangle's
    winding is reversed too. The majority's winding is written directly; only the minority
    is reordered afterwards.
    """
    if np.all(signs == signs.flat[0]):  # one sign everywhere (the usual case): nothing to vote on
        flipped = None
        majority_flipped = bool(signs.flat[0] < 0.0)
    else:
        signs = np.broadcast_to(signs, (rings, columns))
        here, right, below, across = signs[:-1, :-1], signs[:-1, 1:], signs[1:, :-1], signs[1:, 1:]
        flipped = np.stack([here + right + below < 0.0, right + across + below < 0.0], axis=2)
        majority_flipped = 2 * np.count_nonzero(flipped) > flipped.size
    faces = _wound_grid(rings, columns, flip=majority_flipped)
    if flipped is not None:
        minority = ~flipped if majority_flipped else flipped
        if np.any(minority):
            faces[minority] = faces[minority][:, [0, 2, 1]]
    return faces.reshape(-1, 3)


def _wound_grid(rings: int, columns: int, flip: bool) -> np.ndarray:
    """Triangles (rings-1, columns-1, 2, 3) int32 of a vertex grid, all wound one way.

    One ring's triangles are written once; every other ring is that row plus the ring's
    first index, a single contiguous pass over the output (the bulk of a mesh's bytes).
    """
    second, third = (2, 1) if flip else (1, 2)
    j = np.arange(columns - 1, dtype=np.int32)
    row = np.empty((columns - 1, 2, 3), dtype=np.int32)
    row[:, 0, 0] = j
    row[:, 0, second] = j + 1
    row[:, 0, third] = j + columns
    row[:, 1, 0] = j + 1
    row[:, 1, second] = j + columns + 1
    row[:, 1, third] = j + columns
    faces = np.empty((rings - 1, (columns - 1) * 6), dtype=np.int32)
    np.add(row.reshape(1, -1), np.arange(rings - 1, dtype=np.int32)[:, None] * np.int32(columns), out=faces)
    return faces.reshape(rings - 1, columns - 1, 2, 3)


def orient_by_geometry(faces: np.ndarray, positions: np.ndarray, normals: np.ndarray,
                       which: np.ndarray) -> np.ndarray:
    """Wind the triangles ``which`` (F,) bool counter-clockwise seen from their vertex normals.

    A triangle straddling a fold spans two sheets of the parametrisation, and no vote of its
    vertices' signs tells its winding; its own geometric normal against the sum of its vertex
    normals does.
    """
    every = bool(np.all(which))
    chosen = None if every else np.flatnonzero(which)
    if not every and chosen.size == 0:
        return faces
    picked = faces if every else faces[chosen]
    # corner by corner (three (T, 3) gathers, not one (T, 3, 3)); the same sums in the same order
    first = positions[picked[:, 0]]
    geometric = np.cross(positions[picked[:, 1]] - first, positions[picked[:, 2]] - first)
    summed = normals[picked[:, 0]] + normals[picked[:, 1]] + normals[picked[:, 2]]
    against = np.flatnonzero(np.einsum("ti,ti->t", geometric, summed) < 0.0)
    rows = against if every else chosen[against]
    faces = faces.copy()
    faces[rows] = faces[rows][:, [0, 2, 1]]
    return faces


def drop_zero_area(positions: np.ndarray, faces: np.ndarray, suspects: np.ndarray) -> np.ndarray:
    """Remove triangles of zero area among those touching the suspect vertices (indices)."""
    if suspects.size == 0:
        return faces
    suspect = np.zeros(len(positions), dtype=bool)
    suspect[suspects] = True
    candidates = np.flatnonzero(suspect[faces].any(axis=1))
    if candidates.size == 0:
        return faces
    p = positions[faces[candidates]]
    edge_a, edge_b = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    area2 = np.linalg.norm(np.cross(edge_a, edge_b), axis=1)
    longest = np.maximum(np.einsum("ti,ti->t", edge_a, edge_a), np.einsum("ti,ti->t", edge_b, edge_b))
    degenerate = area2 <= 1e-12 * longest
    return np.delete(faces, candidates[degenerate], axis=0)


def read_rings(surface: EvolvedSurface, t: np.ndarray) -> CircleRings:
    """The circles at parameters t, read out once for the mesher (a line's centre is at infinity:
    ``mesh_circle_surface`` refuses it)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return CircleRings.from_projection(surface.sample(t), surface.frame)


def kept_rings(rings: CircleRings, keep: np.ndarray) -> CircleRings:
    """The rings ``keep`` (bool (K,)) of ``rings``."""
    return CircleRings(rings.centre[keep], rings.normal[keep], rings.radius[keep], rings.omega[keep], rings.frame)


def mesh_circle_surface(surface: EvolvedSurface, around: int, along: int | None = None, caps: bool = False,
                        closed: bool = False, t: np.ndarray | None = None,
                        with_tangents: bool = False, distinct: bool = False,
                        rings: CircleRings | None = None) -> SurfaceMesh:
    """Triangulate an evolved circle surface on rings of ``around`` vertices.

    The rings sit at the increasing parameters ``t`` (from 0 to the segment count), or at
    ``along`` evenly spaced ones. Each ring carries around + 1 vertices (the UV seam column
    repeats the first one). ``with_tangents``: also the analytic tangents (for normal maps).
    ``distinct``: leave out rings that would coincide with the ring before in an output file
    (``distinct_rings``), as every mesh that is written should. ``rings``: the circles at ``t``
    already read out (``read_rings``), not read again.
    """
    if t is None:
        t = np.linspace(0.0, surface.segment_count, along)
    surface.check_projection_exists(sampled=t)
    if rings is None:
        rings = read_rings(surface, t)
    _refuse_lines(rings, t, surface.segment_count)
    keep = distinct_rings(rings.centre, rings.normal, rings.radius, surface.frame.scale, surface.name) \
        if distinct else np.ones(len(t), dtype=bool)
    if not keep.all():
        t, rings = t[keep], kept_rings(rings, keep)
    along = len(t)
    u, v = transported_frames(rings.normal, closed, t)
    field = _ring_normals(surface, t, rings, u, v)

    theta = 2.0 * np.pi * np.arange(around + 1) / around
    circle_basis = np.stack([np.ones_like(theta), np.cos(theta), np.sin(theta)], axis=1)
    placement = np.stack([rings.centre, rings.radius[:, None] * u, rings.radius[:, None] * v], axis=1)
    positions = normal_field.expand(placement, circle_basis)

    normals, smallest, near_zero = normal_field.unit_normals(field.raw, theta, field.speed, NEAR_ZERO_FRACTION)
    signs, turning, turned = _continuous_signs(surface, t, u, field, theta, smallest)
    if _outward_sum(field, signs, rings, positions, normals) < 0.0:
        signs = -signs
    _apply_signs(normals, signs)
    # Tangent along +u: the circle's own tangent n x e_r = d x / d theta. The normal is
    # signs * (n x e_r) x x' / |.|, so (normal x tangent) . d x / d t has the sign of ``signs``:
    # w = signs makes the bitangent point along +v (v grows with t).
    # Only when an output asks for them: they cost as much as the normals.
    tangents = None
    if with_tangents:
        circle_tangent = normal_field.expand(np.stack([u, v], axis=1),
                                             np.stack([-np.sin(theta), np.cos(theta)], axis=1))
        tangents = np.concatenate([circle_tangent, np.broadcast_to(signs, (along, around + 1))[..., None]], axis=-1)
        tangents[:, -1] = tangents[:, 0]
        if closed:
            tangents[-1] = tangents[0]

    positions[:, -1] = positions[:, 0]
    normals[:, -1] = normals[:, 0]
    if closed:
        positions[-1] = positions[0]
        normals[-1] = normals[0]

    columns = around + 1
    faces = grid_faces(along, columns, signs)
    positions = positions.reshape(-1, 3)
    normals = normals.reshape(-1, 3)
    if np.any(turning) or np.any(turned):
        # Next to a fold or a pinch point the vertex normals of one triangle may differ
        # widely, and between rings turned far apart the chord need not follow d/dt: such
        # triangles are wound by their own geometry.
        strip = turning[:-1] | turning[1:] | turned
        faces = orient_by_geometry(faces, positions, normals, np.repeat(strip, 2 * around))
    if tangents is not None:
        tangents = tangents.reshape(-1, 4)
    faces = drop_zero_area(positions, faces, near_zero[0] * columns + near_zero[1])
    travelled = uv_map.along_lengths(field.samples)
    uvs = uv_map.grid_uvs(uv_map.normalised(travelled), columns)
    circumference = uv_map.mean_along(2.0 * np.pi * rings.radius, travelled)
    # The same two lengths at every grid vertex: a read-only view, not 16 bytes per vertex.
    uv_lengths = np.broadcast_to([circumference, travelled[-1] if travelled[-1] > 0.0 else circumference],
                                 (len(positions), 2))
    weld = _grid_weld(along, around, closed)

    if caps:
        # Each cap faces away from the tube: against the direction its ring moves in.
        leaving = np.sign(field.frame[[0, -1], 0, 0]) * np.array([-1.0, 1.0])
        leaving[leaving == 0.0] = np.array([-1.0, 1.0])[leaving == 0.0]
        parts = [positions, normals, uvs, faces, tangents, uv_lengths, weld]
        for ring, facing in zip((0, along - 1), leaving):
            parts = _add_cap(*parts, rings, u, ring, columns, around, theta[:-1], facing)
        positions, normals, uvs, faces, tangents, uv_lengths, weld = parts
    return SurfaceMesh(name=surface.name, positions=positions, normals=normals, uvs=uvs, faces=faces,
                       tangents=tangents, uv_lengths=uv_lengths, weld=weld)


def distinct_rings(centre: np.ndarray, normal: np.ndarray, radius: np.ndarray, size: float,
                   name: str) -> np.ndarray:
    """Which rings (K,) bool to mesh: each kept ring lies more than DISTINCT_RING_FRACTION of the
    surface's size along the surface from the ring kept before it; the first and the last are kept.

    Rings closer than that (along a segment between nearly identical controls) would give
    triangles of no area once positions are rounded to float32 in an output file. Distance
    along is the running sum of a bound on how far any vertex moves between consecutive rings,
    |dc| + |dr| + r |dn|, which never underestimates, so where rings are apart (the usual case)
    every one is kept. Elsewhere the first ring of each stretch of that length is kept, and one
    that follows the previous kept ring too closely (two stretches' first rings can straddle
    their boundary) gives way. Where the last ring is too near the ring kept before it, that
    one gives way instead (the surface's end stays where it is).
    """
    step = ring_steps(centre, normal, radius, size)
    if np.all(step > DISTINCT_RING_FRACTION):
        return np.ones(len(centre), dtype=bool)
    along = np.concatenate([[0.0], np.cumsum(step)])
    if along[-1] <= DISTINCT_RING_FRACTION:
        raise DegenerateGeometryError(
            f"surface '{name}': every circle of the surface lies within {DISTINCT_RING_FRACTION:g} of its "
            "size of the first, so it has no area to mesh")
    stretch = np.floor(along / DISTINCT_RING_FRACTION)
    first = np.flatnonzero(np.concatenate([[True], stretch[1:] > stretch[:-1]]))
    first = first[np.concatenate([[True], np.diff(along[first]) > DISTINCT_RING_FRACTION])]
    if first[-1] != len(along) - 1:
        if along[-1] - along[first[-1]] <= DISTINCT_RING_FRACTION and len(first) > 1:
            first = first[:-1]
        first = np.append(first, len(along) - 1)
    keep = np.zeros(len(along), dtype=bool)
    keep[first] = True
    return keep


def ring_steps(centre: np.ndarray, normal: np.ndarray, radius: np.ndarray, size) -> np.ndarray:
    """(..., K - 1) a bound on how far any vertex moves from each ring to the next, relative to
    ``size`` (a scalar, or one per ring: (..., K)): |dc| + |dr| + r |dn| of circles (..., K, 3),
    (..., K). ``distinct_rings``' step, shared by the batched passes so that they decide alike."""
    size = np.asarray(size, dtype=np.float64)
    centre, radius = centre / size[..., None], radius / size  # relative: no length of 1e-300 underflows
    return (np.linalg.norm(np.diff(centre, axis=-2), axis=-1) + np.abs(np.diff(radius, axis=-1))
            + np.maximum(radius[..., 1:], radius[..., :-1]) * np.linalg.norm(np.diff(normal, axis=-2), axis=-1))


def _grid_weld(along: int, around: int, closed: bool) -> np.ndarray:
    """weld (along * (around + 1),): the seam column onto column 0, a closed loop's last ring onto ring 0."""
    columns = around + 1
    grid = np.arange(along * columns, dtype=np.int32).reshape(along, columns)
    grid[:, -1] = grid[:, 0]
    if closed:
        grid[-1] = grid[0]
    return grid.ravel()


def _add_cap(positions, normals, uvs, faces, tangents, uv_lengths, weld, rings, u, ring, columns,
             around, theta, facing):
    """Append a flat disc closing ring ``ring``; facing = +1 along the circle's normal, -1 against.

    Its rim repeats the ring's vertices (welded onto them). UVs map the disc onto [0, 1]^2 with
    u along facing * (the ring's axis u) and v along n x u, so the UVs wind counter-clockwise
    seen from the cap's normal facing * n; the tangent is facing * u, with w = +1.
    """
    first = ring * columns
    rim = positions[first: first + around]
    start = len(positions)
    cap_normal = facing * rings.normal[ring]
    cap_positions = np.vstack([rim, rings.centre[ring][None]])
    j = np.arange(around)
    centre = start + around
    fan = np.stack([np.full(around, centre), start + j, start + (j + 1) % around], axis=1)
    if facing < 0:  # rim points run counter-clockwise about the circle's normal
        fan = fan[:, [0, 2, 1]]
    count = around + 1
    return (
        np.vstack([positions, cap_positions]),
        np.vstack([normals, np.broadcast_to(cap_normal, cap_positions.shape)]),
        np.vstack([uvs, uv_map.disc_uvs(theta, mirrored=facing < 0)]),
        np.vstack([faces, fan.astype(faces.dtype)]),
        None if tangents is None else np.vstack([tangents, np.broadcast_to(np.append(facing * u[ring], 1.0), (count, 4))]),
        np.vstack([uv_lengths, np.full((count, 2), 2.0 * rings.radius[ring])]),
        np.concatenate([weld, weld[first: first + around], [centre]]),
    )
