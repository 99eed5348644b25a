"""Float32 files keep a surface's precision far from the origin (positions relative to a translation).

A tube centred 1e5 from the origin is exported; its vertices, read back through the file's
own transforms, stay on the true surface within 1e-6 of the surface's size, although float32
alone would put them ~1e-3 of the size off at that distance.
"""

from __future__ import annotations

import numpy as np
import pytest

from export_checks import pxr_or_skip
from cgamesh.export.options import WriteOptions
from cgamesh.meshing.tolerance.deviation import circle_read_out
from cgamesh.export.registry import write
from cgamesh.pipelines.scene import Resolution, build_surface, mesh_scene
from cgamesh.readers.readback import read_gltf
from cgamesh.inputs.scene import parse_scene

FAR = """\
cgamesh: 1
up: z
surfaces:
  - name: far_tube
    type: circles
    curve: kb
    controls:
      - {center: [100000.0, -60000.0, 80000.0], normal: [0, 0, 1], radius: 0.5}
      - {center: [100000.4, -60000.1, 80001.0], normal: [0.3, 0, 1], radius: 0.4}
      - {center: [100001.2, -60000.0, 80001.8], normal: [1, 0, 0.6], radius: 0.45}
"""
AROUND, ALONG = 16, 48


def distance_to_surface(surface, points: np.ndarray) -> np.ndarray:
    """Distances of grid points (ALONG, AROUND + 1, 3) to their rings' true circles."""
    centre, normal, radius = circle_read_out(surface, np.linspace(0.0, surface.segment_count, ALONG))
    offset = points - centre[:, None, :]
    height = np.einsum("kmi,ki->km", offset, normal)
    in_plane = np.linalg.norm(offset - height[..., None] * normal[:, None, :], axis=-1)
    return np.hypot(height, in_plane - radius[:, None])


@pytest.fixture(scope="module")
def far():
    scene = parse_scene(FAR, "far.yaml")
    meshes = mesh_scene(scene, Resolution(AROUND, ALONG))
    surface = build_surface(scene.surfaces[0])
    return scene, meshes, surface


def test_glb_positions_through_the_node_translation_stay_on_the_surface(far, tmp_path):
    scene, meshes, surface = far
    path = tmp_path / "far.glb"
    write(path, meshes, WriteOptions(scene.up, scene.meters_per_unit, scene.units))
    gltf_world = read_gltf(path, world=True)[0].positions
    # glTF (x, y, z) is the scene's (x, -z, y) for up: z, in metres (units m).
    scene_frame = np.stack([gltf_world[:, 0], -gltf_world[:, 2], gltf_world[:, 1]], axis=1)
    grid = scene_frame[: ALONG * (AROUND + 1)].reshape(ALONG, AROUND + 1, 3)
    assert distance_to_surface(surface, grid).max() <= 1e-6 * surface.frame.scale
    # Without the translation, float32 could not do it: its spacing at 1e5 is ~8e-3.
    assert np.spacing(np.float32(1e5)) > 1e-3 * surface.frame.scale


def test_usd_points_through_the_xform_translation_stay_on_the_surface(far, tmp_path):
    pxr_or_skip()
    from pxr import Usd, UsdGeom

    scene, meshes, surface = far
    path = tmp_path / "far.usda"
    write(path, meshes, WriteOptions(scene.up, scene.meters_per_unit, scene.units))
    stage = Usd.Stage.Open(str(path))
    prim = next(p for p in stage.Traverse() if p.IsA(UsdGeom.Mesh))
    matrix = np.array(UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(Usd.TimeCode.Default()), dtype=np.float64)
    points = np.array(UsdGeom.Mesh(prim).GetPointsAttr().Get(), dtype=np.float64)
    world = points @ matrix[:3, :3] + matrix[3, :3]  # USD matrices act on row vectors
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.z  # no axis swap for .usda
    # USD welds the seam: compare every point with its nearest grid vertex of the true surface.
    mesh = meshes[0][0]
    grid = mesh.positions[: ALONG * (AROUND + 1)]
    nearest = np.argmin(np.linalg.norm(world[:, None, :] - grid[None, :, :], axis=-1), axis=1)
    assert np.linalg.norm(world - grid[nearest], axis=1).max() <= 1e-6 * surface.frame.scale
