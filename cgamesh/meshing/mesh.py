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
    max_deviation: an upper bound of the largest distance of the mesh from its true surface
               over triangle interiors (file units), for tolerance-driven meshes (the a priori
               bound of cgamesh.meshing.tolerance.tolerance_plan, docs/tolerance.md).

    Optional, filled by meshers that know them exactly (None: exporters derive what they need):
    tangents:   (V, 4) float64 unit tangents along +u, orthogonal to the normals, and w = +-1 with
                the bitangent cross(normal, tangent) * w pointing along +v (glTF's TANGENT, in
                this frame; v as stored here, before any exporter's V flip).
    uv_lengths: (V, 2) float64 file-unit lengths that one unit of u and of v spans at each vertex
                (a tube: its circumference averaged along it, and its length; a cap: its
                diameter both ways): the natural-UV stage (uv.py) scales by them. May be a
                read-only broadcast view (a tube's grid has one pair of lengths).
    weld:       (V,) integer index of the first vertex at the bit-identical position (weld[i] <= i;
                seams and cap rims repeat vertices): exporters that weld points use it.
    colors:     (V, 3) float64 linear RGB in [0, 1] per vertex (glTF COLOR_0, USD displayColor).
    attributes: per-vertex raw values by lower-case name, each (V,) float64 (e.g. ``radius``,
                ``segment``, ``scalar``): glTF custom attributes ``_RADIUS`` ..., USD primvars.
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
    colors: np.ndarray | None = None
    attributes: dict[str, np.ndarray] | None = None

    @property
    def vertex_count(self) -> int:
        return int(self.positions.shape[0])

    @property
    def triangle_count(self) -> int:
        return int(self.faces.shape[0])
