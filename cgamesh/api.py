"""The Python API: any input to meshes in one call, for notebooks and pipelines.

    import cgamesh

    neuron = cgamesh.load("neuron.swc", color_by="radius")        # SWC, .trk, .tck, .trx, .npz, a scene...
    neuron.positions, neuron.normals, neuron.uvs, neuron.faces   # plain numpy arrays
    neuron.export("neuron.glb")                                   # any output format, written atomically

    bundle = cgamesh.tubes([line_a, line_b], radii=0.25)          # polylines as (n, 3) arrays
    tree = cgamesh.tubes(points, radii=r, parents=p)              # a skeleton: parent index, -1 for roots

Both return a ``Meshes``. Nothing heavy is imported until it is needed: reading a tractogram
imports nibabel, exporting USD imports usd-core, ``to_trimesh`` imports trimesh.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from cgamesh.errors import InvalidInputError
from cgamesh.material import Material
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.options import CENTERLINES, keywords

# cgamesh.tubes takes the centreline options but ``units``, which is its own parameter.
TUBE_KEYWORDS = tuple(name for name in keywords(CENTERLINES) if name != "units")


@dataclass(frozen=True)
class Meshes:
    """Meshes of one input with what the writers need to place them.

    surfaces: each mesh with its material (one mesh for a merged or watertight centreline
              input, one per surface of a scene, one per segment with ``split``).
    up:       the up axis of the coordinates ("z" or "y"); units, meters_per_unit: their length unit.
    skipped:  one line per centreline segment that could not be meshed (empty when all were).

    The array properties join every surface into one mesh (faces shifted accordingly).
    """

    surfaces: tuple[tuple[SurfaceMesh, Material], ...]
    up: str = "z"
    units: str = "m"
    meters_per_unit: float = 1.0
    skipped: tuple[str, ...] = ()

    @cached_property
    def _joined(self) -> SurfaceMesh:
        meshes = [mesh for mesh, _ in self.surfaces]
        if len(meshes) == 1:
            return meshes[0]
        from cgamesh.meshing.merge import merge

        return merge(meshes, "meshes")

    @property
    def positions(self) -> np.ndarray:
        """(V, 3) float64 vertex positions, in ``units``, ``up`` the file's up axis."""
        return self._joined.positions

    @property
    def normals(self) -> np.ndarray:
        """(V, 3) float64 unit vertex normals."""
        return self._joined.normals

    @property
    def uvs(self) -> np.ndarray:
        """(V, 2) float64 texture coordinates (u around, v along)."""
        return self._joined.uvs

    @property
    def faces(self) -> np.ndarray:
        """(F, 3) integer vertex indices, counter-clockwise seen from the normals' side."""
        return self._joined.faces

    @property
    def colors(self) -> np.ndarray | None:
        """(V, 3) float64 linear RGB per vertex, or None when no colouring was asked for."""
        return self._joined.colors

    @property
    def attributes(self) -> dict[str, np.ndarray]:
        """Per-vertex values by name, each (V,) float64: ``radius``, ``segment`` and, colouring by
        a field of the file, ``scalar`` (empty for scene files)."""
        return dict(self._joined.attributes or {})

    def export(self, path: str | os.PathLike[str], **options: bool) -> int:
        """Write every surface to ``path`` in the format of its extension (.glb, .gltf, .usda,
        .usdc, .usd, .usdz, .obj, .ply, .stl), atomically; returns the bytes written.

        ``options``: the writer options of the table in cgamesh.options (``write_keywords``):
        ``tangents``, ``quantize`` (glTF; other formats have no use for them).
        """
        from cgamesh import options as table
        from cgamesh.export.options import GltfOptions, WriteOptions
        from cgamesh.export.registry import write

        table.check_keywords(options, table.write_keywords())
        return write(path, list(self.surfaces), WriteOptions(self.up, self.meters_per_unit, self.units,
                                                             GltfOptions.from_options(options)))

    def to_trimesh(self):
        """One ``trimesh.Trimesh`` of every surface (welded seams kept apart: UVs differ there),
        with vertex normals, UVs and, when present, vertex colours."""
        import trimesh

        mesh = self._joined
        visual = trimesh.visual.TextureVisuals(uv=mesh.uvs)
        result = trimesh.Trimesh(vertices=mesh.positions, faces=mesh.faces, vertex_normals=mesh.normals,
                                 visual=visual, process=False)
        if mesh.colors is not None:
            rgba = np.concatenate([np.clip(mesh.colors, 0.0, 1.0), np.ones((mesh.vertex_count, 1))], axis=1)
            result.visual = trimesh.visual.ColorVisuals(result, vertex_colors=np.round(rgba * 255).astype(np.uint8))
        return result


