"""Meshing evolved circle surfaces by TRS-rotor stepping (paper section 11), any number at once.

The first ring is the unit circle's points carried to C(0) by the TRS rotor Z_0 = T D R_0;
each following ring is the previous one carried by the TRS rotor from C(t_k) to C(t_{k+1}).
Translation and dilation of that rotor are fixed by the two circles' centres and radii; its
rotation R_k is the smallest rotation between their planes, and only the rotations
accumulate (cgamesh.meshing.ring_frames). So ring k's points are

    x_kj = c_k + r_k (cos theta_j u_k + sin theta_j v_k),   u_k = (R_k ... R_1 R_0) e1,

which is the sandwich Z X ~Z of the composed rotors evaluated as the similarity it is.
Centre and radius are read from C(t_k) itself at every ring, so no error accumulates in
them, and u_k is re-orthogonalised against the exact plane: vertices stay on their circles
to rounding at any step count. The (t, theta) grid is triangulated directly; its seam
column and, for closed loops, its last ring repeat the first bit for bit.

One mesher serves one surface and many: ``mesh_rings`` takes the rings of S surfaces as rows
(cgamesh.meshing.ring_rows; a single surface is S = 1, ``mesh_circle_surface``) and does every
step over all rows at once. The rare repairs run on the rows that need them, in the same pass:
rings that stand still take their normals from just past them, rings whose field may fold are
examined vertex by vertex (cgamesh.meshing.ring_normals), strips next to them are wound by their
own geometry, triangles at vanishing normals of no area are dropped, and rings that would
coincide in an output file are left out.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cgamesh.errors import CgameshError, DegenerateGeometryError
from cgamesh.geometry.surface import CircleRings, EvolvedSurface
from cgamesh.meshing import normals as normal_field
from cgamesh.meshing import uv as uv_map
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.meshing.ring_frames import close_loops, transported_axes
from cgamesh.meshing.ring_normals import (STATIONARY_FRACTION, RingNormals, RingSigns, continuous_signs,
                                          nearby_normals, outward_flips, step_inside, turned_pairs)
from cgamesh.meshing.ring_rows import Resample, RingRows, SurfaceRows, padded_rows

# Triangles next to vertices where the normal field vanishes are checked for zero area.
NEAR_ZERO_FRACTION = 1e-6
# Consecutive rings whose vertices all lie within this fraction of the surface's size of each
# other are one ring (float32, as output files store positions, resolves about 6e-8).
DISTINCT_RING_FRACTION = 1e-6


@dataclass(frozen=True)
class CircleSurfaces:
    """What the mesher knows of each of S surfaces beyond its rings: names, ends (S,) the last
    parameter (the segment count), closed and caps (S,) bool, and ``resample`` to read their
    circles at other parameters (``ring_rows.Resample``, by index into these S)."""

    names: tuple[str, ...]
    ends: np.ndarray
    closed: np.ndarray
    caps: np.ndarray
    resample: Resample

    @classmethod
    def single(cls, surface: EvolvedSurface, closed: bool, caps: bool) -> "CircleSurfaces":
        def resample(_: np.ndarray, t: np.ndarray) -> tuple[RingRows, np.ndarray]:
            rings = CircleRings.from_projection(surface.sample(t), surface.frame)
            return RingRows.of_rings(rings, t), np.ones(len(t), dtype=bool)

        return cls((surface.name,), np.array([float(surface.segment_count)]), np.array([closed]), np.array([caps]),
                   resample)


@dataclass(frozen=True)
class CircleMeshes:
    """The meshes of S surfaces, surface after surface in one set of arrays.

    positions, normals (V, 3); uvs (V, 2); tangents (V, 4) or None; faces (F, 3) int32, indices
    into these arrays; vertex_first, face_first (S + 1,) each surface's block; uv_lengths (S, 2)
    (circumference, length); ring_surface, ring_local (K,) the surface of every ring kept and
    its index among the surface's rows as given (a ring's around + 1 vertices are consecutive);
    columns = around + 1; meshed (S,) which surfaces have a mesh here; errors {surface: error}
    for those that cannot be meshed (the rest of the unmeshed need to be meshed alone, where
    their own reader names what is wrong); caps: each capped surface's two end rings.
    """

    names: tuple[str, ...]
    positions: np.ndarray
    normals: np.ndarray
    uvs: np.ndarray
    tangents: np.ndarray | None
    faces: np.ndarray
    vertex_first: np.ndarray
    face_first: np.ndarray
    uv_lengths: np.ndarray
    ring_surface: np.ndarray
    ring_local: np.ndarray
    columns: int
    closed: np.ndarray
    meshed: np.ndarray
    errors: dict
    caps: dict

    def surface_mesh(self, s: int) -> SurfaceMesh:
        """Surface s as a mesh of its own (indices from 0, its seam and loop welded, its caps)."""
        if s in self.errors:
            raise self.errors[s]
        vs, ve, fs, fe = self.vertex_first[s], self.vertex_first[s + 1], self.face_first[s], self.face_first[s + 1]
        positions, normals, uvs = self.positions[vs:ve], self.normals[vs:ve], self.uvs[vs:ve]
        tangents = None if self.tangents is None else self.tangents[vs:ve]
        faces = self.faces[fs:fe] - np.int32(vs) if vs else self.faces[fs:fe]
        rings = (ve - vs) // self.columns
        girth, length = self.uv_lengths[s]
        uv_lengths = np.broadcast_to([girth, length], (ve - vs, 2))
        weld = grid_weld(rings, self.columns - 1, bool(self.closed[s]))
        if s in self.caps:
            parts = [positions, normals, uvs, faces, tangents, uv_lengths, weld]
            for ring, (centre, normal, radius, u, facing) in zip((0, rings - 1), self.caps[s]):
                parts = _add_cap(*parts, centre, normal, radius, u, ring, self.columns, facing)
            positions, normals, uvs, faces, tangents, uv_lengths, weld = parts
        return SurfaceMesh(name=self.names[s], positions=positions, normals=normals, uvs=uvs, faces=faces,
                           tangents=tangents, uv_lengths=uv_lengths, weld=weld)


def mesh_rings(rings: RingRows, layout: SurfaceRows, surfaces: CircleSurfaces, around: int,
               tangents: bool = False, distinct: bool = False) -> CircleMeshes:
    """Triangulate S evolved circle surfaces on rings of ``around`` vertices (module doc).

    Each ring carries around + 1 vertices (the UV seam column repeats the first one).
    ``tangents``: also the analytic tangents (for normal maps). ``distinct``: leave out rings
    that would coincide with the ring before in an output file (``distinct_rings``), as every
    mesh that is written should. A surface with a circle through infinity, or without two
    distinct rings, gets its error in ``errors``.
    """
    errors: dict[int, CgameshError] = {}
    keep = np.ones(len(rings), dtype=bool)
    line = ~(np.isfinite(rings.centre).all(axis=1) & np.isfinite(rings.radius))
    for s in np.flatnonzero(np.bincount(layout.surface[line], minlength=len(layout.count))):
        first_line = layout.first[s] + int(np.argmax(line[layout.first[s]: layout.first[s] + layout.count[s]]))
        errors[int(s)] = _line_error(rings.t[first_line], surfaces.ends[s])
    if errors:
        keep &= ~np.isin(layout.surface, list(errors))
    if distinct:
        step = ring_steps(rings.centre, rings.normal, rings.radius, rings.scale)
        close = layout.within & ~(step > DISTINCT_RING_FRACTION) & keep[1:]
        for s in np.flatnonzero(np.bincount(layout.surface[1:][close], minlength=len(layout.count))):
            rows = slice(layout.first[s], layout.first[s] + layout.count[s])
            try:
                keep[rows] = distinct_rings(rings.centre[rows], rings.normal[rows], rings.radius[rows],
                                            float(rings.scale[layout.first[s]]), surfaces.names[s])
            except CgameshError as error:
                errors[int(s)] = error
                keep[rows] = False
    ring_local, kept = layout.local, layout
    if not keep.all():
        rings, ring_local, kept = rings.take(keep), ring_local[keep], layout.kept(keep)
    if not len(rings):  # every surface refused
        empty = np.zeros((0, 3))
        return CircleMeshes(surfaces.names, empty, empty, np.zeros((0, 2)), None, np.zeros((0, 3), np.int32),
                            np.zeros(len(kept.count) + 1, np.int64), np.zeros(len(kept.count) + 1, np.int64),
                            np.zeros((len(kept.count), 2)), kept.surface, ring_local, around + 1, surfaces.closed,
                            np.zeros(len(kept.count), dtype=bool), errors, {})
    grid = _Grid(rings, kept, surfaces, around, tangents)
    meshed = ~grid.missing & (kept.count > 0)  # a refused surface has no rings left
    return CircleMeshes(surfaces.names, grid.positions, grid.normals, grid.uvs, grid.tangents, grid.faces,
                        grid.vertex_first, grid.face_first, grid.uv_lengths, kept.surface, ring_local, around + 1,
                        surfaces.closed, meshed, errors, grid.caps)


class _Grid:
    """The (t, theta) grids of the kept rings of every surface: vertices, normals, tangents,
    UVs, faces and caps (``mesh_rings``)."""

    def __init__(self, rings: RingRows, layout: SurfaceRows, surfaces: CircleSurfaces, around: int,
                 with_tangents: bool):
        columns = around + 1
        surface = layout.surface
        closed = surfaces.closed & (layout.count > 0)
        u, v = transported_axes(rings.normal, layout.local)
        if closed.any():
            close_loops(u, v, rings.normal, rings.t, layout.first[closed], layout.count[closed])
        field = RingNormals.of(rings, u, v)
        self.missing = np.zeros(len(layout.count), dtype=bool)
        stationary = field.speed <= STATIONARY_FRACTION * rings.radius / rings.scale  # both in working units
        if np.any(stationary):
            which = np.flatnonzero(stationary)
            near_t = step_inside(rings.t[which], surfaces.ends[surface[which]], 1.0)
            # at least two rows read: a lone row's sums can round otherwise than a batch's, and a
            # surface's repair must read the same bits whether it is meshed alone or among others
            pad = np.zeros(1 if len(which) == 1 else 0, dtype=np.intp)
            read, exists = surfaces.resample(surface[np.concatenate([which, which[pad]])],
                                             np.concatenate([near_t, near_t[pad]]))
            if pad.size:
                read, exists = read.take(slice(0, 1)), exists[:1]
            self.missing[surface[which[~exists]]] = True
            with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
                field = field.replace_rings(stationary, nearby_normals(read, u[stationary]))

        # each ring's circle, axes and normal field are let go as soon as what is made from them
        # is made, before the faces: a chunk of many surfaces then holds little beyond its vertices
        v_coordinate, self.uv_lengths = _along(field.samples, rings.radius, layout)
        theta = 2.0 * np.pi * np.arange(columns) / around
        circle_basis = np.stack([np.ones_like(theta), np.cos(theta), np.sin(theta)], axis=1)
        placement = np.stack([rings.centre, rings.radius[:, None] * u, rings.radius[:, None] * v], axis=1)
        positions = normal_field.expand(placement, circle_basis)
        del placement
        normals, smallest, near_zero = normal_field.unit_normals(field.raw, theta, field.speed, NEAR_ZERO_FRACTION)
        signs = continuous_signs(field, smallest, theta, rings, layout, surfaces.ends, u, surfaces.resample)
        self.missing |= signs.missing
        signs = signs.flipped(outward_flips(field, signs, rings, layout, positions, normals), surface)
        self.caps = {}
        for s in np.flatnonzero(surfaces.caps & (layout.count > 0)):
            ends = (layout.first[s], layout.last[s])
            # Each cap faces away from the tube: against the direction its ring moves in.
            leaving = np.sign(field.frame[list(ends), 0, 0]) * np.array([-1.0, 1.0])
            leaving[leaving == 0.0] = np.array([-1.0, 1.0])[leaving == 0.0]
            self.caps[int(s)] = [(rings.centre[k], rings.normal[k], rings.radius[k], u[k], facing)
                                 for k, facing in zip(ends, leaving)]
        del field
        _apply_signs(normals, signs)
        # Tangent along +u: the circle's own tangent n x e_r = d x / d theta. The normal is
        # signs * (n x e_r) x x' / |.|, so (normal x tangent) . d x / d t has the sign of the
        # signs: w = signs makes the bitangent point along +v (v grows with t). Only when an
        # output asks for them: they cost as much as the normals.
        tangents = None
        if with_tangents:
            tangents = np.empty(positions.shape[:2] + (4,))
            tangents[..., :3] = normal_field.expand(np.stack([u, v], axis=1),
                                                    np.stack([-np.sin(theta), np.cos(theta)], axis=1))
            tangents[..., 3] = signs.ring[:, None]
            tangents[signs.examined, :, 3] = signs.at(signs.examined, columns)
            tangents[:, -1] = tangents[:, 0]
        del u, v
        positions[:, -1] = positions[:, 0]
        normals[:, -1] = normals[:, 0]
        loop_first, loop_last = layout.first[closed], layout.last[closed]
        for grid in (positions, normals) if tangents is None else (positions, normals, tangents):
            grid[loop_last] = grid[loop_first]

        faces = _faces(signs, layout, columns)
        face_counts = 2 * around * np.maximum(layout.count - 1, 0)
        self.positions, self.normals = positions.reshape(-1, 3), normals.reshape(-1, 3)
        # Next to a fold or a pinch point the vertex normals of one triangle may differ widely,
        # and between rings turned far apart the chord need not follow d/dt: such triangles are
        # wound by their own geometry.
        turning = signs.examined_rows
        strip = ((turning[:-1] | turning[1:] | turned_pairs(signs.agreement)) & layout.within)[layout.within]
        if np.any(strip):
            orient_by_geometry(faces, self.positions, self.normals, np.repeat(strip, 2 * around), in_place=True)
        if near_zero[0].size:
            faces, gone = drop_zero_area(self.positions, faces, near_zero[0] * columns + near_zero[1], removed=True)
            # each removed triangle's surface, from the surfaces' triangle counts
            face_counts = face_counts - np.bincount(np.searchsorted(np.cumsum(face_counts), gone, side="right"),
                                                    minlength=len(face_counts))
        self.faces = faces
        self.tangents = None if tangents is None else tangents.reshape(-1, 4)
        self.vertex_first = np.concatenate([layout.first, [len(layout.surface)]]) * columns
        self.face_first = np.concatenate([[0], np.cumsum(face_counts)])
        uvs = np.empty(positions.shape[:2] + (2,))
        uvs[..., 0] = np.linspace(0.0, 1.0, columns)[None, :]
        uvs[..., 1] = v_coordinate[:, None]
        self.uvs = uvs.reshape(-1, 2)


def _apply_signs(normals: np.ndarray, signs: RingSigns) -> None:
    """normals (R, M, 3) *= the signs, touching only rings with a negative sign."""
    flipped = signs.ring < 0.0
    examined = signs.examined_rows
    if flipped.all() and not examined.any():  # the whole field turned outward
        np.negative(normals, out=normals)
    else:
        rows = np.flatnonzero(flipped & ~examined)
        if rows.size:
            normals[rows] *= -1.0
        if signs.examined.size:
            normals[signs.examined] *= signs.at(signs.examined, normals.shape[1])[..., None]


def _faces(signs: RingSigns, layout: SurfaceRows, columns: int) -> np.ndarray:
    """Triangles (2 (K - S)(columns - 1), 3) int32 of every surface's (rings, columns) vertex grid,
    surface after surface, 2 (columns - 1) for each pair of consecutive rings.

    Quad (k, j) splits into (k,j)(k,j+1)(k+1,j) and (k,j+1)(k+1,j+1)(k+1,j), both wound like
    d/dtheta x d/dt; where the normal field is flipped (the sum of a triangle's three vertex
    signs is negative) the triangle's winding is reversed too. Rows of one winding are written
    from one pattern, only the others reordered afterwards.
    """
    pair = np.flatnonzero(layout.within)  # ring k and k + 1 of one surface
    j = np.arange(columns - 1, dtype=np.int32)
    row = np.empty((columns - 1, 2, 3), dtype=np.int32)
    row[:, 0, 0], row[:, 0, 1], row[:, 0, 2] = j, j + 1, j + columns
    row[:, 1, 0], row[:, 1, 1], row[:, 1, 2] = j + 1, j + columns + 1, j + columns
    examined = signs.examined_rows
    by_vertex = np.flatnonzero(examined[pair] | examined[pair + 1])
    uniform = not by_vertex.size and (np.all(signs.ring > 0.0) or np.all(signs.ring < 0.0))
    flipped = None
    if uniform:  # one sign everywhere (the usual case): nothing to vote on
        majority = bool(signs.ring[0] < 0.0)
    else:
        # with one sign per ring: (2 s_k + s_k+1) < 0 for the first triangle, (s_k + 2 s_k+1) < 0 for the second
        flipped = np.empty((len(pair), columns - 1, 2), dtype=bool)
        flipped[:, :, 0] = (signs.ring[pair] < 0.0)[:, None]
        flipped[:, :, 1] = (signs.ring[pair + 1] < 0.0)[:, None]
        if by_vertex.size:
            a, b = signs.at(pair[by_vertex], columns), signs.at(pair[by_vertex] + 1, columns)
            flipped[by_vertex, :, 0] = a[:, :-1] + a[:, 1:] + b[:, :-1] < 0.0
            flipped[by_vertex, :, 1] = a[:, 1:] + b[:, 1:] + b[:, :-1] < 0.0
        majority = bool(2 * np.count_nonzero(flipped) > flipped.size)
    base = row[:, :, [0, 2, 1]] if majority else row
    faces = np.empty((len(pair), (columns - 1) * 6), dtype=np.int32)
    np.add(base.reshape(1, -1), (pair * columns).astype(np.int32)[:, None], out=faces)
    faces = faces.reshape(len(pair), columns - 1, 2, 3)
    if flipped is not None:
        minority = ~flipped if majority else flipped
        if np.any(minority):
            faces[minority] = faces[minority][:, [0, 2, 1]]
    return faces.reshape(-1, 3)


def grid_faces(rings: int, columns: int, signs: np.ndarray) -> np.ndarray:
    """Triangles (2 (rings - 1)(columns - 1), 3) int32 of one (rings, columns) vertex grid whose
    rings have the signs (rings, 1), or one sign for all (1, 1) (``_faces`` of a single surface)."""
    ring = np.broadcast_to(np.asarray(signs, dtype=np.float64)[:, 0], (rings,))
    one = RingSigns(ring, np.ones((0, columns)), np.empty(0, np.intp), np.zeros(1, dtype=bool), np.ones(rings - 1),
                    np.zeros(1, dtype=bool))
    return _faces(one, SurfaceRows.of_counts([rings]), columns)


def _along(samples: np.ndarray, radius: np.ndarray, layout: SurfaceRows) -> tuple[np.ndarray, np.ndarray]:
    """Each ring's v (R,), the arc length travelled from its surface's first ring over the
    surface's length (evenly spaced where it does not move: ``uv.normalised``), and (S, 2) the
    circumference averaged along each surface and its length (``uv.mean_along``)."""
    steps = np.linalg.norm(np.diff(samples, axis=0), axis=-1).mean(axis=-1)  # ring r to r + 1
    travelled = np.zeros(len(radius))
    girth = 2.0 * np.pi * radius
    surfaces = len(layout.count)
    length = np.zeros(surfaces)
    around_sum = np.zeros(surfaces)
    # running sums along each surface, and the trapezoid sums: numpy's pairwise sum depends on a
    # row's length, so rows of one length at a time
    for members, grid, valid in padded_rows(layout.first, layout.count):
        step_rows = np.where(valid[:, 1:], steps[np.maximum(grid[:, 1:], 1) - 1], 0.0)
        cumulative = np.concatenate([np.zeros((len(members), 1)), np.cumsum(step_rows, axis=1)], axis=1)
        travelled[grid[valid]] = cumulative[valid]
        present = np.flatnonzero(np.bincount(layout.count[members]))
        for width in present[present > 0]:  # the lengths present, ascending (a surface may have none left)
            same = np.flatnonzero(layout.count[members] == width)
            run, c = cumulative[same, :width], girth[grid[same, :width]]
            length[members[same]] = run[:, -1]
            around_sum[members[same]] = np.sum(0.5 * (c[:, 1:] + c[:, :-1]) * np.diff(run, axis=1), axis=1)
    moving = length > 0.0
    v = travelled / np.where(moving, length, 1.0)[layout.surface]
    circumference = around_sum / np.where(moving, length, 1.0)
    for s in np.flatnonzero(~moving & (layout.count > 0)):  # rings that do not move: evenly spaced
        rows = slice(layout.first[s], layout.first[s] + layout.count[s])
        v[rows] = np.linspace(0.0, 1.0, layout.count[s])
        circumference[s] = np.mean(girth[rows])
    return v, np.stack([circumference, np.where(moving, length, circumference)], axis=1)


def _line_error(t: float, end: float) -> DegenerateGeometryError:
    """The error of a circle that is a line (its centre and radius at infinity: blade
    interpolation between controls of opposite orientation, align false) at parameter t."""
    from cgamesh.geometry.curves import split_parameter

    segment, alpha = split_parameter(np.array([t]), int(round(end)))
    return DegenerateGeometryError(
        f"the interpolated circle is a line (through infinity) at segment {int(segment[0])}, "
        f"alpha = {float(alpha[0]):.3g}; controls of opposite orientation interpolate through one "
        "(align: true turns them alike)")


def orient_by_geometry(faces: np.ndarray, positions: np.ndarray, normals: np.ndarray,
                       which: np.ndarray, in_place: bool = False) -> np.ndarray:
    """Wind the triangles ``which`` (F,) bool counter-clockwise seen from their vertex normals
    (those of a copy of ``faces``, or of ``faces`` itself ``in_place``).

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
    if not in_place:
        faces = faces.copy()
    faces[rows] = faces[rows][:, [0, 2, 1]]
    return faces


