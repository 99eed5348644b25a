"""Read exported files back into SurfaceMeshes (for ``cgamesh check`` and round-trip tests).

Each reader imports its format library only when called. Positions are returned as the file
stores them after dequantisation, without node / xform transforms (the report's measures do
not depend on them); ``read_gltf(world=True)`` applies the glTF node transforms.
"""

from __future__ import annotations

from pathlib import Path
from urllib.parse import unquote

import numpy as np

from cgamesh.errors import InvalidInputError
from cgamesh.meshing.colors import srgb_to_linear
from cgamesh.meshing.mesh import SurfaceMesh

_GLTF_DTYPES = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_GLTF_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}


def gltf_accessor(gltf, blob: bytes, index: int) -> np.ndarray:
    """(count, width) float64 (or integer, for indices) values of accessor ``index``, dequantised
    when normalized; honours byteStride."""
    acc = gltf.accessors[index]
    view = gltf.bufferViews[acc.bufferView]
    dtype = np.dtype(_GLTF_DTYPES[acc.componentType])
    width = _GLTF_WIDTH[acc.type]
    stride = view.byteStride or dtype.itemsize * width
    start = (view.byteOffset or 0) + (acc.byteOffset or 0)
    raw = np.frombuffer(blob, np.uint8, stride * (acc.count - 1) + dtype.itemsize * width, start)
    rows = np.lib.stride_tricks.as_strided(raw, (acc.count, dtype.itemsize * width), (stride, 1))
    values = np.ascontiguousarray(rows).view(dtype).reshape(acc.count, width)
    if acc.normalized:
        bound = float(np.iinfo(dtype).max)
        return np.maximum(values.astype(np.float64) / bound, -1.0)
    return values


def _gltf_blob(gltf, path: Path) -> bytes:
    buffer = gltf.buffers[0]
    if buffer.uri is None:
        return gltf.binary_blob()
    if buffer.uri.startswith("data:"):
        return gltf.decode_data_uri(buffer.uri)
    return (path.parent / unquote(buffer.uri)).read_bytes()


def read_gltf(path: str | Path, world: bool = False) -> list[SurfaceMesh]:
    """Every mesh's first primitive; UVs back in SurfaceMesh's bottom-left origin (v = 1 - V).

    ``COLOR_0`` becomes ``colors`` (RGB; an alpha channel is dropped) and every SCALAR
    application-specific attribute ``_NAME`` an entry ``name`` of ``attributes``; other
    attributes (TEXCOORD_1, JOINTS_0, vector-valued custom ones ...) are ignored.

    ``world``: positions and normals through the node's translation / rotation / scale.
    """
    import pygltflib

    path = Path(path)
    gltf = pygltflib.GLTF2().load(str(path))
    blob = _gltf_blob(gltf, path)
    nodes = {node.mesh: node for node in gltf.nodes if node.mesh is not None}
    out = []
    for index, gmesh in enumerate(gltf.meshes):
        prim = gmesh.primitives[0]
        positions = gltf_accessor(gltf, blob, prim.attributes.POSITION).astype(np.float64)
        normals = gltf_accessor(gltf, blob, prim.attributes.NORMAL).astype(np.float64)
        if prim.attributes.TEXCOORD_0 is not None:
            uvs = gltf_accessor(gltf, blob, prim.attributes.TEXCOORD_0).astype(np.float64)
            uvs[:, 1] = 1.0 - uvs[:, 1]
        else:
            uvs = np.zeros((len(positions), 2))
        tangents = None
        if prim.attributes.TANGENT is not None:
            tangents = gltf_accessor(gltf, blob, prim.attributes.TANGENT).astype(np.float64)
        faces = gltf_accessor(gltf, blob, prim.indices).reshape(-1, 3).astype(np.int64)
        node = nodes.get(index)
        if world and node is not None:
            scale = np.asarray(node.scale or [1.0, 1.0, 1.0])
            rotation = _quaternion_matrix(node.rotation or [0.0, 0.0, 0.0, 1.0])
            positions = (positions * scale) @ rotation.T + np.asarray(node.translation or [0.0, 0.0, 0.0])
            normals = (normals / scale) @ rotation.T
            if tangents is not None:
                tangents[:, :3] = (tangents[:, :3] * scale) @ rotation.T
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        if tangents is not None:
            tangents[:, :3] /= np.linalg.norm(tangents[:, :3], axis=1, keepdims=True)
        double_sided = bool(prim.material is not None and gltf.materials[prim.material].doubleSided)
        colors, attributes = _gltf_channels(gltf, blob, prim.attributes)
        out.append(SurfaceMesh(gmesh.name or f"mesh{index}", positions, normals, uvs, faces, double_sided,
                               tangents=tangents, colors=colors, attributes=attributes))
    return out


