"""Meshes read back from a glTF binary (.glb) into the scene file's own frame and units.

The exporter's mapping is undone: node transforms are applied (the exporter stores positions
relative to a node translation, and with KHR_mesh_quantization as normalised integers under a
dequantising translation and scale), then glTF's +Y-up metres go back to the scene file's
axes and units: for ``up: z`` glTF (X, Y, Z) is the scene's (x, z, -y), so (x, y, z) =
(X, -Z, Y); lengths are divided by the file's metres per unit. Normals get the inverse
transpose of the node matrices and the same axis map, and are normalised.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from cgamesh.readers.files import UnreadableFileError
from cgamesh.readers.gltf_reader import GltfFile, invertible_linear_part


@dataclass(frozen=True)
class MeshData:
    """One mesh in the scene's frame: positions (V, 3), unit normals (V, 3), faces (F, 3)."""

    name: str
    positions: np.ndarray
    normals: np.ndarray
    faces: np.ndarray
    double_sided: bool


def read_glb(path: str | os.PathLike, up: str, meters_per_unit: float, limit: int | None = None) -> list[MeshData]:
    """Every mesh instance of the file (one per node with a mesh), named after its mesh.

    The file is read by ``readers.gltf_reader`` (nothing it declares is trusted); a primitive
    without normals, or with a zero-length normal, cannot be traced along and is refused.
    ``limit``: the most bytes read and decoded (readers.files.read_limit; None for its default).
    """
    reader = GltfFile(path) if limit is None else GltfFile(path, limit)
    meshes = []
    for instance in reader.instances():
        parts, offset, double_sided = [], 0, False
        for k, primitive in enumerate(reader.primitives(instance.mesh)):
            where = f"meshes[{instance.mesh}].primitives[{k}]"
            if primitive.normals is None:
                raise UnreadableFileError(f"{reader.path}: {where} has no NORMAL; verify traces along the normals")
            size = np.linalg.norm(primitive.normals, axis=1)
            if np.any(size < 0.5):
                raise UnreadableFileError(f"{reader.path}: {where}.attributes.NORMAL element "
                                          f"{int(np.argmax(size < 0.5))} has length {size.min():.3g}; verify "
                                          "needs a direction to trace along")
            parts.append((primitive.positions, primitive.normals, primitive.faces + offset))
            offset += len(primitive.positions)
            double_sided |= primitive.double_sided
        positions = np.concatenate([p for p, _, _ in parts])
        normals = np.concatenate([n for _, n, _ in parts])
        faces = np.concatenate([f for _, _, f in parts])
        matrix = instance.matrix
        positions = positions @ matrix[:3, :3].T + matrix[:3, 3]
        normals = normals @ invertible_linear_part(reader, instance)  # the inverse transpose, applied to rows
        positions, normals = to_scene_frame(positions, up, meters_per_unit), to_scene_frame(normals, up, 1.0)
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        mesh = reader.item("meshes", instance.mesh, "mesh")
        node = reader.item("nodes", instance.node, "node")
        name = mesh.get("name") if isinstance(mesh.get("name"), str) else node.get("name")
        meshes.append(MeshData(name if isinstance(name, str) else f"mesh{instance.mesh}", positions, normals, faces,
                               double_sided))
    return meshes


def to_scene_frame(values: np.ndarray, up: str, meters_per_unit: float) -> np.ndarray:
    """glTF (X, Y, Z) in metres -> the scene file's (x, y, z) in its units."""
    out = values / meters_per_unit
    if up == "z":
        out = np.stack([out[:, 0], -out[:, 2], out[:, 1]], axis=1)
    return out
