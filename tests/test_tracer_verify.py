"""cgamesh verify: exported meshes of every example pass against the tracer; broken ones fail."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from cgamesh.export.gltf import write_glb
from cgamesh.export.options import GltfOptions, WriteOptions
from cgamesh.pipelines.scene import Resolution, mesh_scene
from cgamesh.inputs.scene import load_scene
from cgamesh.tracer import verify
from cgamesh.tracer.meshfile import read_glb
from cgamesh.tracer.png import read_png
from cgamesh.tracer.world import build_world
from cgamesh_cli.main import main

EXAMPLES = sorted((Path(__file__).resolve().parent.parent / "examples").glob("*.yaml"))
LOW = ["--around", "12", "--along", "24", "-q"]


def export(scene_path: Path, out: Path) -> Path:
    assert main([str(scene_path), "-o", str(out), *LOW]) == 0
    return out


@pytest.mark.parametrize("scene_path", EXAMPLES, ids=lambda p: p.stem)
def test_every_example_mesh_passes_verify_at_the_default_thresholds(scene_path, tmp_path, capsys):
    glb = export(scene_path, tmp_path / "mesh.glb")
    assert main(["verify", str(scene_path), str(glb)]) == 0, capsys.readouterr().out
    table = capsys.readouterr().out
    for spec in load_scene(scene_path).surfaces:
        assert spec.name in table
    assert "FAIL" not in table


@pytest.fixture(scope="module")
def kb_tube(tmp_path_factory):
    """(traced surface, its mesh read back from a GLB) of the KB tube example (with caps)."""
    scene_path = next(p for p in EXAMPLES if p.stem == "kb_tube")
    glb = export(scene_path, tmp_path_factory.mktemp("kb") / "kb.glb")
    scene = load_scene(scene_path)
    return build_world(scene, primitives=False).surfaces()[0], read_glb(glb, scene.up, scene.meters_per_unit)[0]


def test_the_read_back_mesh_is_the_mesher_s_up_to_float32(kb_tube):
    _, mesh = kb_tube
    scene = load_scene(next(p for p in EXAMPLES if p.stem == "kb_tube"))
    original, _ = mesh_scene(scene, Resolution(12, 24))[0]
    np.testing.assert_allclose(mesh.positions, original.positions, atol=1e-6)
    np.testing.assert_allclose(mesh.normals, original.normals, atol=1e-6)
    np.testing.assert_array_equal(mesh.faces, original.faces)


def test_a_flipped_normal_fails_by_its_sign(kb_tube):
    surface, mesh = kb_tube
    normals = mesh.normals.copy()
    normals[40] *= -1.0
    report = verify.check_mesh(surface, replace(mesh, normals=normals))
    assert not report.passed and report.sign_breaks >= 1
    assert report.angle_max < 1e-3  # the line is the same: only the sign check sees it


def test_a_perturbed_normal_fails_by_its_angle(kb_tube):
    surface, mesh = kb_tube
    normals = mesh.normals.copy()
    normals[40] = normals[40] + 0.01 * np.cross(normals[40], [0.3, 0.5, 0.8])
    normals[40] /= np.linalg.norm(normals[40])
    report = verify.check_mesh(surface, replace(mesh, normals=normals))
    assert not report.passed and report.angle_max > verify.MAX_ANGLE_DEGREES and report.sign_breaks == 0


def test_a_displaced_vertex_fails_by_its_distance(kb_tube):
    surface, mesh = kb_tube
    positions = mesh.positions.copy()
    positions[40] += 1e-3 * mesh.normals[40]
    report = verify.check_mesh(surface, replace(mesh, positions=positions))
    assert not report.passed and report.distance_max > 1e-4


def test_an_inward_normal_field_fails_the_outward_check(kb_tube):
    surface, mesh = kb_tube
    report = verify.check_mesh(surface, replace(mesh, normals=-mesh.normals))
    assert report.outward is False and report.sign_breaks == 0 and not report.passed


def test_verify_exits_1_on_a_broken_file_and_writes_the_comparison_image(tmp_path, capsys):
    scene_path = next(p for p in EXAMPLES if p.stem == "fig18_linear_surface")
    scene = load_scene(scene_path)
    meshes = mesh_scene(scene, Resolution(12, 24))
    good = tmp_path / "good.glb"
    write_glb(good, meshes, WriteOptions(scene.up, scene.meters_per_unit, scene.units))
    image = tmp_path / "diff.png"
    assert main(["verify", str(scene_path), str(good), "--image", str(image), "--size", "40x30"]) == 0
    assert read_png(image).shape == (30, 120, 3)
    mesh, material = meshes[0]
    normals = mesh.normals.copy()
    normals[5] *= -1.0
    bad = tmp_path / "bad.glb"
    write_glb(bad, [(replace(mesh, normals=normals), material)], WriteOptions(scene.up, scene.meters_per_unit, scene.units))
    capsys.readouterr()
    assert main(["verify", str(scene_path), str(bad)]) == 1
    assert "FAIL" in capsys.readouterr().out


def test_verify_reads_quantized_files_within_their_precision(tmp_path):
    scene_path = next(p for p in EXAMPLES if p.stem == "rational_tube")
    scene = load_scene(scene_path)
    glb = tmp_path / "q.glb"
    write_glb(glb, mesh_scene(scene, Resolution(12, 24)), WriteOptions(scene.up, scene.meters_per_unit, scene.units, GltfOptions(quantize=True)))
    surface = build_world(scene, primitives=False).surfaces()[0]
    report = verify.check_mesh(surface, read_glb(glb, scene.up, scene.meters_per_unit)[0],
                               verify.Thresholds(max_angle=1.5, max_distance=2e-4))
    assert report.passed, report


def test_verify_names_a_missing_mesh(tmp_path, capsys):
    glb = export(next(p for p in EXAMPLES if p.stem == "fig08_linear"), tmp_path / "a.glb")
    assert main(["verify", str(next(p for p in EXAMPLES if p.stem == "kb_tube")), str(glb)]) == 2
    assert "no mesh named 'kb_tube'" in capsys.readouterr().err