def _gltf_channels(gltf, blob: bytes, attributes) -> tuple[np.ndarray | None, dict[str, np.ndarray] | None]:
    """COLOR_0 as (V, 3) float64 RGB and the SCALAR ``_NAME`` attributes by lower-case name."""
    colors = None
    if getattr(attributes, "COLOR_0", None) is not None:
        colors = gltf_accessor(gltf, blob, attributes.COLOR_0)[:, :3].astype(np.float64)
    custom = {}
    for semantic, index in vars(attributes).items():
        if semantic.startswith("_") and index is not None and gltf.accessors[index].type == "SCALAR":
            custom[semantic[1:].lower()] = gltf_accessor(gltf, blob, index)[:, 0].astype(np.float64)
    return colors, custom or None


def _quaternion_matrix(q) -> np.ndarray:
    x, y, z, w = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def read_usd(path: str | Path) -> list[SurfaceMesh]:
    """Every UsdGeom.Mesh of the stage, one stored vertex per triangle corner (USD's points
    are welded; faceVarying normals and st differ per corner). ``primvars:displayColor``
    becomes ``colors`` and every other authored scalar float primvar an entry of
    ``attributes``; primvars of other types are ignored."""
    from cgamesh.optional import require

    require("pxr", "usd", "reading USD")
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.Open(str(path))
    if stage is None:
        raise InvalidInputError(f"{path}: usd-core cannot open this file")
    out = []
    for prim in stage.Traverse():
        if not prim.IsA(UsdGeom.Mesh):
            continue
        mesh = UsdGeom.Mesh(prim)
        corners = expand_usd_mesh(mesh, channels=True)
        count = len(corners["points"])
        attributes = {name[len(ATTRIBUTE_KEY):]: values[:, 0] for name, values in corners.items()
                      if name.startswith(ATTRIBUTE_KEY)}
        out.append(SurfaceMesh(prim.GetName(), corners["points"], corners["normals"], corners["st"],
                               np.arange(count, dtype=np.int64).reshape(-1, 3),
                               bool(mesh.GetDoubleSidedAttr().Get()), colors=corners.get("displayColor"),
                               attributes=attributes or None))
    return out


# expand_usd_mesh's key prefix for the scalar float primvars it reads with channels=True
ATTRIBUTE_KEY = "attribute:"


def expand_usd_mesh(mesh, channels: bool = False) -> dict[str, np.ndarray]:
    """points, normals, st (3F, k) per triangle corner of a triangulated UsdGeom.Mesh.

    ``channels``: also displayColor (3F, 3) when authored, and every other authored float[]
    primvar as ``"attribute:" + name`` (3F, 1).
    """
    from pxr import Sdf, UsdGeom

    points = np.asarray(mesh.GetPointsAttr().Get(), dtype=np.float64)
    counts = np.asarray(mesh.GetFaceVertexCountsAttr().Get())
    indices = np.asarray(mesh.GetFaceVertexIndicesAttr().Get(), dtype=np.int64)
    if not (counts == 3).all():
        raise InvalidInputError(f"{mesh.GetPath()}: only triangle meshes can be read back")
    primvars = UsdGeom.PrimvarsAPI(mesh.GetPrim())
    out = {"points": points[indices]}
    for name, width in (("normals", 3), ("st", 2)):
        primvar = primvars.GetPrimvar(name)
        if not primvar or primvar.Get() is None:
            out[name] = np.zeros((len(indices), width))
            continue
        out[name] = _corner_values(primvar, indices, width)
    if channels:
        for primvar in primvars.GetAuthoredPrimvars():
            name = primvar.GetPrimvarName()
            if primvar.Get() is None:
                continue
            if name == "displayColor":
                out[name] = _corner_values(primvar, indices, 3)
            elif name not in ("normals", "st") and primvar.GetTypeName() in (Sdf.ValueTypeNames.FloatArray,
                                                                            Sdf.ValueTypeNames.DoubleArray):
                out[ATTRIBUTE_KEY + name] = _corner_values(primvar, indices, 1)
    return out


