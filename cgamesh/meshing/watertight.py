"""One closed 2-manifold surface from closed pieces, by a mesh boolean union (manifold3d)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from cgamesh.errors import DegenerateGeometryError
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.optional import require


def union(pieces: Sequence[SurfaceMesh], name: str) -> SurfaceMesh:
    """The union of closed ``pieces`` (each closed once welded) as one closed 2-manifold mesh.

    Normals are the area-weighted face normals of the result (flat where the boolean cut).
    """
    m3d = require("manifold3d", "neuro", "--watertight")
    solids = []
    for piece in pieces:
        faces = (piece.weld if piece.weld is not None else np.arange(piece.vertex_count))[piece.faces]
        used, faces = np.unique(faces, return_inverse=True)
        mesh = m3d.Mesh64(vert_properties=np.ascontiguousarray(piece.positions[used], dtype=np.float64),
                          tri_verts=np.ascontiguousarray(faces.reshape(-1, 3), dtype=np.uint64))
        solid = m3d.Manifold(mesh)
        if solid.status() != m3d.Error.NoError:
            raise DegenerateGeometryError(f"{piece.name}: not a closed 2-manifold piece ({solid.status()})")
        solids.append(solid)
    result = m3d.Manifold.batch_boolean(solids, m3d.OpType.Add).to_mesh64()
    positions = np.asarray(result.vert_properties, dtype=np.float64)[:, :3]
    faces = np.asarray(result.tri_verts, dtype=np.int64)
    corner = positions[faces]
    face_normals = np.cross(corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0])
    normals = np.zeros_like(positions)
    for k in range(3):
        np.add.at(normals, faces[:, k], face_normals)
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.where(length > 0.0, normals / np.where(length > 0.0, length, 1.0), [0.0, 0.0, 1.0])
    return SurfaceMesh(name=name, positions=positions, normals=normals, uvs=np.zeros((len(positions), 2)),
                       faces=faces.astype(np.int32), weld=np.arange(len(positions), dtype=np.int32))
