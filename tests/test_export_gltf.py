"""GLB export: checked by the Khronos glTF-Validator and by reloading through pygltflib and trimesh."""

from __future__ import annotations

import json
import os
import time

import numpy as np
import pygltflib
import pytest
import trimesh

from cgamesh.errors import ExportError
from cgamesh.export import atomic
from cgamesh.export.gltf import write_glb
from cgamesh.export.options import WriteOptions
from cgamesh.material import Material
from cgamesh.meshing.mesh import SurfaceMesh
from gltf_validator import assert_clean

# glTF's +Y-up frame from each source up axis: out = points @ AXIS_MAP[up].T
AXIS_MAP = {"z": np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]]), "y": np.eye(3)}


def torus_patch(name, n_around, n_along, *, centre=(0.0, 0.0, 0.0), R=2.0, r=0.5, double_sided=False):
    """A patch of a Euclidean torus about the z axis with exact outward normals.

    theta in [0, 1.5 pi] around the tube (u), phi in [0, 0.5 pi] along it (v); faces wind
    counter-clockwise seen from the normals (d/dphi x d/dtheta is outward).
    """
    theta = np.linspace(0.0, 1.5 * np.pi, n_around)
    phi = np.linspace(0.0, 0.5 * np.pi, n_along)
    t, p = np.meshgrid(theta, phi)  # (n_along, n_around): vertex k = j * n_around + i
    normals = np.stack([np.cos(t) * np.cos(p), np.cos(t) * np.sin(p), np.sin(t)], axis=-1).reshape(-1, 3)
    ring = np.stack([R * np.cos(p), R * np.sin(p), np.zeros_like(p)], axis=-1).reshape(-1, 3)
    positions = np.asarray(centre) + ring + r * normals
    u, v = np.meshgrid(np.linspace(0, 1, n_around), np.linspace(0, 1, n_along))
    uvs = np.stack([u, v], axis=-1).reshape(-1, 2)
    a = (np.arange(n_along - 1)[:, None] * n_around + np.arange(n_around - 1)).ravel()
    b, c, d = a + n_around, a + 1, a + n_around + 1  # b: next along phi, c: next around theta
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([c, b, d], 1)]).astype(np.int64)
    return SurfaceMesh(name, positions, normals, uvs, faces, double_sided)


def expected_positions(mesh, up, scale):
    return mesh.positions @ AXIS_MAP[up].T * scale


def read_accessor(gltf, blob, index):
    """(count, components) array of a tightly packed accessor."""
    acc = gltf.accessors[index]
    view = gltf.bufferViews[acc.bufferView]
    dtype = {pygltflib.FLOAT: np.float32, pygltflib.UNSIGNED_SHORT: np.uint16, pygltflib.UNSIGNED_INT: np.uint32}
    width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3}[acc.type]
    start = view.byteOffset + acc.byteOffset
    return np.frombuffer(blob, dtype[acc.componentType], acc.count * width, start).reshape(acc.count, width)


@pytest.fixture
def scene():
    """Two surfaces: a single-sided tube patch and a double-sided one with other material values."""
    return [
        (torus_patch("tube", 17, 9), Material((0.8, 0.3, 0.2), roughness=0.5, metallic=0.0)),
        (torus_patch("ribbon", 5, 6, centre=(3.0, -1.0, 0.5), R=1.0, r=0.25, double_sided=True),
         Material((0.1, 0.6, 0.9), roughness=0.25, metallic=1.0)),
    ]


