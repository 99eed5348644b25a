"""Many meshes into one: a whole neuron or tractogram as one mesh, one draw call.

Positions, normals, UVs, colours and attributes are stacked, faces shifted by each piece's
vertex offset (32-bit indices unless 2^31 vertices are exceeded), and the weld recomputed over
all positions, so a viewer or a checker sees pieces that share a vertex as connected.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.meshing.weld import weld_by_position


def merge(pieces: Sequence[SurfaceMesh], name: str) -> SurfaceMesh:
    """One mesh of every piece, in order.

    Colours are kept when every piece has them, and an attribute when every piece has it;
    tangents when every piece has them; ``uv_lengths`` likewise. ``double_sided`` if any piece is.
    """
    if not pieces:
        raise ValueError("merge needs at least one mesh")
    counts = np.array([p.vertex_count for p in pieces], dtype=np.int64)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    total = int(counts.sum())
    index = np.int32 if total < 2**31 else np.int64
    faces = np.concatenate([p.faces.astype(index) + index(start) for p, start in zip(pieces, starts)])
    positions = np.concatenate([p.positions for p in pieces])

    def stacked(arrays):
        return None if any(a is None for a in arrays) else np.concatenate(arrays)

    attributes = None
    if all(p.attributes for p in pieces):
        keys = set.intersection(*(set(p.attributes) for p in pieces))
        attributes = {key: np.concatenate([p.attributes[key] for p in pieces]) for key in sorted(keys)}
    return SurfaceMesh(
        name=name,
        positions=positions,
        normals=np.concatenate([p.normals for p in pieces]),
        uvs=np.concatenate([p.uvs for p in pieces]),
        faces=faces,
        double_sided=any(p.double_sided for p in pieces),
        tangents=stacked([p.tangents for p in pieces]),
        uv_lengths=stacked([p.uv_lengths for p in pieces]),
        weld=weld_by_position(positions).astype(index),
        colors=stacked([p.colors for p in pieces]),
        attributes=attributes,
    )
