"""Every example scene builds, exports a GLB the Khronos validator accepts, and reloads intact."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pygltflib
import pytest
import trimesh

from cgamesh.pipelines.scene import Resolution, mesh_scene
from cgamesh.inputs.scene import load_scene
from cgamesh_cli.main import main
from gltf_validator import assert_clean

EXAMPLES = sorted((Path(__file__).resolve().parent.parent / "examples").glob("*.yaml"))
LOW = ["--around", "12", "--along", "24"]


def test_there_are_examples_of_every_paper_figure():
    names = {path.stem for path in EXAMPLES}
    for figure in ("fig08_linear", "fig08_quadratic", "fig08_cubic", "fig14_bezier_orders", "kb_tube",
                   "fig18_linear_surface"):
        assert figure in names


@pytest.mark.parametrize("scene_path", EXAMPLES, ids=lambda p: p.stem)
def test_example_exports_a_valid_glb_that_reloads(scene_path, tmp_path, gltf_validate, capsys):
    output = tmp_path / f"{scene_path.stem}.glb"
    assert main([str(scene_path), "-o", str(output), *LOW]) == 0
    assert capsys.readouterr().err == ""
    assert_clean(gltf_validate(output))

    scene = load_scene(scene_path)
    meshes = mesh_scene(scene, Resolution(12, 24))
    document = pygltflib.GLTF2().load(str(output))
    assert [m.name for m in document.meshes] == [spec.name for spec in scene.surfaces]
    reloaded = trimesh.load(str(output), force="scene", process=False)
    for (mesh, _), spec in zip(meshes, scene.surfaces):
        geometry = reloaded.geometry[spec.name]
        assert len(geometry.vertices) == mesh.vertex_count
        assert len(geometry.faces) == mesh.triangle_count
        assert np.all(np.isfinite(mesh.positions)) and np.all(np.isfinite(mesh.normals))
        np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-12)
        assert mesh.uvs.min() >= 0.0 and mesh.uvs.max() <= 1.0


@pytest.mark.parametrize("scene_path", EXAMPLES, ids=lambda p: p.stem)
def test_example_triangles_wind_with_their_normals_and_have_area(scene_path):
    for mesh, _ in mesh_scene(load_scene(scene_path), Resolution(24, 48)):
        corners = mesh.positions[mesh.faces]
        geometric = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        assert np.all(np.linalg.norm(geometric, axis=1) > 0.0)
        agreement = np.einsum("ti,ti->t", geometric, mesh.normals[mesh.faces].sum(axis=1))
        assert np.all(agreement > 0.0), f"{np.count_nonzero(agreement <= 0)} triangles wind against their normals"
