"""Binary glTF 2.0 (.glb) export; glTF's own vocabulary stays inside this file.

Every surface becomes one mesh and one node of that name in the one default scene. The
conventions are the scene format's: glTF is +Y up and in metres, so a file with ``up: z`` maps
(x, y, z) to (x, z, -y) and every length is multiplied by ``meters_per_unit``. Positions are
stored as float32 relative to the node's translation (the float64 centre of the surface's
bounding box), which keeps float32's 24 bits of precision for the surface's size rather than
for its distance from the origin.

The document model is pygltflib's; the binary chunk is one numpy byte array that every
attribute is computed into in place, and the GLB container is assembled here: pygltflib's own
save path copies the blob several times and alone costs about as much as all of this module.
"""

from __future__ import annotations

import os
import struct
from collections.abc import Sequence
from importlib import metadata

import numpy as np
import pygltflib as g

from cgamesh.errors import ExportError
from cgamesh.export.atomic import atomic_write
from cgamesh.material import Material
from cgamesh.mesh import SurfaceMesh

_GLB_MAGIC = 0x46546C67  # b"glTF"
_CHUNK_JSON = 0x4E4F534A  # b"JSON"
_CHUNK_BIN = 0x004E4942  # b"BIN\0"

# Unit normals after the float32 cast are within ~1e-7 of length 1; an input normal further than
# this from unit length is a bug upstream (SurfaceMesh promises unit normals), not rounding.
_NORMAL_LENGTH_TOLERANCE = 1e-3

# Signed axis permutation (output axis j = sign_j * input axis src_j) from the scene's frame to
# glTF's +Y-up frame.
_AXIS_MAPS = {
    "z": ((0, 2, 1), (1.0, 1.0, -1.0)),  # (x, y, z) -> (x, z, -y), as Blender's exporter does
    "y": ((0, 1, 2), (1.0, 1.0, 1.0)),
}


def write_glb(
    path: str | os.PathLike[str],
    surfaces: Sequence[tuple[SurfaceMesh, Material]],
    *,
    up: str,
    meters_per_unit: float,
    source_units: str,
) -> int:
    """Write every (mesh, material) pair into one GLB file at ``path``; returns bytes written.

    ``up`` is the scene file's up axis ("z" or "y"), ``meters_per_unit`` its length unit in
    metres and ``source_units`` that unit's name (recorded in ``asset.extras``).

    Raises ExportError, leaving any existing file at ``path`` untouched, when an array holds a
    NaN or an infinity, shapes or indices are inconsistent, a mesh is empty, or the file cannot
    be written.
    """
    if up not in _AXIS_MAPS:
        raise ExportError(f"cannot export {path}: up must be 'z' or 'y', got {up!r}")
    scale = float(meters_per_unit)
    if not (np.isfinite(scale) and scale > 0.0):
        raise ExportError(f"cannot export {path}: meters_per_unit must be finite and > 0, got {meters_per_unit!r}")
    if len(surfaces) == 0:
        raise ExportError(f"cannot export {path}: no surfaces to write")

    layouts = [_check_mesh(mesh, path) for mesh, _ in surfaces]
    blob = np.zeros(sum(layout.nbytes for layout in layouts), dtype=np.uint8)

    doc = g.GLTF2(
        asset=g.Asset(
            generator=f"cgamesh {_version()}",
            extras={"source_units": source_units, "meters_per_unit": scale, "source_up": up},
        ),
        scene=0,
        scenes=[g.Scene(nodes=list(range(len(surfaces))))],
    )
    offset = 0
    for i, ((mesh, material), layout) in enumerate(zip(surfaces, layouts)):
        translation = _fill_mesh(doc, blob, offset, mesh, layout, up, scale, path)
        offset += layout.nbytes
        doc.materials.append(_material(mesh, material, path))
        doc.meshes.append(g.Mesh(name=mesh.name, primitives=[_primitive(doc, i)]))
        doc.nodes.append(g.Node(name=mesh.name, mesh=i, translation=translation))
    doc.buffers.append(g.Buffer(byteLength=int(blob.nbytes)))
    return _write_container(path, doc, blob)


class _Layout:
    """Index type and byte sizes of one mesh's four bufferViews, in blob order."""

    def __init__(self, vertex_count: int, triangle_count: int) -> None:
        self.vertex_count = vertex_count
        self.triangle_count = triangle_count
        # 65535 is the primitive-restart value for UNSIGNED_SHORT and must not be an index.
        self.index_dtype = np.dtype(np.uint16 if vertex_count <= 65535 else np.uint32)
        self.index_component = g.UNSIGNED_SHORT if self.index_dtype == np.uint16 else g.UNSIGNED_INT
        self.index_bytes = 3 * triangle_count * self.index_dtype.itemsize
        # positions, normals, uvs, indices: exact byte lengths, and the same padded to 4 bytes
        self.lengths = [12 * vertex_count, 12 * vertex_count, 8 * vertex_count, self.index_bytes]
        self.views = [_pad4(n) for n in self.lengths]
        self.nbytes = sum(self.views)


