"""The triangle mesh of one surface, as plain arrays in the scene file's own frame."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class SurfaceMesh:
    """A triangulated surface ready for export.

    Coordinates are in the scene file's frame and units (no axis swap, no unit scaling:
    the exporters apply those).

    positions: (V, 3) float64 vertex positions.
    normals:   (V, 3) float64 unit vertex normals.
    uvs:       (V, 2) float64 texture coordinates, u around / across, v along; the meshers give
               them in [0, 1], the scene's ``uv`` mode (uv.py) may rescale or replace them;
               v = 0 at the surface's start (exporters flip to their own V convention).
    faces:     (F, 3) integer vertex indices (int32 from the meshers), counter-clockwise seen from the normals' side.
    name:      the surface's name from the scene file.
    double_sided: True for surfaces meant to be seen from both sides (ribbons).
    max_deviation: the measured largest distance of the mesh from its true surface over
               triangle interiors (file units), when it was measured (tolerance-driven meshes).
    """

    name: str
    positions: np.ndarray
    normals: np.ndarray
    uvs: np.ndarray
    faces: np.ndarray
    double_sided: bool = False
    tangents: np.ndarray | None = None
    uv_lengths: np.ndarray | None = None
    weld: np.ndarray | None = None
    max_deviation: float | None = None

    @property
    def vertex_count(self) -> int:
        return int(self.positions.shape[0])

    @property
    def triangle_count(self) -> int:
        return int(self.faces.shape[0])