@pytest.mark.parametrize(("up", "scale", "units"), [("z", 1.0, "m"), ("y", 0.01, "cm"), ("z", 0.001, "mm")])
def test_glb_is_valid_and_round_trips_through_pygltflib(tmp_path, gltf_validate, scene, up, scale, units):
    path = tmp_path / "scene.glb"
    written = write_glb(path, scene, WriteOptions(up, scale, units))
    assert written == path.stat().st_size
    assert_clean(gltf_validate(path))

    gltf = pygltflib.GLTF2().load(str(path))
    blob = gltf.binary_blob()
    assert gltf.asset.generator.startswith("cgamesh ")
    assert gltf.asset.extras == {"source_units": units, "meters_per_unit": scale, "source_up": up}
    assert gltf.scene == 0 and gltf.scenes[0].nodes == [0, 1]
    for i, (mesh, material) in enumerate(scene):
        node, gmesh = gltf.nodes[i], gltf.meshes[gltf.nodes[i].mesh]
        assert node.name == gmesh.name == mesh.name
        prim = gmesh.primitives[0]
        positions = read_accessor(gltf, blob, prim.attributes.POSITION)
        normals = read_accessor(gltf, blob, prim.attributes.NORMAL)
        uvs = read_accessor(gltf, blob, prim.attributes.TEXCOORD_0)
        faces = read_accessor(gltf, blob, prim.indices).reshape(-1, 3)
        assert len(positions) == mesh.vertex_count and len(faces) == mesh.triangle_count

        expected = expected_positions(mesh, up, scale)
        size = np.ptp(expected, axis=0).max()
        # in the scene's units relative to the translation, the unit in metres as uniform scale
        assert node.scale == (None if scale == 1.0 else [scale] * 3)
        got = positions.astype(np.float64) * scale + node.translation
        np.testing.assert_allclose(got, expected, rtol=0, atol=1e-6 * size)
        acc = gltf.accessors[prim.attributes.POSITION]
        assert acc.min == positions.min(axis=0).tolist() and acc.max == positions.max(axis=0).tolist()

        np.testing.assert_allclose(np.linalg.norm(normals.astype(np.float64), axis=1), 1.0, atol=1e-6)
        np.testing.assert_allclose(normals, mesh.normals @ AXIS_MAP[up].T, atol=1e-6)
        np.testing.assert_allclose(uvs, np.c_[mesh.uvs[:, 0], 1.0 - mesh.uvs[:, 1]], atol=1e-7)
        np.testing.assert_array_equal(faces, mesh.faces)
        expected_index_type = pygltflib.UNSIGNED_SHORT  # both meshes are small
        assert gltf.accessors[prim.indices].componentType == expected_index_type

        gmat = gltf.materials[prim.material]
        pbr = gmat.pbrMetallicRoughness
        assert pbr.baseColorFactor == [*material.color, 1.0]
        assert (pbr.metallicFactor, pbr.roughnessFactor) == (material.metallic, material.roughness)
        assert gmat.doubleSided is mesh.double_sided


def test_trimesh_reload_matches_and_winding_agrees_with_normals(tmp_path, scene):
    path = tmp_path / "scene.glb"
    write_glb(path, scene, WriteOptions("z", 1.0, "m"))
    loaded = trimesh.load(path, force="scene", process=False)
    assert sorted(loaded.geometry) == sorted(m.name for m, _ in scene)
    for mesh, _ in scene:
        (node,) = loaded.graph.geometry_nodes[mesh.name]
        transform, _ = loaded.graph[node]
        geom = loaded.geometry[mesh.name]
        assert (len(geom.vertices), len(geom.faces)) == (mesh.vertex_count, mesh.triangle_count)
        expected = expected_positions(mesh, "z", 1.0)
        got = trimesh.transform_points(geom.vertices, transform)
        np.testing.assert_allclose(got, expected, rtol=0, atol=1e-6 * np.ptp(expected, axis=0).max())
        # The axis map is a rotation, so winding must still agree with the stored normals.
        normals = np.asarray(geom.vertex_normals)
        assert (np.einsum("ij,ij->i", geom.face_normals, normals[geom.faces].mean(axis=1)) > 0).all()


def test_far_from_origin_keeps_float32_precision(tmp_path, gltf_validate):
    mesh = torus_patch("far", 33, 17, centre=(1e5, -1e5 / 3, 7e4))
    path = tmp_path / "far.glb"
    write_glb(path, [(mesh, Material())], WriteOptions("z", 1.0, "m"))
    assert_clean(gltf_validate(path))
    expected = expected_positions(mesh, "z", 1.0)
    size = np.ptp(expected, axis=0).max()
    for loaded in (_pygltflib_world_positions(path), _trimesh_world_positions(path)):
        # Absolute float32 coordinates would be off by ~1e5 * 6e-8 = 6e-3, i.e. 1e-3 of the size.
        assert np.abs(loaded - expected).max() <= 1e-6 * size


def _pygltflib_world_positions(path):
    gltf = pygltflib.GLTF2().load(str(path))
    positions = read_accessor(gltf, gltf.binary_blob(), gltf.meshes[0].primitives[0].attributes.POSITION)
    return positions.astype(np.float64) * (gltf.nodes[0].scale or [1.0])[0] + gltf.nodes[0].translation


def _trimesh_world_positions(path):
    loaded = trimesh.load(path, force="scene", process=False)
    (node,) = loaded.graph.geometry_nodes["far"]
    transform, name = loaded.graph[node]
    return trimesh.transform_points(loaded.geometry[name].vertices, transform)