def _check_mesh(mesh: SurfaceMesh, path) -> _Layout:
    """Shapes and index ranges; the finiteness checks ride on the reductions in _fill_mesh."""
    v = mesh.vertex_count
    where = f"cannot export {path}: surface {mesh.name!r}"
    expected = {"positions": (v, 3), "normals": (v, 3), "uvs": (v, 2)}
    for name, shape in expected.items():
        got = np.shape(getattr(mesh, name))
        if got != shape:
            raise ExportError(f"{where}: {name} must have shape {shape}, got {got}")
    if np.ndim(mesh.faces) != 2 or np.shape(mesh.faces)[1] != 3:
        raise ExportError(f"{where}: faces must have shape (F, 3), got {np.shape(mesh.faces)}")
    if v == 0 or mesh.triangle_count == 0:
        raise ExportError(f"{where}: empty mesh ({v} vertices, {mesh.triangle_count} triangles)")
    if not np.issubdtype(np.asarray(mesh.faces).dtype, np.integer):
        raise ExportError(f"{where}: faces must be integers, got {np.asarray(mesh.faces).dtype}")
    lo, hi = int(mesh.faces.min()), int(mesh.faces.max())
    if lo < 0 or hi >= v:
        raise ExportError(f"{where}: face indices must be in [0, {v - 1}], got [{lo}, {hi}]")
    return _Layout(v, mesh.triangle_count)


def _fill_mesh(doc, blob, offset, mesh, layout, up, scale, path) -> list[float]:
    """Compute one mesh's attributes into ``blob`` from ``offset``; add bufferViews, accessors.

    Returns the node translation (bounding-box centre in glTF metres, float64).
    """
    where = f"cannot export {path}: surface {mesh.name!r}"
    src, sign = _AXIS_MAPS[up]
    perm = list(src)
    factor = np.asarray(sign) * scale
    v = layout.vertex_count
    base = len(doc.bufferViews)
    views = []
    targets = [g.ARRAY_BUFFER] * 3 + [g.ELEMENT_ARRAY_BUFFER]
    for nbytes, padded, target in zip(layout.lengths, layout.views, targets):
        doc.bufferViews.append(g.BufferView(buffer=0, byteOffset=offset, byteLength=nbytes, target=target))
        views.append(blob[offset : offset + padded])
        offset += padded
    pos_out = views[0].view(np.float32).reshape(v, 3)
    nrm_out = views[1].view(np.float32).reshape(v, 3)
    uv_out = views[2].view(np.float32).reshape(v, 2)
    idx_out = views[3][: layout.index_bytes].view(layout.index_dtype).reshape(-1, 3)

    positions = np.asarray(mesh.positions, dtype=np.float64)
    lo, hi = _bounds(positions)
    if not (np.isfinite(lo).all() and np.isfinite(hi).all()):
        raise ExportError(f"{where}: positions contain NaN or infinity")
    centre = 0.5 * (lo + hi)
    _map_axes(pos_out, positions, perm, factor, shift=centre)
    pos_min, pos_max = _bounds(pos_out)  # from the exact float32 values stored
    if not (np.isfinite(pos_min).all() and np.isfinite(pos_max).all()):
        raise ExportError(f"{where}: positions overflow float32 after scaling by {scale}")

    normals = np.asarray(mesh.normals, dtype=np.float64)
    length = np.sqrt(np.einsum("ij,ij->i", normals, normals))
    bad = ~(np.abs(length - 1.0) <= _NORMAL_LENGTH_TOLERANCE)  # NaN compares False: caught too
    if bad.any():
        k = int(np.argmax(bad))
        raise ExportError(f"{where}: normals must be finite unit vectors, vertex {k} has {normals[k].tolist()}")
    # Normalise in float64 and round once: the stored float32 vector is then as close to unit
    # length as float32 allows (the validator checks it), with the axis map applied.
    _map_axes(nrm_out, normals, perm, np.asarray(sign), divisor=length)

    uvs = np.asarray(mesh.uvs, dtype=np.float64)
    if not np.isfinite(_bounds(uvs)).all():
        raise ExportError(f"{where}: uvs contain NaN or infinity")
    # glTF puts the UV origin at the top-left of the image; SurfaceMesh at the bottom-left.
    uv_out[:, 0] = uvs[:, 0]
    np.subtract(1.0, uvs[:, 1], out=uv_out[:, 1], casting="same_kind")

    np.copyto(idx_out, mesh.faces, casting="unsafe")  # range checked in _check_mesh

    doc.accessors += [
        g.Accessor(bufferView=base, componentType=g.FLOAT, count=v, type=g.VEC3,
                   min=pos_min.tolist(), max=pos_max.tolist()),
        g.Accessor(bufferView=base + 1, componentType=g.FLOAT, count=v, type=g.VEC3),
        g.Accessor(bufferView=base + 2, componentType=g.FLOAT, count=v, type=g.VEC2),
        g.Accessor(bufferView=base + 3, componentType=layout.index_component,
                   count=3 * layout.triangle_count, type=g.SCALAR),
    ]
    return (centre[perm] * factor).tolist()