def _corner_values(primvar, indices: np.ndarray, width: int) -> np.ndarray:
    """(3F, width) float64 values of a primvar at each triangle corner, by its interpolation."""
    from pxr import UsdGeom

    values = np.asarray(primvar.ComputeFlattened(), dtype=np.float64).reshape(-1, width)
    interpolation = primvar.GetInterpolation()
    if interpolation in (UsdGeom.Tokens.vertex, UsdGeom.Tokens.varying):
        return values[indices]
    if interpolation == UsdGeom.Tokens.faceVarying:
        return values
    if interpolation == UsdGeom.Tokens.uniform:
        return np.repeat(values, 3, axis=0)
    return np.broadcast_to(values[:1], (len(indices), width)).copy()  # constant


def read_trimesh(path: str | Path) -> list[SurfaceMesh]:
    """OBJ / PLY / STL through trimesh, one mesh per geometry, with the file's vertex normals
    (STL: the face normals, spread to the vertices) and UVs (zeros where the file has none).
    A PLY file's 8-bit vertex colours (sRGB-encoded) come back as linear ``colors`` and its
    other scalar vertex properties as ``attributes``."""
    from cgamesh.optional import require

    trimesh = require("trimesh", "formats", "reading OBJ / PLY / STL")
    loaded = trimesh.load(str(path), force="scene", process=False)
    out = []
    for name, geometry in loaded.geometry.items():
        positions = np.asarray(geometry.vertices, dtype=np.float64)
        faces = np.asarray(geometry.faces, dtype=np.int64)
        normals = np.asarray(geometry.vertex_normals, dtype=np.float64)
        uv = getattr(geometry.visual, "uv", None)
        uvs = np.asarray(uv, dtype=np.float64) if uv is not None and len(uv) == len(positions) else np.zeros((len(positions), 2))
        colors, attributes = _ply_channels(geometry, len(positions))
        out.append(SurfaceMesh(str(name), positions, normals, uvs, faces, colors=colors, attributes=attributes))
    return out


# PLY vertex properties that are not per-vertex attributes
_PLY_STANDARD = {"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue", "alpha", "s", "t", "u", "v",
                 "texture_u", "texture_v"}


def _ply_channels(geometry, count: int) -> tuple[np.ndarray | None, dict[str, np.ndarray] | None]:
    """Vertex colours (linear, from 8-bit sRGB) and extra scalar vertex properties of a PLY mesh."""
    rgba = getattr(geometry, "vertex_attributes", {}).get("color")
    if rgba is None and getattr(geometry.visual, "kind", None) == "vertex":
        rgba = geometry.visual.vertex_colors
    colors = None
    if rgba is not None and len(rgba) == count:
        colors = srgb_to_linear(np.asarray(rgba)[:, :3].astype(np.float64) / 255.0)
    raw = geometry.metadata.get("_ply_raw", {}).get("vertex", {}).get("data")
    attributes = {}
    if raw is not None and raw.dtype.names is not None and len(raw) == count:
        for field in raw.dtype.names:
            if field not in _PLY_STANDARD and raw.dtype[field].shape == ():
                attributes[field] = np.asarray(raw[field], dtype=np.float64)
    return colors, attributes or None
