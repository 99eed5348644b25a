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

from cgamesh.errors import InvalidInputError

_DTYPES = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_WIDTHS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}


@dataclass(frozen=True)
class MeshData:
    """One mesh in the scene's frame: positions (V, 3), unit normals (V, 3), faces (F, 3)."""

    name: str
    positions: np.ndarray
    normals: np.ndarray
    faces: np.ndarray
    double_sided: bool


def _accessor(gltf, blob: bytes, index: int) -> np.ndarray:
    accessor = gltf.accessors[index]
    view = gltf.bufferViews[accessor.bufferView]
    dtype = np.dtype(_DTYPES[accessor.componentType])
    width = _WIDTHS[accessor.type]
    item = dtype.itemsize * width
    stride = view.byteStride or item
    start = (view.byteOffset or 0) + (accessor.byteOffset or 0)
    raw = np.frombuffer(blob, np.uint8, stride * (accessor.count - 1) + item, start)
    rows = np.lib.stride_tricks.as_strided(raw, (accessor.count, item), (stride, 1))
    values = np.ascontiguousarray(rows).view(dtype).reshape(accessor.count, width)
    if accessor.normalized:
        return np.maximum(values.astype(np.float64) / float(np.iinfo(dtype).max), -1.0)
    return values


def _node_matrix(node) -> np.ndarray:
    if node.matrix is not None:
        return np.asarray(node.matrix, dtype=np.float64).reshape(4, 4).T  # glTF stores column-major
    x, y, z, w = node.rotation or (0.0, 0.0, 0.0, 1.0)
    rotation = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])
    out = np.eye(4)
    out[:3, :3] = rotation * np.asarray(node.scale or (1.0, 1.0, 1.0))[None, :]
    out[:3, 3] = node.translation or (0.0, 0.0, 0.0)
    return out


def _world_matrices(gltf) -> dict[int, np.ndarray]:
    """Node index -> world matrix (4, 4) for every node reachable from the scene's roots."""
    scene = gltf.scenes[gltf.scene or 0] if gltf.scenes else None
    roots = scene.nodes if scene is not None else range(len(gltf.nodes))
    out, stack = {}, [(k, np.eye(4)) for k in roots]
    while stack:
        k, parent = stack.pop()
        out[k] = parent @ _node_matrix(gltf.nodes[k])
        stack.extend((child, out[k]) for child in (gltf.nodes[k].children or []))
    return out


def read_glb(path: str | os.PathLike, up: str, meters_per_unit: float) -> list[MeshData]:
    """Every mesh instance of the file (one per node with a mesh), named after its mesh."""
    import pygltflib

    name = os.fsdecode(path)
    try:
        gltf = pygltflib.GLTF2().load(name)
    except Exception as exc:  # pygltflib raises assorted errors for unreadable files
        raise InvalidInputError(f"{name}: cannot read the glTF file: {exc}") from exc
    if gltf is None:
        raise InvalidInputError(f"{name}: cannot read the glTF file")
    blob = gltf.binary_blob()
    if blob is None:
        buffer = gltf.buffers[0]
        if buffer.uri.startswith("data:"):
            blob = gltf.decode_data_uri(buffer.uri)
        else:
            with open(os.path.join(os.path.dirname(name), buffer.uri), "rb") as stream:
                blob = stream.read()
    meshes = []
    for k, matrix in sorted(_world_matrices(gltf).items()):
        node = gltf.nodes[k]
        if node.mesh is None:
            continue
        mesh = gltf.meshes[node.mesh]
        parts = []
        offset = 0
        double_sided = False
        for primitive in mesh.primitives:
            positions = _accessor(gltf, blob, primitive.attributes.POSITION).astype(np.float64)
            normals = _accessor(gltf, blob, primitive.attributes.NORMAL).astype(np.float64)
            faces = _accessor(gltf, blob, primitive.indices).reshape(-1, 3).astype(np.int64)
            parts.append((positions, normals, faces + offset))
            offset += len(positions)
            if primitive.material is not None:
                double_sided |= bool(gltf.materials[primitive.material].doubleSided)
        positions = np.concatenate([p for p, _, _ in parts])
        normals = np.concatenate([n for _, n, _ in parts])
        faces = np.concatenate([f for _, _, f in parts])
        positions = positions @ matrix[:3, :3].T + matrix[:3, 3]
        normals = normals @ np.linalg.inv(matrix[:3, :3])  # the inverse transpose, applied to rows
        positions, normals = to_scene_frame(positions, up, meters_per_unit), to_scene_frame(normals, up, 1.0)
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        meshes.append(MeshData(mesh.name or node.name or f"mesh{node.mesh}", positions, normals, faces, double_sided))
    return meshes


def to_scene_frame(values: np.ndarray, up: str, meters_per_unit: float) -> np.ndarray:
    """glTF (X, Y, Z) in metres -> the scene file's (x, y, z) in its units."""
    out = values / meters_per_unit
    if up == "z":
        out = np.stack([out[:, 0], -out[:, 2], out[:, 1]], axis=1)
    return out
