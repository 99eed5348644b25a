"""Read exported files back into SurfaceMeshes (for ``cgamesh check`` and round-trip tests).

Each reader imports its format library only when called, and distrusts the file: glTF through
``readers.gltf_reader`` (every declared length, offset and index checked), USD and OBJ / PLY /
STL only after ``readers.files`` has found a regular file of bounded size, their libraries'
failures and diagnostics turned into one line, and every array taken from them checked
(shapes, counts, indices in range, finite values). Positions are returned as the file stores
them after dequantisation, without node / xform transforms (the report's measures do not
depend on them); ``read_gltf(world=True)`` applies the glTF node transforms. Normals are
returned as stored (a zero or non-unit normal is the report's to count), except through
``world`` transforms, where they are carried by the inverse transpose and normalised.

Per-vertex channels come back too, checked like the rest: glTF ``COLOR_0`` as ``colors``
(RGB; an alpha channel is dropped) and every SCALAR application-specific attribute ``_NAME``
as ``attributes["name"]``; USD ``primvars:displayColor`` and every other authored scalar
float primvar; a PLY file's 8-bit vertex colours (sRGB, returned linear) and other scalar
vertex properties.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from cgamesh.meshing.colors import srgb_to_linear
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.readers.files import MAX_FILE_BYTES, UnreadableFileError, check_regular, resolve_relative
from cgamesh.readers.gltf_reader import GltfFile, invertible_linear_part
from cgamesh.readers.library_calls import quiet_library


def read_gltf(path: str | Path, world: bool = False, limit: int = MAX_FILE_BYTES) -> list[SurfaceMesh]:
    """Every mesh's first primitive; UVs back in SurfaceMesh's bottom-left origin (v = 1 - V).

    ``world``: positions, normals and tangents through the world transform of the first node
    that shows the mesh. A primitive without NORMAL gets an empty (0, 3) normal array.
    ``COLOR_0`` becomes ``colors`` and every SCALAR ``_NAME`` attribute an entry ``name`` of
    ``attributes`` (neither depends on the transforms); other attributes (TEXCOORD_1,
    JOINTS_0, vector-valued custom ones ...) are ignored.
    """
    reader = GltfFile(path, limit)
    instances = {}
    for instance in reader.instances():  # checks the node graph even when its transforms are not used
        if world:
            instances.setdefault(instance.mesh, instance)
    out = []
    for index in range(reader.mesh_count()):
        primitive = reader.primitives(index, first_only=True)[0]
        positions = primitive.positions
        count = len(positions)
        normals = primitive.normals if primitive.normals is not None else np.zeros((0, 3))
        if primitive.uvs is not None:
            uvs = primitive.uvs.copy()
            uvs[:, 1] = 1.0 - uvs[:, 1]
        else:
            uvs = np.zeros((count, 2))
        tangents = primitive.tangents
        instance = instances.get(index)
        if instance is not None:
            linear, shift = instance.matrix[:3, :3], instance.matrix[:3, 3]
            positions = positions @ linear.T + shift
            normals = _unit(normals @ invertible_linear_part(reader, instance))
            if tangents is not None:
                tangents = tangents.copy()
                tangents[:, :3] = _unit(tangents[:, :3] @ linear.T)
        out.append(SurfaceMesh(reader.mesh_name(index), positions, normals, uvs, primitive.faces,
                               primitive.double_sided, tangents=tangents, colors=primitive.colors,
                               attributes=primitive.attributes))
    return out


def _unit(vectors: np.ndarray) -> np.ndarray:
    """Rows scaled to length 1; zero rows stay zero."""
    size = np.linalg.norm(vectors, axis=1, keepdims=True)
    return np.divide(vectors, size, out=np.zeros_like(vectors), where=size > 0.0)


# Most layers a USD file may pull in (sublayers, references, payloads, recursively).
MAX_USD_LAYERS = 64


def read_usd(path: str | Path, limit: int = MAX_FILE_BYTES) -> list[SurfaceMesh]:
    """``read_usd_here`` in a child process (``usd_sandbox``): a file that makes usd-core abort
    or stall costs the child, and the user gets one line."""
    from cgamesh.optional import require
    from cgamesh.readers.usd_sandbox import read_usd as read_in_child

    require("pxr", "usd", "reading USD")
    check_regular(path, limit)
    return read_in_child(path, limit)


def read_usd_here(path: str | Path, limit: int = MAX_FILE_BYTES) -> list[SurfaceMesh]:
    """Every UsdGeom.Mesh of the stage, one stored vertex per triangle corner (USD's points
    are welded; faceVarying normals and st differ per corner), read in this process.
    ``primvars:displayColor`` becomes ``colors`` and every other authored scalar float
    primvar an entry of ``attributes``; primvars of other types are ignored.

    The file must be a regular file; every layer it composes (sublayers, references,
    payloads) must be one too, inside its folder (``readers.files``), before usd-core opens
    the stage.
    """
    from cgamesh.optional import require

    require("pxr", "usd", "reading USD")
    from pxr import Sdf, Usd, UsdGeom

    name = os.fsdecode(path)
    check_regular(name, limit)
    with quiet_library(name, "usd-core"):
        layer = Sdf.Layer.FindOrOpen(name)
    if layer is None:
        raise UnreadableFileError(f"{name}: usd-core cannot open this file")
    _check_usd_dependencies(layer, name, limit)
    with quiet_library(name, "usd-core"):
        stage = Usd.Stage.Open(layer)
    if stage is None:
        raise UnreadableFileError(f"{name}: usd-core cannot open this file")
    out, budget = [], [limit]
    with quiet_library(name, "usd-core"):
        prims = [prim for prim in stage.Traverse() if prim.IsA(UsdGeom.Mesh)]
    for prim in prims:
        mesh = UsdGeom.Mesh(prim)
        corners = expand_usd_mesh(mesh, name, budget, channels=True)
        count = len(corners["points"])
        attributes = {key[len(ATTRIBUTE_KEY):]: values[:, 0] for key, values in corners.items()
                      if key.startswith(ATTRIBUTE_KEY)}
        with quiet_library(name, "usd-core"):
            double_sided = bool(mesh.GetDoubleSidedAttr().Get())
        out.append(SurfaceMesh(prim.GetName(), corners["points"], corners["normals"], corners["st"],
                               np.arange(count, dtype=np.int64).reshape(-1, 3), double_sided,
                               colors=corners.get("displayColor"), attributes=attributes or None))
    return out


def _check_usd_dependencies(root, name: str, limit: int) -> None:
    """Every layer ``root`` composes, recursively, a regular file inside its own folder."""
    from pxr import Sdf

    seen, todo = {root.identifier}, [root]
    while todo:
        layer = todo.pop()
        folder = os.path.dirname(os.path.abspath(layer.realPath or name))
        with quiet_library(name, "usd-core"):
            dependencies = list(layer.GetCompositionAssetDependencies())
        for reference in dependencies:
            label = f"{name}: the layer it composes"
            target = resolve_relative(folder, reference, label)
            check_regular(target, limit, f"{label} {reference!r}")
            key = str(target)
            if key in seen:
                continue
            seen.add(key)
            if len(seen) > MAX_USD_LAYERS:
                raise UnreadableFileError(f"{name}: composes more than {MAX_USD_LAYERS} layers; refused")
            with quiet_library(name, "usd-core"):
                child = Sdf.Layer.FindOrOpen(key)
            if child is None:
                raise UnreadableFileError(f"{label} {reference!r} cannot be opened")
            todo.append(child)


# expand_usd_mesh's key prefix for the scalar float primvars it reads with channels=True
ATTRIBUTE_KEY = "attribute:"


def expand_usd_mesh(mesh, name: str = "", budget: list[int] | None = None,
                    channels: bool = False) -> dict[str, np.ndarray]:
    """points, normals, st (3F, k) per triangle corner of a triangulated UsdGeom.Mesh, every
    count and index checked (``name`` labels errors; ``budget`` [bytes] is drawn down by the
    arrays made).

    ``channels``: also displayColor (3F, 3) when authored, and every other authored float[]
    or double[] primvar as ``"attribute:" + name`` (3F, 1), checked like normals and st.
    """
    from pxr import Sdf, UsdGeom

    where = f"{name}: {mesh.GetPath()}" if name else str(mesh.GetPath())
    with quiet_library(where, "usd-core"):
        points = mesh.GetPointsAttr().Get()
        counts = mesh.GetFaceVertexCountsAttr().Get()
        indices = mesh.GetFaceVertexIndicesAttr().Get()
    sizes = [0 if array is None else len(array) for array in (points, counts, indices)]
    if budget is not None and (3 * sizes[0] + sizes[1] + 9 * sizes[2]) * 8 > budget[0]:
        raise UnreadableFileError(f"{where}: {sizes[0]} points, {sizes[1]} faces and {sizes[2]} indices would take "
                                  "the arrays past the reader's limit (--max-memory); refused")
    points = np.zeros((0, 3)) if points is None else np.asarray(points, dtype=np.float64).reshape(-1, 3)
    counts = np.zeros(0, dtype=np.int64) if counts is None else np.asarray(counts, dtype=np.int64).ravel()
    indices = np.zeros(0, dtype=np.int64) if indices is None else np.asarray(indices, dtype=np.int64).ravel()
    if not (counts == 3).all():
        raise UnreadableFileError(f"{where}: only triangle meshes can be read back")
    if len(indices) != 3 * len(counts):
        raise UnreadableFileError(f"{where}: faceVertexIndices has {len(indices)} entries, faceVertexCounts asks "
                                  f"for {3 * len(counts)}")
    if indices.size and (indices.min() < 0 or indices.max() >= len(points)):
        bad = int(np.flatnonzero((indices < 0) | (indices >= len(points)))[0])
        raise UnreadableFileError(f"{where}: faceVertexIndices[{bad}] is {int(indices[bad])}, but there are "
                                  f"{len(points)} points")
    _finite(points, f"{where}.points")
    if budget is not None:
        budget[0] -= len(indices) * 8 * 8  # points, normals and st per corner
        if budget[0] < 0:
            raise UnreadableFileError(f"{where}: its corners would take the arrays past the reader's limit (--max-memory); refused")
    primvars = UsdGeom.PrimvarsAPI(mesh.GetPrim())
    out = {"points": points[indices]}
    counted = {UsdGeom.Tokens.vertex: len(points), UsdGeom.Tokens.faceVarying: len(indices),
               UsdGeom.Tokens.uniform: len(counts), UsdGeom.Tokens.varying: len(points)}
    for key, width in (("normals", 3), ("st", 2)):
        with quiet_library(where, "usd-core"):
            primvar = primvars.GetPrimvar(key)
            present = bool(primvar) and primvar.Get() is not None
        if not present:
            out[key] = np.zeros((len(indices), width))
            continue
        out[key] = _corner_values(primvar, key, width, indices, counted, where)
    if channels:
        scalar = (Sdf.ValueTypeNames.FloatArray, Sdf.ValueTypeNames.DoubleArray)
        with quiet_library(where, "usd-core"):
            authored = [(p, p.GetPrimvarName(), p.GetTypeName()) for p in primvars.GetAuthoredPrimvars()
                        if p.Get() is not None]
        for primvar, key, kind in authored:
            if key == "displayColor":
                label, width = key, 3
            elif key not in ("normals", "st") and kind in scalar:
                label, width = ATTRIBUTE_KEY + key, 1
            else:
                continue
            if budget is not None:
                budget[0] -= len(indices) * width * 8
                if budget[0] < 0:
                    raise UnreadableFileError(f"{where}: primvars:{key} would take the arrays past the reader's "
                                              "limit (--max-memory); refused")
            out[label] = _corner_values(primvar, key, width, indices, counted, where)
    return out


def _corner_values(primvar, key: str, width: int, indices: np.ndarray, counted: dict, where: str) -> np.ndarray:
    """(3F, width) float64 values of an authored primvar at each triangle corner, by its
    interpolation, after checking its shape, its count for that interpolation and that every
    value is finite."""
    from pxr import UsdGeom

    with quiet_library(where, "usd-core"):
        flat = primvar.ComputeFlattened()
        interpolation = primvar.GetInterpolation()
    if flat is None:
        raise UnreadableFileError(f"{where}: primvars:{key} has indices outside its values")
    values = np.asarray(flat, dtype=np.float64)
    if width == 1 and values.ndim == 1:
        values = values.reshape(-1, 1)
    if values.ndim != 2 or values.shape[1] != width:
        raise UnreadableFileError(f"{where}: primvars:{key} must hold {width}-vectors, got shape {values.shape}")
    _finite(values, f"{where}.primvars:{key}")
    expected = counted.get(interpolation, 1)
    if len(values) < expected or len(values) == 0:
        raise UnreadableFileError(f"{where}: primvars:{key} ({interpolation}) has {len(values)} values, needs "
                                  f"{expected}")
    if interpolation in (UsdGeom.Tokens.vertex, UsdGeom.Tokens.varying):
        return values[indices]
    if interpolation == UsdGeom.Tokens.faceVarying:
        return values[:len(indices)]
    if interpolation == UsdGeom.Tokens.uniform:
        return np.repeat(values[:len(indices) // 3], 3, axis=0)
    return np.broadcast_to(values[:1], (len(indices), width)).copy()  # constant


def _finite(values: np.ndarray, where: str) -> None:
    bad = ~np.isfinite(values)
    if bad.any():
        row = int(np.flatnonzero(bad.reshape(len(values), -1).any(axis=1))[0])
        raise UnreadableFileError(f"{where}[{row}] is not finite ({values[row].tolist()})")


class _FolderResolver:
    """trimesh's resolver interface over ``readers.files``: a file an OBJ names (its .mtl, its
    textures) is read only if it is a regular file inside the OBJ's folder."""

    def __init__(self, folder: str, limit: int, label: str):
        self.folder, self.limit, self.label = folder, limit, label

    def get(self, key: str) -> bytes:
        from cgamesh.readers.files import read_reference

        return read_reference(self.folder, key.strip(), self.limit, f"{self.label}: the file it names")

    __getitem__ = get

    def namespaced(self, namespace: str) -> "_FolderResolver":
        from cgamesh.readers.files import resolve_relative

        return _FolderResolver(str(resolve_relative(self.folder, namespace, self.label)), self.limit, self.label)

    def keys(self):
        return iter(())

    def __contains__(self, key: str) -> bool:
        return False

    def write(self, name: str, data) -> None:
        raise UnreadableFileError(f"{self.label}: reading a mesh never writes ({name!r})")


