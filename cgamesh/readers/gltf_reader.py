"""glTF 2.0 files (.glb, .gltf) read for ``check`` and ``verify``, trusting nothing they declare.

pygltflib parses well-formed files, but takes a GLB's chunk lengths, an accessor's count,
offset and stride, and a buffer's ``uri`` at their word. Here the container and the JSON are
read by hand (the GLB container is three little-endian words and two chunks) and every value
used is checked before use, against the data actually there:

- the file and every buffer it names go through ``readers.files`` (regular files inside the
  file's folder, base64 data URIs, bounded sizes); a GLB's header and chunk lengths must
  match the file; the JSON (at most MAX_JSON_BYTES) must be an object with ``asset.version``
  "2.0" (NaN and infinity constants, invalid UTF-8 and nesting deeper than Python's parser
  allows are refused);
- an accessor's component type, type, count (>= 1), normalized flag and byte offset, its
  buffer view's buffer, offset, length and stride (4 to 252, a multiple of 4, at least one
  element), and offset + stride (count - 1) + element <= the view's length <= the buffer's;
  sparse accessors and accessors without a buffer view are refused (never written by
  cgamesh, and not needed to read a mesh);
- the decoded arrays are counted against ``limit`` before they are allocated; float values
  must be finite, and an accessor's declared min / max must be the data's;
- primitives must be triangles (mode 4), their attributes of one count, their indices
  unsigned and below it; node children must be valid indices with one parent each, and a
  node that is its own ancestor (a cycle) is refused; transforms must be finite, and
  invertible where normals are carried through them;
- the per-vertex channels are accessors like the others: COLOR_0 (VEC3 or VEC4; float, or
  normalized unsigned 8- or 16-bit integers, as glTF requires) and every application-specific
  SCALAR attribute ``_NAME`` (any component type; names must stay distinct in lower case);
  vector-valued custom attributes are not read.

Every problem is an ``UnreadableFileError``: one line, ``FILE: where: what``.
"""

from __future__ import annotations

import json
import math
import os
import struct
from dataclasses import dataclass

import numpy as np

from cgamesh.readers.files import MAX_FILE_BYTES, UnreadableFileError, read_reference, read_regular

GLB_MAGIC = b"glTF"
GLB_JSON = 0x4E4F534A
GLB_BIN = 0x004E4942
COMPONENTS = {5120: np.dtype("<i1"), 5121: np.dtype("<u1"), 5122: np.dtype("<i2"), 5123: np.dtype("<u2"),
              5125: np.dtype("<u4"), 5126: np.dtype("<f4")}
WIDTHS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
TRIANGLES = 4
FLOAT = 5126
INDEX_COMPONENTS = (5121, 5123, 5125)
# Attributes read, with their accessor type and allowed component types (float32, or the
# integer types of KHR_mesh_quantization).
ATTRIBUTES = {"POSITION": ("VEC3", (5126, 5120, 5121, 5122, 5123)), "NORMAL": ("VEC3", (5126, 5120, 5122)),
              "TEXCOORD_0": ("VEC2", (5126, 5120, 5121, 5122, 5123)), "TANGENT": ("VEC4", (5126, 5120, 5122))}
# COLOR_0: its accessor types and component types (integers only normalized).
COLOR = ("COLOR_0", ("VEC3", "VEC4"), (5126, 5121, 5123))
# Application-specific attributes ("_NAME"): only SCALAR ones are read, of any component type.
CUSTOM_COMPONENTS = tuple(COMPONENTS)
# Largest JSON document parsed: a few kilobytes per surface in cgamesh's files; parsed JSON can
# take 20 times its text in Python objects, so this bounds the parse to about 0.7 GiB.
MAX_JSON_BYTES = 32 << 20
# Relative slack when comparing an accessor's declared min / max with its data (writers round).
MIN_MAX_RTOL = 1e-6


