"""Every example exported to every format from one meshing, checked by the formats' own tools.

.glb / .gltf: the Khronos glTF-Validator (0 errors, 0 warnings), plain and with --quantize
--tangents, and a reload; USD: usd-core's compliance checks, the mesh checks they skip, and a
reload of points, normals and st; .obj / .ply / .stl: a reload through trimesh with the same
counts.
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np
import pytest
import trimesh

from cgamesh.export import usdz
from cgamesh.export.registry import WRITERS
from cgamesh.pipelines.scene import Resolution, mesh_scene
from cgamesh.inputs.scene import load_scene
from cgamesh_cli.main import main
from export_checks import check_gltf_reload, check_usd_file, pxr_or_skip
from gltf_validator import assert_clean, validate_many

EXAMPLES = sorted((Path(__file__).resolve().parent.parent / "examples").glob("*.yaml"))
AROUND, ALONG = 8, 12
LOW = ["--around", str(AROUND), "--along", str(ALONG)]
USD = (".usda", ".usdc", ".usd", ".usdz")
TRIMESH = (".obj", ".ply", ".stl")


@pytest.fixture(scope="module")
def exported(tmp_path_factory, request):
    """{example stem: (folder, meshes, scene)}: every example written to every format, and to
    .glb / .gltf again with --quantize --tangents (two runs of the command, one meshing each)."""
    out = {}
    for scene_path in EXAMPLES:
        folder = tmp_path_factory.mktemp(scene_path.stem)
        outputs = [str(folder / f"plain{suffix}") for suffix in WRITERS]
        assert main([str(scene_path), *[a for o in outputs for a in ("-o", o)], *LOW, "-q"]) == 0
        packed = [str(folder / "packed.glb"), str(folder / "packed.gltf")]
        assert main([str(scene_path), "-o", packed[0], "-o", packed[1], "--quantize", "--tangents", *LOW, "-q"]) == 0
        scene = load_scene(scene_path)
        out[scene_path.stem] = (folder, mesh_scene(scene, Resolution(AROUND, ALONG), tangents=True), scene)
    return out


def test_every_format_has_a_writer():
    assert set(WRITERS) == {".glb", ".gltf", *USD, *TRIMESH}


def test_gltf_files_of_every_example_validate(exported, gltf_validate):
    paths = [folder / name for folder, _, _ in exported.values()
             for name in ("plain.glb", "plain.gltf", "packed.glb", "packed.gltf")]
    for path in paths:
        assert path.is_file(), path
    for path, report in zip(paths, validate_many(paths)):
        assert_clean(report)
        assert report["info"]["totalVertexCount"] > 0, path


@pytest.mark.parametrize("stem", [p.stem for p in EXAMPLES])
def test_gltf_files_reload_with_the_same_values(exported, stem):
    folder, meshes, scene = exported[stem]
    for name, quantized, tangents in (("plain.glb", False, False), ("plain.gltf", False, False),
                                      ("packed.glb", True, True), ("packed.gltf", True, True)):
        check_gltf_reload(folder / name, meshes, up=scene.up, meters_per_unit=scene.meters_per_unit,
                          quantized=quantized, tangents=tangents)
    assert (folder / "plain.bin").is_file() and (folder / "packed.bin").is_file()


@pytest.mark.parametrize("stem", [p.stem for p in EXAMPLES])
def test_usd_files_pass_compliance_and_mesh_checks_and_reload(exported, stem):
    pxr_or_skip()
    folder, meshes, scene = exported[stem]
    for suffix in USD:
        check_usd_file(folder / f"plain{suffix}", meshes, up=scene.up, meters_per_unit=scene.meters_per_unit)


@pytest.mark.parametrize("stem", [p.stem for p in EXAMPLES])
def test_usdz_holds_one_stored_crate_aligned_to_64_bytes(exported, stem):
    # The usdz specification's layout, read straight off the archive's headers.
    folder, _, _ = exported[stem]
    entries = usdz.data_offsets(folder / "plain.usdz")
    assert [(name, compression) for name, _, compression in entries] == [("plain.usdc", zipfile.ZIP_STORED)]
    assert entries[0][1] % 64 == 0
    with zipfile.ZipFile(folder / "plain.usdz") as package:
        assert package.testzip() is None  # CRC and sizes as stored
        assert package.read("plain.usdc")[:8] == b"PXR-USDC"


@pytest.mark.parametrize("name_length", range(1, 70))
def test_usdz_padding_aligns_every_name_length(tmp_path, name_length):
    crate = tmp_path / "crate"
    crate.write_bytes(b"PXR-USDC" + bytes(range(256)) * 3)
    name = "n" * name_length
    with open(tmp_path / "p.usdz", "wb") as archive:
        usdz.write_package(crate, archive, name)
    (entry, offset, compression), = usdz.data_offsets(tmp_path / "p.usdz")
    assert (entry, offset % 64, compression) == (name, 0, zipfile.ZIP_STORED)
    with zipfile.ZipFile(tmp_path / "p.usdz") as package:
        assert package.read(name) == crate.read_bytes()


def test_a_crate_too_large_for_a_usdz_is_refused(tmp_path, monkeypatch):
    crate = tmp_path / "crate"
    crate.write_bytes(bytes(100))
    monkeypatch.setattr(usdz, "LARGEST", 100)
    with open(tmp_path / "p.usdz", "wb") as archive, pytest.raises(usdz.PackageTooLargeError, match="Zip64"):
        usdz.write_package(crate, archive, "x.usdc")


@pytest.mark.parametrize("stem", [p.stem for p in EXAMPLES])
def test_obj_ply_stl_reload_through_trimesh_with_the_same_counts(exported, stem):
    folder, meshes, _ = exported[stem]
    vertices = sum(mesh.vertex_count for mesh, _ in meshes)
    triangles = sum(mesh.triangle_count for mesh, _ in meshes)
    obj = trimesh.load(folder / "plain.obj", force="scene", process=False)
    assert sorted(obj.geometry) == sorted(m.name for m, _ in meshes)
    for mesh, _ in meshes:
        geometry = obj.geometry[mesh.name]
        assert (len(geometry.vertices), len(geometry.faces)) == (mesh.vertex_count, mesh.triangle_count)
        np.testing.assert_allclose(geometry.vertices, mesh.positions, atol=1e-7 * max(1.0, np.abs(mesh.positions).max()))
        np.testing.assert_allclose(geometry.vertex_normals, mesh.normals, atol=1e-7)
    ply = trimesh.load(folder / "plain.ply", process=False)
    assert (len(ply.vertices), len(ply.faces)) == (vertices, triangles)
    np.testing.assert_allclose(ply.vertex_normals, np.concatenate([m.normals for m, _ in meshes]), atol=1e-6)
    stl = trimesh.load(folder / "plain.stl", process=False)
    assert len(stl.faces) == triangles
    welded = {tuple(p) for mesh, _ in meshes for p in np.asarray(mesh.positions, dtype=np.float32)}
    assert len({tuple(p) for p in np.asarray(stl.vertices, dtype=np.float32)}) == len(welded)
    assert (folder / "plain.mtl").is_file()