@pytest.mark.parametrize(("n_around", "n_along", "component"), [
    (255, 257, pygltflib.UNSIGNED_SHORT),  # 65535 vertices: largest index 65534, below the restart value
    (256, 256, pygltflib.UNSIGNED_INT),  # 65536 vertices: index 65535 would be the restart value
])
def test_index_type_follows_vertex_count(tmp_path, gltf_validate, n_around, n_along, component):
    mesh = torus_patch("grid", n_around, n_along)
    path = tmp_path / "grid.glb"
    write_glb(path, [(mesh, Material())], WriteOptions("z", 1.0, "m"))
    assert_clean(gltf_validate(path))
    gltf = pygltflib.GLTF2().load(str(path))
    prim = gltf.meshes[0].primitives[0]
    assert gltf.accessors[prim.indices].componentType == component
    np.testing.assert_array_equal(read_accessor(gltf, gltf.binary_blob(), prim.indices).reshape(-1, 3), mesh.faces)
    targets = [gltf.bufferViews[gltf.accessors[i].bufferView].target for i in (prim.attributes.POSITION, prim.indices)]
    assert targets == [pygltflib.ARRAY_BUFFER, pygltflib.ELEMENT_ARRAY_BUFFER]
    assert all(view.byteOffset % 4 == 0 for view in gltf.bufferViews)


def _with(mesh, **changes):
    fields = {k: getattr(mesh, k) for k in ("name", "positions", "normals", "uvs", "faces", "double_sided")}
    return SurfaceMesh(**{**fields, **changes})


def _poisoned(mesh, field, value):
    array = getattr(mesh, field).copy()
    array[len(array) // 2, 1] = value
    return _with(mesh, **{field: array})


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("field", ["positions", "normals", "uvs"])
def test_non_finite_values_raise_and_write_nothing(tmp_path, field, value):
    mesh = _poisoned(torus_patch("bad", 5, 4), field, value)
    path = tmp_path / "bad.glb"
    with pytest.raises(ExportError, match=f"'bad'.*{field}"):
        write_glb(path, [(mesh, Material())], WriteOptions("z", 1.0, "m"))
    assert os.listdir(tmp_path) == []


def test_refused_export_leaves_existing_file_intact(tmp_path):
    path = tmp_path / "scene.glb"
    path.write_bytes(b"previous good file")
    mesh = _poisoned(torus_patch("bad", 5, 4), "positions", np.nan)
    with pytest.raises(ExportError):
        write_glb(path, [(mesh, Material())], WriteOptions("z", 1.0, "m"))
    assert path.read_bytes() == b"previous good file" and os.listdir(tmp_path) == ["scene.glb"]


def test_failure_mid_write_leaves_existing_file_intact(tmp_path, monkeypatch, scene):
    path = tmp_path / "scene.glb"
    path.write_bytes(b"previous good file")

    def failing_fsync(fd):  # the temp file exists and holds the new data by now
        assert len(os.listdir(tmp_path)) == 2
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(atomic.os, "fsync", failing_fsync)
    with pytest.raises(ExportError, match="scene.glb: No space left on device"):
        write_glb(path, scene, WriteOptions("z", 1.0, "m"))
    assert path.read_bytes() == b"previous good file" and os.listdir(tmp_path) == ["scene.glb"]


def test_missing_directory_is_an_export_error(tmp_path, scene):
    path = tmp_path / "no" / "such" / "scene.glb"
    with pytest.raises(ExportError) as info:
        write_glb(path, scene, WriteOptions("z", 1.0, "m"))
    message = str(info.value)
    assert "\n" not in message and str(path) in message and "does not exist" in message


@pytest.mark.parametrize(("change", "match"), [
    (lambda m: _with(m, normals=2 * m.normals), "unit"),
    (lambda m: _with(m, faces=m.faces + 1), r"face indices must be in \[0, 19\]"),
    (lambda m: _with(m, faces=m.faces[:0]), "empty mesh"),
    (lambda m: _with(m, uvs=m.uvs[:, :1]), r"uvs must have shape \(20, 2\)"),
])
def test_inconsistent_meshes_are_refused(tmp_path, change, match):
    with pytest.raises(ExportError, match=match):
        write_glb(tmp_path / "x.glb", [(change(torus_patch("m", 5, 4)), Material())], WriteOptions("z", 1.0, "m"))
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"up": "x"}, "up must be"),
    ({"meters_per_unit": 0.0}, "meters_per_unit"),
    ({"meters_per_unit": float("nan")}, "meters_per_unit"),
])
def test_bad_arguments_are_refused(tmp_path, scene, kwargs, match):
    args = {"up": "z", "meters_per_unit": 1.0, "source_units": "m", **kwargs}
    with pytest.raises(ExportError, match=match):
        write_glb(tmp_path / "x.glb", scene, WriteOptions(**args))


