"""One closed 2-manifold surface from overlapping closed pieces (capped tubes, spheres): their union.

The boolean is manifold3d's (``cgamesh[neuro]``), which guarantees an oriented 2-manifold result
(symbolic perturbation decides every coincidence, so touching and coplanar pieces are handled
consistently) and carries per-vertex properties through: every vertex channel of a piece
(normal, UV, colour, attributes) travels as a property column beside the position.

What the output's vertices hold:
- a vertex of a piece that survives the union (away from the cut lines) keeps its normal, UV,
  colour and attributes exactly: manifold3d copies a retained vertex's properties (its
  barycentric weight is exactly 1), and properties are float64 end to end (``Mesh64``);
- a vertex made on a cut line exists once per side of the cut (the pieces' normals differ
  there: the union has a crease), and on each side takes the values of the piece it lies on,
  interpolated barycentrically inside that piece's triangle (the value a renderer would have
  interpolated there, so shading does not change along the piece); normals are then
  renormalised, colours clamped to [0, 1], and a channel that is the same at the triangle's
  three corners (a tube's segment id, a cap's normal) is set to exactly that value;
- every position is then rounded to the grid that float32 files store exactly (two float32
  steps at the largest coordinate), and the triangles that rounding leaves crossing another,
  flat, or pinched at a shared grid point are repaired by local edge collapses and flips
  (``cgamesh.meshing.float32_grid``, checked exactly by ``cgamesh.meshing.self_intersections``):
  a collapse removes a cut-line vertex before a piece's, so the analytic values stay where
  they were.

Tangents are dropped (exporters derive them from the UVs when asked). The pieces must be
closed and consistently oriented after welding their repeated vertices (``SurfaceMesh.weld``,
or bit-identical positions).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from cgamesh.errors import InvalidInputError
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.meshing.weld import weld_by_position

# property columns: position, normal, uv, then colour and attributes when the pieces have them
_POSITION, _NORMAL, _UV = slice(0, 3), slice(3, 6), slice(6, 8)
_FIXED = 8


def union(pieces: Sequence[SurfaceMesh], name: str) -> SurfaceMesh:
    """The union of closed pieces as one closed, oriented 2-manifold mesh named ``name``.

    pieces: SurfaceMeshes that are each closed once welded, wound counter-clockwise seen from
    outside (the meshers' convention), all with colours or all without, and with the same
    attribute names. Raises InvalidInputError naming the piece that is not closed (or
    inconsistent), MissingDependencyError when manifold3d is not installed.
    """
    from cgamesh.optional import require

    manifold3d = require("manifold3d", "neuro", "a watertight union (--watertight)")
    if len(pieces) == 0:
        raise InvalidInputError(f"{name}: a union needs at least one piece")
    colors, attribute_names = _channels(pieces, name)
    solids, rows, faces = [], [], []
    first_id = manifold3d.Manifold.reserve_ids(len(pieces))
    piece_of_id: dict[int, int] = {}
    for k, piece in enumerate(pieces):
        props = _properties(piece, colors, attribute_names)
        solid = manifold3d.Manifold(_mesh64(manifold3d, piece, props, first_id + k))
        status = solid.status()
        if status != manifold3d.Error.NoError:
            raise InvalidInputError(f"{name}: piece {k} ({piece.name!r}) is not a closed, consistently "
                                    f"oriented 2-manifold once welded (manifold3d: {status.name})")
        piece_of_id[first_id + k] = k
        solids.append(solid)
        rows.append(props)
        faces.append(np.asarray(piece.faces, dtype=np.int64))
    result = manifold3d.Manifold.batch_boolean(solids, manifold3d.OpType.Add)
    if result.status() != manifold3d.Error.NoError:
        raise InvalidInputError(f"{name}: the union failed (manifold3d: {result.status().name})")
    result = result.simplify(_float32_tolerance(rows))
    out = result.to_mesh64()
    props = np.array(out.vert_properties, dtype=np.float64)  # a copy we may write to
    tris = np.asarray(out.tri_verts, dtype=np.int64)
    source = _source_corners(out, tris, piece_of_id, rows, faces)
    new = _fix_new_vertices(props, tris, source, colors, name)
    props, tris = _on_float32_grid(props, tris, new, name)
    return _surface_mesh(name, props, tris, colors, attribute_names)


def _on_float32_grid(props: np.ndarray, tris: np.ndarray, new: np.ndarray, name: str) -> tuple[np.ndarray, np.ndarray]:
    """Positions rounded to the grid every float32 writer stores exactly, the triangles that
    rounding left crossing or flat repaired (``cgamesh.meshing.float32_grid``; the few it cannot
    yet repair are left as they are), unused vertices dropped."""
    from cgamesh.meshing.float32_grid import grid_step, repair

    step = grid_step(props[:, _POSITION])
    topology = weld_by_position(props[:, _POSITION])  # before rounding: the union's own vertices
    positions, tris, _ = repair(props[:, _POSITION], step, tris, topology, new)
    props[:, _POSITION] = positions
    used = np.zeros(len(props), dtype=bool)
    used[tris.ravel()] = True
    index = np.cumsum(used) - 1
    return props[used], index[tris]


def _float32_tolerance(rows: list[np.ndarray]) -> float:
    """Four float32 steps at the pieces' largest coordinate: what the union may move its surface
    by when it simplifies (manifold3d's ``simplify`` swaps and collapses the sliver triangles a
    cut leaves where cut lines nearly meet). Every writer stores float32 positions; far from the
    origin (a neuron at 35,000 units has steps of 0.004) rounding a sliver narrower than a step
    can make it pass through its neighbour, and removing the slivers first avoids most of that."""
    scale = max(float(np.abs(r[:, _POSITION]).max()) for r in rows)
    return 4.0 * float(np.spacing(np.float32(scale)))


def _channels(pieces: Sequence[SurfaceMesh], name: str) -> tuple[bool, list[str]]:
    """Whether the pieces carry colours, and their attribute names; every piece must agree."""
    colors = pieces[0].colors is not None
    names = sorted(pieces[0].attributes or {})
    for k, piece in enumerate(pieces):
        if (piece.colors is not None) != colors or sorted(piece.attributes or {}) != names:
            raise InvalidInputError(
                f"{name}: piece {k} ({piece.name!r}) has colours {piece.colors is not None} and attributes "
                f"{sorted(piece.attributes or {})}, piece 0 has {colors} and {names}: a union needs the same channels")
    return colors, names


def _properties(piece: SurfaceMesh, colors: bool, attribute_names: list[str]) -> np.ndarray:
    """(V, P) float64 property rows: position, normal, uv, [colour], attributes."""
    columns = [piece.positions, piece.normals, piece.uvs]
    if colors:
        columns.append(piece.colors)
    columns.extend(np.asarray(piece.attributes[n], dtype=np.float64)[:, None] for n in attribute_names)
    return np.ascontiguousarray(np.concatenate([np.asarray(c, dtype=np.float64).reshape(piece.vertex_count, -1)
                                                for c in columns], axis=1))


def _mesh64(manifold3d, piece: SurfaceMesh, props: np.ndarray, original_id: int):
    """The piece as a manifold3d Mesh64: properties per vertex, merge vectors that weld the
    repeated vertices (seams, cap rims) into one position each, and one run of triangles
    marked with the piece's id and numbered by the piece's own face indices."""
    weld = np.asarray(piece.weld if piece.weld is not None else weld_by_position(piece.positions))
    repeated = np.flatnonzero(weld != np.arange(len(weld)))
    return manifold3d.Mesh64(
        vert_properties=props,
        tri_verts=np.ascontiguousarray(piece.faces, dtype=np.uint64),
        merge_from_vert=repeated.astype(np.uint64),
        merge_to_vert=weld[repeated].astype(np.uint64),
        run_index=np.array([0, 3 * piece.triangle_count], dtype=np.uint64),
        run_original_id=np.array([original_id], dtype=np.uint32),
        face_id=np.arange(piece.triangle_count, dtype=np.uint64),
    )


def _source_corners(out, tris: np.ndarray, piece_of_id: dict[int, int], rows: list[np.ndarray],
                    faces: list[np.ndarray]) -> np.ndarray:
    """(T, 3, P) property rows of the three corners of each output triangle's source triangle
    (the piece's triangle it was cut from), found through manifold3d's run and face ids."""
    run_index = np.asarray(out.run_index, dtype=np.int64)  # offsets into the flat triangle corners
    run_piece = np.array([piece_of_id[int(i)] for i in np.asarray(out.run_original_id)], dtype=np.int64)
    corner = 3 * np.arange(len(tris))
    piece = run_piece[np.searchsorted(run_index, corner, side="right") - 1]
    vertex_offset = np.cumsum([0] + [len(r) for r in rows])
    face_offset = np.cumsum([0] + [len(f) for f in faces])
    all_rows = np.concatenate(rows)
    all_faces = np.concatenate([f + offset for f, offset in zip(faces, vertex_offset)])
    face = face_offset[piece] + np.asarray(out.face_id, dtype=np.int64)
    return all_rows[all_faces[face]]


def _fix_new_vertices(props: np.ndarray, tris: np.ndarray, source: np.ndarray, colors: bool, name: str) -> np.ndarray:
    """Give vertices made by the union (on cut lines) their final values, in place; vertices
    whose row is one of their source triangle's corners are left exactly as they are. Returns
    (V,) whether each vertex is new."""
    corners = props[tris]  # (T, 3, P)
    kept_corner = np.zeros(tris.shape, dtype=bool)
    for j in range(3):
        kept_corner |= (corners == source[:, None, j, :]).all(axis=2)
    kept = np.zeros(len(props), dtype=bool)
    kept[tris[kept_corner]] = True
    new = ~kept
    if not new.any():
        return new
    # A channel equal at the source triangle's three corners is that value exactly (the
    # barycentric sum of three equal values can miss it by an ulp).
    same = (source[:, 0] == source[:, 1]) & (source[:, 1] == source[:, 2])  # (T, P)
    same[:, _POSITION] = False
    for i in range(3):
        vertex = tris[:, i]
        pick = new[vertex][:, None] & same
        t, p = np.nonzero(pick)
        props[vertex[t], p] = source[t, 0, p]
    normals = props[new, _NORMAL]
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    if not (length > 1e-9).all():  # only pieces whose normals cancel inside a triangle get here
        raise InvalidInputError(f"{name}: the union cut a triangle whose vertex normals cancel out: the "
                                "pieces' normals must agree in direction within every triangle")
    props[new, _NORMAL] = normals / length
    if colors:
        block = slice(_FIXED, _FIXED + 3)
        props[new, block] = np.clip(props[new, block], 0.0, 1.0)
    return new


def _surface_mesh(name: str, props: np.ndarray, tris: np.ndarray, colors: bool,
                  attribute_names: list[str]) -> SurfaceMesh:
    positions = np.ascontiguousarray(props[:, _POSITION])
    column = _FIXED + (3 if colors else 0)
    attributes = {n: np.ascontiguousarray(props[:, column + j]) for j, n in enumerate(attribute_names)}
    return SurfaceMesh(
        name=name,
        positions=positions,
        normals=np.ascontiguousarray(props[:, _NORMAL]),
        uvs=np.ascontiguousarray(props[:, _UV]),
        faces=np.ascontiguousarray(tris, dtype=np.int32 if len(props) < 2**31 else np.int64),
        weld=weld_by_position(positions),
        colors=np.ascontiguousarray(props[:, _FIXED:_FIXED + 3]) if colors else None,
        attributes=attributes or None,
    )