def read_trimesh(path: str | Path, limit: int = MAX_FILE_BYTES) -> list[SurfaceMesh]:
    """OBJ / PLY / STL through trimesh, one mesh per geometry, with the file's vertex normals
    (STL: the face normals, spread to the vertices) and UVs (zeros where the file has none).
    A PLY file's 8-bit vertex colours (sRGB-encoded) come back as linear ``colors`` and its
    other scalar vertex properties as ``attributes``.

    The file is read by ``readers.files`` (a regular file, bounded size) and handed to trimesh
    as bytes, with a resolver that reads only regular files beside it; the arrays trimesh
    returns are checked (shapes, finite values, faces indexing the vertices).
    """
    import io

    from cgamesh.optional import require

    name = os.fsdecode(path)
    trimesh = require("trimesh", "formats", "reading OBJ / PLY / STL")
    from cgamesh.readers.files import read_regular

    data = read_regular(name, limit)
    kind = Path(name).suffix.lower().lstrip(".")
    resolver = _FolderResolver(os.path.dirname(os.path.abspath(name)), limit, name)
    with quiet_library(name, "trimesh"):
        loaded = trimesh.load(io.BytesIO(data), file_type=kind, force="scene", process=False, resolver=resolver)
        geometries = list(loaded.geometry.items())
    out = []
    for key, geometry in geometries:
        where = f"{name}: {key}"
        with quiet_library(where, "trimesh"):
            positions = np.asarray(geometry.vertices, dtype=np.float64)
            faces = np.asarray(geometry.faces, dtype=np.int64)
        if positions.ndim != 2 or positions.shape[1] != 3 or faces.ndim != 2 or faces.shape[1] != 3:
            raise UnreadableFileError(f"{where}: expected (V, 3) vertices and (F, 3) triangles, got "
                                      f"{positions.shape} and {faces.shape}")
        _finite(positions, f"{where}.vertices")
        if faces.size and (faces.min() < 0 or faces.max() >= len(positions)):
            raise UnreadableFileError(f"{where}: a face indexes vertex {int(faces.max())}, but there are "
                                      f"{len(positions)}")
        with quiet_library(where, "trimesh"):
            normals = np.asarray(geometry.vertex_normals, dtype=np.float64)
            uv = getattr(geometry.visual, "uv", None)
        if normals.shape != positions.shape or not np.isfinite(normals).all():
            normals = np.zeros((0, 3))
        uvs = np.asarray(uv, dtype=np.float64) if uv is not None and len(uv) == len(positions) else np.zeros((len(positions), 2))
        if uvs.ndim != 2 or uvs.shape[1] != 2 or not np.isfinite(uvs).all():
            uvs = np.zeros((len(positions), 2))
        colors, attributes = _ply_channels(geometry, len(positions), where)
        out.append(SurfaceMesh(str(key), positions, normals, uvs, faces, colors=colors, attributes=attributes))
    return out