def drop_zero_area(positions: np.ndarray, faces: np.ndarray, suspects: np.ndarray, removed: bool = False):
    """Remove triangles of zero area among those touching the suspect vertices (indices); with
    ``removed``, also return the indices (into ``faces``) of the triangles removed."""
    gone = np.empty(0, np.intp)
    if suspects.size:
        suspect = np.zeros(len(positions), dtype=bool)
        suspect[suspects] = True
        candidates = np.flatnonzero(suspect[faces].any(axis=1))
        if candidates.size:
            p = positions[faces[candidates]]
            edge_a, edge_b = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
            area2 = np.linalg.norm(np.cross(edge_a, edge_b), axis=1)
            longest = np.maximum(np.einsum("ti,ti->t", edge_a, edge_a), np.einsum("ti,ti->t", edge_b, edge_b))
            gone = candidates[area2 <= 1e-12 * longest]
            faces = np.delete(faces, gone, axis=0)
    return (faces, gone) if removed else faces


def read_rings(surface: EvolvedSurface, t: np.ndarray) -> CircleRings:
    """The circles at parameters t, read out once for the mesher (a line's centre is at infinity:
    the mesher refuses it)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return CircleRings.from_projection(surface.sample(t), surface.frame)


def kept_rings(rings: CircleRings, keep: np.ndarray) -> CircleRings:
    """The rings ``keep`` (bool (K,)) of ``rings``."""
    return CircleRings(rings.centre[keep], rings.normal[keep], rings.radius[keep], rings.omega[keep], rings.frame)


def mesh_circle_surface(surface: EvolvedSurface, around: int, along: int | None = None, caps: bool = False,
                        closed: bool = False, t: np.ndarray | None = None,
                        with_tangents: bool = False, distinct: bool = False,
                        rings: CircleRings | None = None) -> SurfaceMesh:
    """Triangulate one evolved circle surface on rings of ``around`` vertices: ``mesh_rings``
    of a single surface.

    The rings sit at the increasing parameters ``t`` (from 0 to the segment count), or at
    ``along`` evenly spaced ones. ``rings``: the circles at ``t`` already read out
    (``read_rings``), not read again. See ``mesh_rings`` for the rest.
    """
    if t is None:
        t = np.linspace(0.0, surface.segment_count, along)
    surface.check_projection_exists(sampled=t)
    if rings is None:
        rings = read_rings(surface, t)
    meshes = mesh_rings(RingRows.of_rings(rings, t), SurfaceRows.of_counts([len(t)]),
                        CircleSurfaces.single(surface, closed, caps), around, with_tangents, distinct)
    return meshes.surface_mesh(0)


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
    (..., K)."""
    size = np.asarray(size, dtype=np.float64)
    centre, radius = centre / size[..., None], radius / size  # relative: no length of 1e-300 underflows
    return (np.linalg.norm(np.diff(centre, axis=-2), axis=-1) + np.abs(np.diff(radius, axis=-1))
            + np.maximum(radius[..., 1:], radius[..., :-1]) * np.linalg.norm(np.diff(normal, axis=-2), axis=-1))