def _bounds(a: np.ndarray) -> np.ndarray:
    """(2, k) per-column minimum and maximum of an (n, k) array.

    Column by column because numpy's axis-0 reduction over a narrow (n, 3) array is ~20x
    slower than k strided 1-d reductions. NaN propagates through min / max and an infinity
    shows in them, so finite bounds also prove the whole array finite, with no extra pass.
    """
    return np.array([[a[:, j].min() for j in range(a.shape[1])], [a[:, j].max() for j in range(a.shape[1])]])


def _map_axes(out, a, perm, factor, *, shift=None, divisor=None) -> None:
    """out[:, j] = (a[:, perm[j]] - shift[perm[j]]) / divisor * factor[j], rounded once to out.dtype.

    a: (n, 3) float64; out: (n, 3) float32 view into the blob; divisor: (n,) or None.
    Column by column through one float64 scratch column: ~3x faster than fancy indexing the
    whole (n, 3) array, and every operation stays in float64 until the single final rounding.
    """
    tmp = np.empty(a.shape[0])
    for j, s in enumerate(perm):
        if shift is None:
            tmp[:] = a[:, s]
        else:
            np.subtract(a[:, s], shift[s], out=tmp)
        if divisor is not None:
            np.divide(tmp, divisor, out=tmp)
        np.multiply(tmp, factor[j], out=out[:, j], casting="same_kind")


def _primitive(doc, index: int) -> g.Primitive:
    """The triangle primitive of mesh ``index``, whose four accessors are the last added."""
    first = len(doc.accessors) - 4
    return g.Primitive(
        attributes=g.Attributes(POSITION=first, NORMAL=first + 1, TEXCOORD_0=first + 2),
        indices=first + 3,
        material=index,
        mode=g.TRIANGLES,
    )


def _material(mesh: SurfaceMesh, material: Material, path) -> g.Material:
    values = [*material.color, material.metallic, material.roughness]
    if len(material.color) != 3 or not all(np.isfinite(x) and 0.0 <= x <= 1.0 for x in values):
        raise ExportError(
            f"cannot export {path}: surface {mesh.name!r}: material color, metallic and roughness "
            f"must be in [0, 1], got {material}"
        )
    return g.Material(
        name=mesh.name,
        pbrMetallicRoughness=g.PbrMetallicRoughness(
            baseColorFactor=[float(c) for c in material.color] + [1.0],
            metallicFactor=float(material.metallic),
            roughnessFactor=float(material.roughness),
        ),
        doubleSided=bool(mesh.double_sided),
    )


def _write_container(path, doc: g.GLTF2, blob: np.ndarray) -> int:
    """GLB: 12-byte header, JSON chunk padded with spaces, BIN chunk padded with zeros."""
    try:
        text = doc.gltf_to_json(separators=(",", ":"), indent=None)  # allow_nan=False inside
    except ValueError as exc:
        raise ExportError(f"cannot export {path}: {exc}") from exc
    json_bytes = text.encode("utf-8")
    json_bytes += b" " * (_pad4(len(json_bytes)) - len(json_bytes))
    # Each mesh's views are padded to 4 bytes, so the blob already is.
    total = 12 + 8 + len(json_bytes) + 8 + blob.nbytes
    if total >= 2**32:  # the GLB header stores the length as uint32
        raise ExportError(f"cannot export {path}: {total} bytes exceed the GLB format's 4 GiB limit")
    with atomic_write(path) as f:
        f.write(struct.pack("<III", _GLB_MAGIC, 2, total))
        f.write(struct.pack("<II", len(json_bytes), _CHUNK_JSON))
        f.write(json_bytes)
        f.write(struct.pack("<II", blob.nbytes, _CHUNK_BIN))
        f.write(memoryview(blob))
    return total


def _pad4(n: int) -> int:
    return (n + 3) & ~3


def _version() -> str:
    try:
        return metadata.version("cgamesh")
    except metadata.PackageNotFoundError:  # running from a source tree that was not installed
        return "unknown"
