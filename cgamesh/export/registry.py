"""Output formats by file extension: one explicit table, filled here and nowhere else.

Each entry names the module and function that write the format; the module is imported only
when a file of that format is written, so no format library is loaded for another format
(pxr for USD, trimesh for OBJ / PLY / STL). Every writer has the signature

    write(path, surfaces, *, up, meters_per_unit, source_units, tangents=False, quantize=False) -> int

and returns the bytes written.
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from cgamesh.errors import InvalidInputError
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


def write(path: str | os.PathLike[str], surfaces: Sequence[tuple[SurfaceMesh, Material]], *, up: str,
          meters_per_unit: float, source_units: str, tangents: bool = False, quantize: bool = False) -> int:
    """Write ``surfaces`` in the format of ``path``'s extension; returns the bytes written."""
    writer = writer_for(path)
    function = getattr(importlib.import_module(writer.module), writer.function)
    return function(path, surfaces, up=up, meters_per_unit=meters_per_unit, source_units=source_units,
                    tangents=tangents, quantize=quantize)