# PLY vertex properties that are not per-vertex attributes
_PLY_STANDARD = {"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue", "alpha", "s", "t", "u", "v",
                 "texture_u", "texture_v"}


def _ply_channels(geometry, count: int, where: str) -> tuple[np.ndarray | None, dict[str, np.ndarray] | None]:
    """Vertex colours (linear, from 8-bit sRGB) and extra scalar vertex properties of a PLY
    mesh; colours of the wrong shape are refused and attribute values must be finite."""
    with quiet_library(where, "trimesh"):
        rgba = getattr(geometry, "vertex_attributes", {}).get("color")
        if rgba is None and getattr(geometry.visual, "kind", None) == "vertex":
            rgba = geometry.visual.vertex_colors
        raw = geometry.metadata.get("_ply_raw", {}).get("vertex", {}).get("data")
    colors = None
    if rgba is not None and len(rgba) == count:
        rgba = np.asarray(rgba)
        if rgba.ndim != 2 or rgba.shape[1] not in (3, 4):
            raise UnreadableFileError(f"{where}: vertex colours must be RGB or RGBA, got shape {rgba.shape}")
        colors = srgb_to_linear(rgba[:, :3].astype(np.float64) / 255.0)
    attributes = {}
    if raw is not None and raw.dtype.names is not None and len(raw) == count:
        for field in raw.dtype.names:
            if field not in _PLY_STANDARD and raw.dtype[field].shape == ():
                values = np.asarray(raw[field], dtype=np.float64)
                _finite(values.reshape(-1, 1), f"{where}.{field}")
                attributes[field] = values
    return colors, attributes or None
