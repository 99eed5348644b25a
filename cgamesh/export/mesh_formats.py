"""Wavefront OBJ (.obj + .mtl), PLY and STL export through trimesh, imported only for these formats.

These formats record neither units nor an up axis, so coordinates are written as the scene
file states them: its own frame and units, no axis swap and no scaling.

- .obj: one object (``o NAME``) per surface, with its vertex normals (``vn``), UVs (``vt``)
  and a material of that name in ``STEM.mtl`` beside it (diffuse colour ``Kd``). Both files
  are renamed into place together.
- .ply: binary little-endian, every surface concatenated into one mesh, with vertex normals
  and UVs (properties s, t). When any surface has vertex colours, every vertex gets 8-bit
  sRGB-encoded ``red green blue alpha`` (the PLY convention; a surface without colours takes its
  material's colour), and every per-vertex attribute that all surfaces carry is a float32 vertex
  property of its name (``radius``, ``segment`` ...); an attribute missing from some surface is
  not written (PLY has no "absent" value).
- .stl: binary, every surface concatenated; STL stores triangles with face normals only, so
  vertex normals, UVs, colours and attributes are not written.
- .obj: OBJ has no standard per-vertex colour or attribute (the ``v x y z r g b`` extension is
  not read by every tool), so colours and attributes are not written; the material's colour is.
"""

from __future__ import annotations

import os
import re
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from cgamesh.errors import ExportError
from cgamesh.export.atomic import atomic_files, atomic_write
from cgamesh.export.checks import check_surfaces
from cgamesh.export.options import WriteOptions
from cgamesh.material import Material
from cgamesh.meshing.colors import linear_to_srgb
from cgamesh.meshing.mesh import SurfaceMesh

SUFFIXES = (".obj", ".ply", ".stl")
_INDEX = re.compile(rb"\d+")


def write_mesh_format(
    path: str | os.PathLike[str],
    surfaces: Sequence[tuple[SurfaceMesh, Material]],
    options: WriteOptions,
) -> int:
    """Write every surface to the .obj, .ply or .stl file at ``path``; returns the bytes written.

    The up axis and unit of ``options`` are checked but, having no place in these formats, not
    applied.
    """
    target = Path(path)
    suffix = target.suffix.lower()
    if suffix not in SUFFIXES:
        raise ExportError(f"cannot export {path}: expected one of {', '.join(SUFFIXES)}, got {suffix!r}")
    check_surfaces(path, surfaces, options.up, options.meters_per_unit)  # the values are checked, not rescaled
    from cgamesh.optional import require

    trimesh = require("trimesh", "formats", f"{suffix} export")
    if suffix == ".obj":
        return _write_obj(trimesh, target, surfaces)
    mesh = _concatenated(trimesh, surfaces, with_attributes=suffix == ".ply")
    data = mesh.export(file_type=suffix[1:])
    with atomic_write(target) as f:
        f.write(data)
    return len(data)


def _trimesh(trimesh, mesh: SurfaceMesh, material: Material | None):
    visual = None
    if material is not None:
        rgba = np.rint(np.append(np.asarray(material.color, dtype=np.float64), 1.0) * 255).astype(np.uint8)
        visual = trimesh.visual.TextureVisuals(
            uv=np.asarray(mesh.uvs, dtype=np.float64),
            material=trimesh.visual.material.SimpleMaterial(diffuse=rgba, name=mesh.name))
    return trimesh.Trimesh(vertices=np.asarray(mesh.positions, dtype=np.float64),
                           faces=np.asarray(mesh.faces, dtype=np.int64),
                           vertex_normals=np.asarray(mesh.normals, dtype=np.float64),
                           visual=visual, process=False, validate=False)