def grid_weld(rings: int, around: int, closed: bool) -> np.ndarray:
    """weld (rings * (around + 1),): the seam column onto column 0, a closed loop's last ring onto ring 0."""
    columns = around + 1
    grid = np.arange(rings * columns, dtype=np.int32).reshape(rings, columns)
    grid[:, -1] = grid[:, 0]
    if closed:
        grid[-1] = grid[0]
    return grid.ravel()


def _add_cap(positions, normals, uvs, faces, tangents, uv_lengths, weld, centre, normal, radius, u, ring, columns,
             facing):
    """Append a flat disc closing ring ``ring``; facing = +1 along the circle's normal, -1 against.

    Its rim repeats the ring's vertices (welded onto them). UVs map the disc onto [0, 1]^2 with
    u along facing * (the ring's axis u) and v along n x u, so the UVs wind counter-clockwise
    seen from the cap's normal facing * n; the tangent is facing * u, with w = +1.
    """
    around = columns - 1
    first = ring * columns
    rim = positions[first: first + around]
    start = len(positions)
    cap_normal = facing * normal
    cap_positions = np.vstack([rim, centre[None]])
    j = np.arange(around)
    middle = start + around
    fan = np.stack([np.full(around, middle), start + j, start + (j + 1) % around], axis=1)
    if facing < 0:  # rim points run counter-clockwise about the circle's normal
        fan = fan[:, [0, 2, 1]]
    count = around + 1
    theta = 2.0 * np.pi * np.arange(around) / around
    return (
        np.vstack([positions, cap_positions]),
        np.vstack([normals, np.broadcast_to(cap_normal, cap_positions.shape)]),
        np.vstack([uvs, uv_map.disc_uvs(theta, mirrored=facing < 0)]),
        np.vstack([faces, fan.astype(faces.dtype)]),
        None if tangents is None else np.vstack([tangents, np.broadcast_to(np.append(facing * u, 1.0), (count, 4))]),
        np.vstack([uv_lengths, np.full((count, 2), 2.0 * radius)]),
        np.concatenate([weld, weld[first: first + around], [middle]]),
    )
