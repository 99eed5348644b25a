"""Output formats by file extension: one explicit table, filled here and nowhere else.

Each entry names the module and function that write the format; the module is imported only
when a file of that format is written, so no format library is loaded for another format
(pxr for USD, trimesh for OBJ / PLY / STL). Every writer has the signature

    write(path, surfaces, options: WriteOptions) -> int

and returns the bytes written; ``options`` (cgamesh.export.options) holds the frame and unit
every format needs and each format's own part, read only by that format's writer.
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from cgamesh.errors import InvalidInputError
from cgamesh.export.options import WriteOptions
from cgamesh.material import Material
from cgamesh.meshing.mesh import SurfaceMesh


@dataclass(frozen=True)
class Writer:
    module: str
    function: str
    description: str


WRITERS: dict[str, Writer] = {
    ".glb": Writer("cgamesh.export.gltf", "write_glb", "binary glTF 2.0"),
    ".gltf": Writer("cgamesh.export.gltf", "write_gltf", "glTF 2.0 JSON with a .bin beside it"),
    ".usda": Writer("cgamesh.export.usd", "write_usd", "USD text"),
    ".usdc": Writer("cgamesh.export.usd", "write_usd", "USD binary crate"),
    ".usd": Writer("cgamesh.export.usd", "write_usd", "USD (binary crate)"),
    ".usdz": Writer("cgamesh.export.usd", "write_usd", "USDZ package"),
    ".obj": Writer("cgamesh.export.mesh_formats", "write_mesh_format", "Wavefront OBJ with a .mtl beside it"),
    ".ply": Writer("cgamesh.export.mesh_formats", "write_mesh_format", "binary PLY"),
    ".stl": Writer("cgamesh.export.mesh_formats", "write_mesh_format", "binary STL"),
}


def writer_for(path: str | os.PathLike[str]) -> Writer:
    """The writer of ``path``'s extension (case-insensitive); InvalidInputError for an unknown one."""
    suffix = Path(path).suffix.lower()
    if suffix not in WRITERS:
        raise InvalidInputError(f"{path}: unknown output format {suffix or '(no extension)'!r}; "
                                f"expected one of {', '.join(WRITERS)}")
    return WRITERS[suffix]


def vertices_written(path: str | os.PathLike[str], surfaces: Sequence[tuple[SurfaceMesh, Material]]) -> tuple[int, str]:
    """(count, word) of the vertices a file of this format holds for ``surfaces``: USD welds
    them into points; STL stores three corners per triangle; the others keep every vertex."""
    suffix = Path(path).suffix.lower()
    if suffix in (".usda", ".usdc", ".usd", ".usdz"):
        from cgamesh.export.usd import point_count

        return point_count(surfaces), "points"
    if suffix == ".stl":
        return 3 * sum(mesh.triangle_count for mesh, _ in surfaces), "triangle corners"
    return sum(mesh.vertex_count for mesh, _ in surfaces), "vertices"


def written_files(path: str | os.PathLike[str]) -> list[Path]:
    """Every file writing ``path`` creates or replaces: the file and its sidecar (.gltf: STEM.bin,
    .obj: STEM.mtl)."""
    path = Path(path)
    sidecar = {".gltf": ".bin", ".obj": ".mtl"}.get(path.suffix.lower())
    return [path] if sidecar is None else [path, path.with_suffix(sidecar)]


def check_distinct(outputs: Sequence[str | os.PathLike[str]], report: str | os.PathLike[str] | None = None,
                   scene: str | os.PathLike[str] | None = None) -> None:
    """InvalidInputError unless every file a run writes is a different file, and none is the
    scene: two -o naming one file (or one's sidecar), or --report naming an output, would
    overwrite one output with another."""
    claimed: dict[str, str] = {}

    def claim(path: Path, by: str) -> None:
        key = os.path.realpath(path)
        if key in claimed:
            raise InvalidInputError(f"{by} would overwrite {claimed[key]}: give each output its own file")
        claimed[key] = by

    if scene is not None:
        claimed[os.path.realpath(scene)] = f"the scene file {scene}"
    for output in outputs:
        for file in written_files(output):
            claim(file, f"-o {output}" if file == Path(output) else f"-o {output} (its {file.name})")
    if report is not None:
        claim(Path(report), f"--report {report}")


def write(path: str | os.PathLike[str], surfaces: Sequence[tuple[SurfaceMesh, Material]],
          options: WriteOptions) -> int:
    """Write ``surfaces`` in the format of ``path``'s extension; returns the bytes written."""
    writer = writer_for(path)
    function = getattr(importlib.import_module(writer.module), writer.function)
    return function(path, surfaces, options)