def _concatenated(trimesh, surfaces, *, with_attributes: bool):
    offsets = np.cumsum([0] + [mesh.vertex_count for mesh, _ in surfaces])
    positions = np.concatenate([mesh.positions for mesh, _ in surfaces])
    faces = np.concatenate([np.asarray(mesh.faces, dtype=np.int64) + offset
                            for (mesh, _), offset in zip(surfaces, offsets)])
    if not with_attributes:
        return trimesh.Trimesh(vertices=positions, faces=faces, process=False, validate=False)
    normals = np.concatenate([mesh.normals for mesh, _ in surfaces])
    uvs = np.concatenate([mesh.uvs for mesh, _ in surfaces])
    if all(mesh.colors is None for mesh, _ in surfaces):
        visual = trimesh.visual.TextureVisuals(uv=uvs)
        vertex_attributes = {}
    else:
        # trimesh holds either UVs or colours as its visual: colours there, UVs as s, t below
        visual = trimesh.visual.ColorVisuals(vertex_colors=_ply_colors(surfaces))
        vertex_attributes = {"s": uvs[:, 0].astype(np.float32), "t": uvs[:, 1].astype(np.float32)}
    shared = set.intersection(*(set(mesh.attributes or ()) for mesh, _ in surfaces))
    for name in sorted(shared):
        vertex_attributes[name] = np.concatenate([np.asarray(mesh.attributes[name], dtype=np.float32)
                                                  for mesh, _ in surfaces])
    return trimesh.Trimesh(vertices=positions, faces=faces, vertex_normals=normals, visual=visual,
                           vertex_attributes=vertex_attributes, process=False, validate=False)


def _ply_colors(surfaces) -> np.ndarray:
    """(V, 4) uint8 sRGB-encoded RGBA of every vertex: its colour, or its material's."""
    parts = []
    for mesh, material in surfaces:
        linear = mesh.colors if mesh.colors is not None else np.broadcast_to(
            np.asarray(material.color, dtype=np.float64), (mesh.vertex_count, 3))
        parts.append(np.clip(np.asarray(linear, dtype=np.float64), 0.0, 1.0))
    srgb = linear_to_srgb(np.concatenate(parts))
    rgba = np.full((len(srgb), 4), 255, dtype=np.uint8)
    rgba[:, :3] = np.rint(srgb * 255.0)
    return rgba


def _write_obj(trimesh, target: Path, surfaces) -> int:
    """Each surface exported alone (trimesh's scene export recomputes normals), then joined:
    the face indices of later objects are offset by the vertices before them."""
    from trimesh.exchange.obj import export_obj

    mtl_path = target.with_suffix(".mtl")
    if mtl_path == target:
        raise ExportError(f"cannot export {target}: an .obj file needs a name that does not end in .mtl")
    parts = [f"# cgamesh\nmtllib {mtl_path.name}\n".encode()]
    materials = []
    offset = 0
    for mesh, material in surfaces:
        text, files = export_obj(_trimesh(trimesh, mesh, material), include_normals=True, include_color=False,
                                 include_texture=True, return_texture=True, mtl_name=mtl_path.name, header=None)
        body = text.encode()
        body = body[body.index(b"usemtl"):] if b"usemtl" in body else body
        start = body.find(b"\nf ")
        if offset and start >= 0:
            shift = offset
            body = body[:start] + _INDEX.sub(lambda m: str(int(m.group()) + shift).encode(), body[start:])
        parts.append(f"\no {mesh.name}\n".encode() + body + b"\n")
        mtl = files.get(mtl_path.name, b"").decode()
        materials.append(mtl[mtl.find("newmtl"):].strip() if "newmtl" in mtl else f"newmtl {mesh.name}")
        offset += mesh.vertex_count
    obj_bytes = b"".join(parts)
    mtl_bytes = ("# cgamesh\n\n" + "\n\n".join(materials) + "\n").encode()
    with atomic_files([mtl_path, target]) as (mtl_file, obj_file):
        mtl_file.write(mtl_bytes)
        obj_file.write(obj_bytes)
    return len(obj_bytes) + len(mtl_bytes)