def test_material_out_of_range_is_refused(tmp_path):
    with pytest.raises(ExportError, match="material"):
        write_glb(tmp_path / "x.glb", [(torus_patch("m", 5, 4), Material((1.5, 0, 0)))], WriteOptions("z", 1.0, "m"))


@pytest.mark.slow
def test_megavertex_write_cost(tmp_path, gltf_validate):
    """Prints the write cost of a 1024 x 1024-vertex mesh (asserts validity, not time).

    Run alone with: python -m pytest -q -s -m slow tests/test_export_gltf.py
    """
    mesh = torus_patch("big", 1024, 1024)
    path = tmp_path / "big.glb"
    times = []
    for _ in range(5):
        start = time.perf_counter()
        written = write_glb(path, [(mesh, Material())], WriteOptions("z", 1.0, "m"))
        times.append(time.perf_counter() - start)
    # Baseline in the same run: the same number of bytes written and fsynced as one raw buffer.
    raw = np.zeros(written, np.uint8)
    base = []
    for _ in range(5):
        start = time.perf_counter()
        with open(tmp_path / "raw.bin", "wb") as f:
            f.write(memoryview(raw))
            f.flush()
            os.fsync(f.fileno())
        base.append(time.perf_counter() - start)
    per_vertex = min(times) / mesh.vertex_count * 1e6
    print(f"\nwrite_glb: {mesh.vertex_count} vertices, {mesh.triangle_count} triangles, {written / 2**20:.1f} MiB: "
          f"best {min(times) * 1e3:.1f} ms = {per_vertex:.3f} us/vertex; "
          f"raw write+fsync of the same bytes {min(base) * 1e3:.1f} ms (ratio {min(times) / min(base):.2f})")
    report = gltf_validate(path)
    assert_clean(report)
    assert report["info"]["totalVertexCount"] == mesh.vertex_count


def test_glb_container_layout(tmp_path, scene):
    path = tmp_path / "scene.glb"
    write_glb(path, scene, WriteOptions("z", 1.0, "m"))
    data = path.read_bytes()
    magic, version, length = np.frombuffer(data[:12], "<u4")
    json_length, json_type = np.frombuffer(data[12:20], "<u4")
    assert (magic, version, length) == (0x46546C67, 2, len(data))
    assert json_type == 0x4E4F534A and json_length % 4 == 0
    doc = json.loads(data[20 : 20 + json_length])  # trailing spaces are valid JSON whitespace
    bin_length, bin_type = np.frombuffer(data[20 + json_length : 28 + json_length], "<u4")
    assert bin_type == 0x004E4942 and bin_length % 4 == 0 and 28 + json_length + bin_length == len(data)
    assert doc["buffers"] == [{"byteLength": int(bin_length)}]


def _stored_normals(path):
    gltf = pygltflib.GLTF2().load(str(path))
    blob = gltf.binary_blob()
    return read_accessor(gltf, blob, gltf.meshes[0].primitives[0].attributes.NORMAL)


def test_float32_normals_unit_within_rounding_are_stored_as_they_are_others_normalised(tmp_path):
    mesh = torus_patch("tube", 300, 240)  # 72,000 vertices: more than one block of rows
    assert mesh.vertex_count > 65536
    rounded = mesh.normals.astype(np.float32)  # unit within float32's rounding
    stored = _stored_normals_of(tmp_path / "rounded.glb", _with(mesh, normals=rounded))
    np.testing.assert_array_equal(stored, rounded @ AXIS_MAP["z"].T.astype(np.float32))
    # float32 normals 1e-4 off unit length are normalised in float64 and rounded once
    long = (mesh.normals * (1.0 + 1e-4)).astype(np.float32)
    stored = _stored_normals_of(tmp_path / "long.glb", _with(mesh, normals=long))
    unit = long.astype(np.float64) / np.linalg.norm(long.astype(np.float64), axis=1, keepdims=True)
    np.testing.assert_array_equal(stored, (unit @ AXIS_MAP["z"].T).astype(np.float32))


@pytest.mark.parametrize("value", [np.nan, 1.01])
def test_bad_float32_normals_name_their_vertex_in_any_block(tmp_path, value):
    mesh = torus_patch("tube", 300, 240)
    normals = mesh.normals.astype(np.float32)
    normals[70000] *= value
    with pytest.raises(ExportError, match="'tube': normals must be finite unit vectors, vertex 70000 has"):
        write_glb(tmp_path / "bad.glb", [(_with(mesh, normals=normals), Material())], WriteOptions("z", 1.0, "m"))
    assert os.listdir(tmp_path) == []


def _stored_normals_of(path, mesh):
    write_glb(path, [(mesh, Material())], WriteOptions("z", 1.0, "m"))
    return _stored_normals(path)