@dataclass(frozen=True)
class Primitive:
    """One triangle primitive: positions (V, 3), normals (V, 3) or None, uvs (V, 2) as stored
    (glTF's V, top-left origin) or None, tangents (V, 4) or None, faces (F, 3) int64, and its
    material's doubleSided flag; colors (V, 3) RGB as stored (COLOR_0's alpha dropped) or None,
    and attributes: the SCALAR ``_NAME`` attributes as (V,) float64 by lower-case name."""

    positions: np.ndarray
    normals: np.ndarray | None
    uvs: np.ndarray | None
    tangents: np.ndarray | None
    faces: np.ndarray
    double_sided: bool
    colors: np.ndarray | None = None
    attributes: dict[str, np.ndarray] | None = None


@dataclass(frozen=True)
class Instance:
    """A node with a mesh, reachable from the scene: its world matrix (4, 4)."""

    node: int
    mesh: int
    matrix: np.ndarray


def _is_int(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _describe(value) -> str:
    text = json.dumps(value) if isinstance(value, (dict, list, str, int, float, bool)) or value is None else repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _no_constants(name: str):
    raise ValueError(f"{name} is not a JSON number")


class GltfFile:
    """A parsed, checked glTF document with its buffers read on demand.

    ``limit``: the most bytes read from any one file and, in all, decoded into arrays.
    """

    def __init__(self, path: str | os.PathLike, limit: int = MAX_FILE_BYTES):
        self.path = os.fsdecode(path)
        self.folder = os.path.dirname(os.path.abspath(self.path))
        self.limit = limit
        self._allocated = 0
        self._buffers: dict[int, memoryview] = {}
        data = read_regular(self.path, limit)
        self._bin: memoryview | None = None
        if data[:4] == GLB_MAGIC:
            text = self._glb_chunks(data)
        elif self.path.lower().endswith(".glb"):
            self.fail(f"not a GLB file (it starts with {data[:4]!r}, not b'glTF')")
        else:
            text = data
        self.document = self._parse(text)

    # --- errors and JSON access ------------------------------------------------------------------

    def fail(self, message: str):
        raise UnreadableFileError(f"{self.path}: {message}")

    def _glb_chunks(self, data: bytes) -> bytes:
        if len(data) < 20:
            self.fail(f"a GLB needs a 12-byte header and a chunk header, the file has {len(data)} bytes")
        _, version, length = struct.unpack_from("<4sII", data, 0)
        if version != 2:
            self.fail(f"GLB version must be 2, got {version}")
        if length != len(data):
            self.fail(f"the GLB header declares {length} bytes, the file has {len(data)}")
        offset, chunks = 12, []
        while offset < len(data):
            if offset + 8 > len(data):
                self.fail(f"a truncated chunk header at byte {offset}")
            size, kind = struct.unpack_from("<II", data, offset)
            if size > len(data) - offset - 8:
                self.fail(f"the chunk at byte {offset} declares {size} bytes, only {len(data) - offset - 8} follow")
            chunks.append((kind, memoryview(data)[offset + 8:offset + 8 + size]))  # views: no copies
            offset += 8 + size
        if not chunks or chunks[0][0] != GLB_JSON:
            self.fail("the first GLB chunk must be JSON")
        if len(chunks) > 1 and chunks[1][0] == GLB_BIN:
            self._bin = chunks[1][1]
        return chunks[0][1]

    def _parse(self, text) -> dict:
        if len(text) > MAX_JSON_BYTES:
            self.fail(f"its JSON has {len(text)} bytes, more than the {MAX_JSON_BYTES} this reader parses")
        try:
            document = json.loads(bytes(text).decode("utf-8"), parse_constant=_no_constants)
        except UnicodeDecodeError as error:
            self.fail(f"the JSON is not UTF-8 (byte {error.start})")
        except RecursionError:
            self.fail("the JSON is nested too deeply")
        except ValueError as error:
            self.fail(f"invalid JSON: {error}")
        if not isinstance(document, dict):
            self.fail(f"the JSON must be an object, got {type(document).__name__}")
        asset = document.get("asset")
        if not isinstance(asset, dict) or asset.get("version") != "2.0":
            version = asset.get("version") if isinstance(asset, dict) else None
            self.fail(f"asset.version must be \"2.0\", got {_describe(version)}")
        for key in ("buffers", "bufferViews", "accessors", "meshes", "nodes", "scenes", "materials"):
            if key in document and not isinstance(document[key], list):
                self.fail(f"{key} must be an array, got {_describe(document[key])}")
        return document

    def item(self, collection: str, index, where: str) -> dict:
        """document[collection][index], an object; ``where`` names the reference."""
        items = self.document.get(collection, [])
        if not _is_int(index) or not 0 <= index < len(items):
            self.fail(f"{where} must be an index into {collection} (0 to {len(items) - 1}), got {_describe(index)}")
        value = items[index]
        if not isinstance(value, dict):
            self.fail(f"{collection}[{index}] must be an object, got {_describe(value)}")
        return value

    def integer(self, obj: dict, key: str, where: str, low: int = 0, high: int | None = None, default=None) -> int:
        if key not in obj:
            if default is None:
                self.fail(f"{where}.{key} is missing")
            return default
        value = obj[key]
        if not _is_int(value) or value < low or (high is not None and value > high):
            bound = f">= {low}" if high is None else f"in [{low}, {high}]"
            self.fail(f"{where}.{key} must be a whole number {bound}, got {_describe(value)}")
        return value

    def numbers(self, obj: dict, key: str, where: str, count: int) -> np.ndarray | None:
        value = obj.get(key)
        if value is None:
            return None
        if not isinstance(value, list) or len(value) != count or not all(_is_number(v) for v in value):
            self.fail(f"{where}.{key} must be {count} finite numbers, got {_describe(value)}")
        return np.asarray(value, dtype=np.float64)

    # --- buffers and accessors ------------------------------------------------------------------

    def buffer(self, index: int, where: str) -> memoryview:
        if index not in self._buffers:
            buffer = self.item("buffers", index, where)
            here = f"buffers[{index}]"
            declared = self.integer(buffer, "byteLength", here, 1)
            uri = buffer.get("uri")
            if uri is None:
                if index != 0 or self._bin is None:
                    self.fail(f"{here} has no uri and the file has no GLB binary chunk for it")
                data = self._bin
            elif not isinstance(uri, str):
                self.fail(f"{here}.uri must be a string, got {_describe(uri)}")
            else:
                data = read_reference(self.folder, uri, self.limit, f"{self.path}: {here}.uri")
            if len(data) < declared:
                self.fail(f"{here}.byteLength is {declared}, but its data has {len(data)} bytes")
            self._buffers[index] = memoryview(data)[:declared]
        return self._buffers[index]

    def accessor(self, index, where: str, types: tuple[str, ...], components: tuple[int, ...],
                 as_indices: bool = False) -> np.ndarray:
        """The values (count, width) of accessor ``index`` as float64 (dequantised when
        normalized) or int64 (indices), every declared number checked against the data."""
        accessor = self.item("accessors", index, where)
        here = f"accessors[{index}]"
        if "sparse" in accessor:
            self.fail(f"{here} ({where}) is sparse; sparse accessors are not read")
        if "bufferView" not in accessor:
            self.fail(f"{here} ({where}) has no bufferView; accessors without data are not read")
        component = accessor.get("componentType")
        if component not in COMPONENTS or not _is_int(component):
            self.fail(f"{here}.componentType must be one of {sorted(COMPONENTS)}, got {_describe(component)}")
        if component not in components:
            self.fail(f"{here} ({where}) must have a componentType among {list(components)}, got {component}")
        kind = accessor.get("type")
        if kind not in types:
            self.fail(f"{here}.type must be {' or '.join(types)} for {where}, got {_describe(kind)}")
        count = self.integer(accessor, "count", here, 1)
        normalized = accessor.get("normalized", False)
        if not isinstance(normalized, bool) or (normalized and (component in (FLOAT, 5125) or as_indices)):
            self.fail(f"{here}.normalized must be false, or true for 8- and 16-bit integers, got {_describe(normalized)}")
        dtype, width = COMPONENTS[component], WIDTHS[kind]
        offset = self.integer(accessor, "byteOffset", here, 0, default=0)
        if offset % dtype.itemsize:
            self.fail(f"{here}.byteOffset {offset} is not a multiple of its component size {dtype.itemsize}")

        view = self.item("bufferViews", accessor["bufferView"], f"{here}.bufferView")
        view_here = f"bufferViews[{accessor['bufferView']}]"
        data = self.buffer(self.integer(view, "buffer", view_here, 0), f"{view_here}.buffer")
        view_offset = self.integer(view, "byteOffset", view_here, 0, default=0)
        view_length = self.integer(view, "byteLength", view_here, 1)
        if view_offset + view_length > len(data):
            self.fail(f"{view_here} spans bytes {view_offset} to {view_offset + view_length}, past the end of its "
                      f"buffer ({len(data)} bytes)")
        element = dtype.itemsize * width
        stride = element
        if "byteStride" in view:
            stride = self.integer(view, "byteStride", view_here, 4, 252)
            if stride % 4 or stride < element:
                self.fail(f"{view_here}.byteStride {stride} must be a multiple of 4 and at least the element "
                          f"size {element} of {here}")
        need = offset + stride * (count - 1) + element
        if need > view_length:
            self.fail(f"{here} needs {need} bytes of {view_here} (offset {offset}, count {count}, stride {stride}), "
                      f"which has {view_length}")
        self._allocate(count * width * 8, here)
        raw = np.ndarray((count, width), dtype=dtype, buffer=data, offset=view_offset + offset,
                         strides=(stride, dtype.itemsize))
        if component == FLOAT:
            with np.errstate(invalid="ignore"):  # a signalling NaN sets the flag; it is refused here
                finite = np.isfinite(raw)
            if not finite.all():
                row = int(np.flatnonzero(~finite.all(axis=1))[0])
                self.fail(f"{here} ({where}) holds a non-finite value ({raw[row][~finite[row]][0]}) at element {row}")
        self._check_bounds(accessor, here, raw, width)
        with np.errstate(invalid="ignore"):
            values = raw.astype(np.int64 if as_indices else np.float64)
        if normalized:
            bound = float(np.iinfo(dtype).max)
            values = np.maximum(values / bound, -1.0)
        return values

    def _allocate(self, size: int, here: str) -> None:
        self._allocated += size
        if self._allocated > self.limit:
            self.fail(f"reading {here} would take the arrays past {self.limit} bytes (--max-memory); refused")

    def _check_bounds(self, accessor: dict, here: str, values: np.ndarray, width: int) -> None:
        """Declared min / max (raw component values) against the data's, where declared."""
        for key, reduce in (("min", np.min), ("max", np.max)):
            declared = self.numbers(accessor, key, here, width)
            if declared is None:
                continue
            actual = reduce(values, axis=0).astype(np.float64)
            slack = MIN_MAX_RTOL * np.maximum(np.abs(declared), np.abs(actual)) + 1e-30
            if np.any(np.abs(declared - actual) > slack):
                self.fail(f"{here}.{key} is {declared.tolist()}, but its data's is {actual.tolist()}")

    # --- meshes ---------------------------------------------------------------------------------

    def mesh_count(self) -> int:
        return len(self.document.get("meshes", []))

    def mesh_name(self, index: int) -> str:
        name = self.item("meshes", index, "mesh").get("name")
        return name if isinstance(name, str) else f"mesh{index}"

    def primitives(self, index: int, first_only: bool = False) -> list[Primitive]:
        """The triangle primitives of meshes[index] (only its first with ``first_only``)."""
        mesh = self.item("meshes", index, "mesh")
        primitives = mesh.get("primitives")
        if not isinstance(primitives, list) or not primitives:
            self.fail(f"meshes[{index}].primitives must be a non-empty array, got {_describe(primitives)}")
        return [self._primitive(index, k, p) for k, p in enumerate(primitives[:1] if first_only else primitives)]

    def _primitive(self, mesh: int, k: int, primitive) -> Primitive:
        here = f"meshes[{mesh}].primitives[{k}]"
        if not isinstance(primitive, dict):
            self.fail(f"{here} must be an object, got {_describe(primitive)}")
        mode = self.integer(primitive, "mode", here, 0, 6, default=TRIANGLES)
        if mode != TRIANGLES:
            self.fail(f"{here}.mode is {mode}; only triangles (4) are read")
        attributes = primitive.get("attributes")
        if not isinstance(attributes, dict) or "POSITION" not in attributes:
            self.fail(f"{here}.attributes must be an object with POSITION, got {_describe(attributes)}")
        arrays = {}
        for name, (kind, components) in ATTRIBUTES.items():
            if name in attributes:
                arrays[name] = self.accessor(attributes[name], f"{here}.attributes.{name}", (kind,), components)
        colors, custom = self._channels(here, attributes)
        if colors is not None:
            arrays[COLOR[0]] = colors
        for semantic, values in custom.items():
            arrays[semantic] = values
        count = len(arrays["POSITION"])
        for name, values in arrays.items():
            if len(values) != count:
                self.fail(f"{here}.attributes.{name} has {len(values)} elements, POSITION has {count}")
        if "indices" in primitive:
            indices = self.accessor(primitive["indices"], f"{here}.indices", ("SCALAR",), INDEX_COMPONENTS,
                                    as_indices=True).ravel()
        else:
            self._allocate(count * 8, f"{here} (implicit indices)")
            indices = np.arange(count, dtype=np.int64)
        if len(indices) % 3:
            self.fail(f"{here} has {len(indices)} indices, not a multiple of 3")
        if indices.size and int(indices.max()) >= count:
            at = int(np.argmax(indices >= count))
            self.fail(f"{here}.indices[{at}] is {int(indices[at])}, but there are only {count} vertices")
        double_sided = False
        if "material" in primitive:
            material = self.item("materials", primitive["material"], f"{here}.material")
            double_sided = material.get("doubleSided", False)
            if not isinstance(double_sided, bool):
                self.fail(f"materials[{primitive['material']}].doubleSided must be true or false, "
                          f"got {_describe(double_sided)}")
        named = {semantic[1:].lower(): values[:, 0] for semantic, values in custom.items()}
        return Primitive(arrays["POSITION"], arrays.get("NORMAL"), arrays.get("TEXCOORD_0"), arrays.get("TANGENT"),
                         indices.reshape(-1, 3), double_sided,
                         colors=None if colors is None else colors[:, :3], attributes=named or None)

    def _channels(self, here: str, attributes: dict) -> tuple[np.ndarray | None, dict[str, np.ndarray]]:
        """COLOR_0 (count, 3 or 4) and the SCALAR ``_NAME`` attributes (count, 1) by semantic,
        each read and checked like any other accessor."""
        semantic, types, components = COLOR
        colors = None
        if semantic in attributes:
            index = attributes[semantic]
            where = f"{here}.attributes.{semantic}"
            accessor = self.item("accessors", index, where)
            if accessor.get("componentType") != FLOAT and accessor.get("normalized") is not True:
                self.fail(f"accessors[{index}] ({where}) must be float or normalized integers, "
                          f"got componentType {_describe(accessor.get('componentType'))} without normalized")
            colors = self.accessor(index, where, types, components)
        custom, names = {}, {}
        for semantic, index in attributes.items():
            if not semantic.startswith("_"):
                continue
            where = f"{here}.attributes.{semantic}"
            if self.item("accessors", index, where).get("type") != "SCALAR":
                continue  # vector-valued application data: not a per-vertex scalar channel
            name = semantic[1:].lower()
            if not name:
                self.fail(f"{where}: an application-specific attribute needs a name after '_'")
            if name in names:
                self.fail(f"{where} and {here}.attributes.{names[name]} are both attribute {name!r}")
            names[name] = semantic
            custom[semantic] = self.accessor(index, where, ("SCALAR",), CUSTOM_COMPONENTS)
        return colors, custom

    # --- the node graph -------------------------------------------------------------------------

    def node_matrix(self, index: int) -> np.ndarray:
        node = self.item("nodes", index, "node")
        here = f"nodes[{index}]"
        matrix = self.numbers(node, "matrix", here, 16)
        if matrix is not None:
            return matrix.reshape(4, 4).T  # glTF stores column-major
        translation = self.numbers(node, "translation", here, 3)
        rotation = self.numbers(node, "rotation", here, 4)
        scale = self.numbers(node, "scale", here, 3)
        x, y, z, w = rotation if rotation is not None else (0.0, 0.0, 0.0, 1.0)
        turn = np.array([
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ])
        out = np.eye(4)
        out[:3, :3] = turn * (scale if scale is not None else np.ones(3))[None, :]
        out[:3, 3] = translation if translation is not None else 0.0
        return out

    def _children(self, index: int) -> list[int]:
        node = self.item("nodes", index, "node")
        children = node.get("children", [])
        count = len(self.document.get("nodes", []))
        if not isinstance(children, list) or not all(_is_int(c) and 0 <= c < count for c in children):
            self.fail(f"nodes[{index}].children must be indices into nodes (0 to {count - 1}), got {_describe(children)}")
        return children

    def instances(self) -> list[Instance]:
        """Every node with a mesh reachable from the scene (scene, or scenes[0], or the nodes no
        node has as a child), with its world matrix; in node order."""
        nodes = self.document.get("nodes", [])
        parent: dict[int, int] = {}
        for index in range(len(nodes)):
            for child in self._children(index):
                if child == index:
                    self.fail(f"nodes[{index}] is its own child")
                if child in parent and parent[child] != index:
                    self.fail(f"nodes[{child}] has two parents (nodes[{parent[child]}] and nodes[{index}])")
                if child in parent:
                    self.fail(f"nodes[{index}].children lists nodes[{child}] twice")
                parent[child] = index
        roots = self._roots(parent)
        out, seen = {}, set()
        stack = [(k, np.eye(4)) for k in reversed(roots)]
        while stack:
            index, above = stack.pop()
            if index in seen:
                self.fail(f"nodes[{index}] is reached twice from the scene's roots (a cycle)")
            seen.add(index)
            matrix = above @ self.node_matrix(index)
            if not np.all(np.isfinite(matrix)):
                self.fail(f"nodes[{index}]: its world transform is not finite")
            node = self.item("nodes", index, "node")
            if "mesh" in node:
                mesh = node["mesh"]
                self.item("meshes", mesh, f"nodes[{index}].mesh")
                out[index] = Instance(index, mesh, matrix)
            stack.extend((child, matrix) for child in reversed(self._children(index)))
        # A cycle that no root reaches still makes the graph invalid: every node on it has a
        # parent. Each node is walked up from once (``acyclic`` remembers), so this is linear.
        acyclic: set[int] = set()
        for index in range(len(nodes)):
            walk, k = set(), index
            while k not in acyclic and k in parent:
                if k in walk:
                    self.fail(f"nodes[{k}] is its own ancestor (a cycle through children)")
                walk.add(k)
                k = parent[k]
            acyclic |= walk
        return [out[k] for k in sorted(out)]

    def _roots(self, parent: dict[int, int]) -> list[int]:
        scenes = self.document.get("scenes", [])
        if scenes:
            index = self.document.get("scene", 0)
            scene = self.item("scenes", index, "scene")
            roots = scene.get("nodes", [])
            count = len(self.document.get("nodes", []))
            if not isinstance(roots, list) or not all(_is_int(k) and 0 <= k < count for k in roots):
                self.fail(f"scenes[{index}].nodes must be indices into nodes, got {_describe(roots)}")
            for k in roots:
                if k in parent:
                    self.fail(f"scenes[{index}].nodes lists nodes[{k}], which is a child of nodes[{parent[k]}]")
            if len(set(roots)) != len(roots):
                self.fail(f"scenes[{index}].nodes lists a node twice")
            return roots
        return [k for k in range(len(self.document.get("nodes", []))) if k not in parent]


def invertible_linear_part(reader: GltfFile, instance: Instance) -> np.ndarray:
    """The inverse of an instance's 3 x 3 linear part (for normals), refused when singular."""
    linear = instance.matrix[:3, :3]
    scale = np.abs(linear).max()
    if not scale > 0.0 or abs(np.linalg.det(linear / scale)) < 1e-12:
        reader.fail(f"nodes[{instance.node}]: its transform is singular; normals cannot be carried through it")
    return np.linalg.inv(linear)