def load(path: str | os.PathLike[str], **options: Any) -> Meshes:
    """Mesh any input file: a scene (.yaml/.yml), centrelines (.swc, .trk, .tck, .trx, .npz) or
    a file of a registered format (cgamesh.inputs.formats).

    Scene options: ``around``, ``along``, ``tolerance``, ``tangents`` (as on the command line).
    Centreline options (``cgamesh.pipelines.tube_options.TubeOptions``): ``radius``,
    ``min_radius``, ``units`` (nm, um, mm, cm, m; default the format's), ``up`` (x, y, z),
    ``around`` (8), ``subdivide`` (3) or ``tolerance``, ``color_by`` (none, radius,
    direction, segment or a per-point field), ``split``, ``watertight``, ``caps``, ``strict``.
    Both lists are ``cgamesh.options.keywords(kind)``, the table the command line's flags come
    from. Mistakes raise ``cgamesh.errors.InvalidInputError`` with a one-line message.
    """
    from cgamesh import options as table
    from cgamesh.inputs.formats import InputKind, format_of

    name = os.fspath(path)
    found = format_of(name)
    table.check_keywords(options, table.keywords(found.kind), found.kind)
    given = table.given(options)
    if found.kind is InputKind.SCENE:
        from cgamesh.pipelines.scene import Resolution, mesh_scene

        scene = found.read(name)
        surfaces = mesh_scene(scene, Resolution.from_options(given), tangents=bool(given.get("tangents", False)))
        return Meshes(tuple(surfaces), up=scene.up, units=scene.units, meters_per_unit=scene.meters_per_unit)
    from cgamesh.inputs.formats import read_centerlines

    return _mesh(read_centerlines(name, units=given.get("units")), given)


def tubes(polylines: np.ndarray | Sequence[np.ndarray], radii: float | np.ndarray | Sequence[np.ndarray] | None = None,
          parents: np.ndarray | None = None, *, scalars: dict[str, np.ndarray] | None = None, units: str = "m",
          name: str = "tubes", **options: Any) -> Meshes:
    """Tubes along polylines, or along a tree of points.

    polylines: a sequence of (n_i, 3) arrays (one tube each), or one (N, 3) array: a single
               polyline, or with ``parents`` the points of a tree.
    radii:     one radius for all, or per point: (N,) for a tree or a single polyline, or a
               sequence of (n_i,) arrays matching ``polylines``.
    parents:   (N,) parent index of each point, -1 for a root (several roots allowed).
    scalars:   per-point values by name, in the layout of ``radii`` (for ``color_by=NAME``).
    units:     the length unit of points and radii; ``name`` names the meshes and messages.
    options:   as for ``load``'s centreline options.
    """
    from cgamesh import options as table
    from cgamesh.inputs.arrays import centerlines_from_arrays
    from cgamesh.inputs.formats import InputKind

    table.check_keywords(options, TUBE_KEYWORDS, InputKind.CENTERLINES)
    options = table.given(options)
    arrays: dict[str, np.ndarray] = {}
    single = isinstance(polylines, np.ndarray) or (len(polylines) and np.ndim(polylines[0]) == 1)
    if parents is not None or single:
        arrays["points"] = np.asarray(polylines, dtype=np.float64)
        pieces = None
    else:
        pieces = polylines
        arrays["points"] = _concatenated(polylines, name)
    if parents is not None:
        arrays["parents"] = np.asarray(parents)
    else:
        lengths = (np.fromiter(map(len, pieces), dtype=np.int64, count=len(pieces)) if pieces is not None
                   else [len(arrays["points"])])
        arrays["offsets"] = np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64)
    if radii is not None and not isinstance(radii, (list, tuple)) and np.ndim(radii) == 0:
        options.setdefault("radius", float(radii))
    elif radii is not None:
        arrays["radii"] = _flat(radii, pieces, name, "radii")
    for key, values in (scalars or {}).items():
        if key in arrays:
            raise InvalidInputError(f"{name}: a scalar cannot be named {key!r}")
        arrays[key] = _flat(values, pieces, name, key)
    return _mesh(centerlines_from_arrays(arrays, name, units), options)


def _concatenated(polylines, name: str) -> np.ndarray:
    """The (n_i, 3) polylines as one (N, 3) float64 array, joined in one call (no Python step
    per polyline); only when that cannot give (N, 3) are they examined one by one, to name the
    first of the wrong shape."""
    if not len(polylines):
        return np.zeros((0, 3))
    try:
        points = np.concatenate(polylines, axis=0, dtype=np.float64)
    except (ValueError, TypeError):
        points = None
    if points is None or points.ndim != 2 or points.shape[1] != 3:
        pieces = [np.asarray(p, dtype=np.float64) for p in polylines]
        wrong = [p.shape for p in pieces if p.ndim != 2 or p.shape[1:] != (3,)]
        if wrong:
            raise InvalidInputError(f"{name}: expected polylines of shape (n, 3), got {wrong[0]}")
        points = np.concatenate(pieces)
    return points


def _flat(values, pieces, name: str, key: str) -> np.ndarray:
    if pieces is not None and isinstance(values, (list, tuple)) and len(values) == len(pieces) \
            and all(np.ndim(v) == 1 for v in values):
        return np.concatenate([np.asarray(v, dtype=np.float64) for v in values]) if values else np.zeros(0)
    try:
        return np.asarray(values, dtype=np.float64).reshape(-1)
    except (ValueError, TypeError):  # ragged, or not numbers
        count = "" if pieces is None else f" or {len(pieces)} arrays, one per polyline"
        raise InvalidInputError(f"{name}: expected {key} as numbers, one per point{count}; got "
                                f"{type(values).__name__} of {len(values) if hasattr(values, '__len__') else 1} "
                                "items that do not form one array") from None


def _mesh(lines, options: dict) -> Meshes:
    from cgamesh.pipelines.centerlines import TubeOptions, mesh_centerlines

    built = mesh_centerlines(lines, TubeOptions.from_options(options))
    return Meshes(tuple((mesh, built.material) for mesh in built.meshes), up=built.up, units=built.units,
                  meters_per_unit=built.meters_per_unit, skipped=built.skipped)
