"""The watertight fallback for a chain that folds: capped frusta and enclosing node spheres,
and the check that tells a folding tube from a sound one."""

from __future__ import annotations

import numpy as np
import pytest

from cgamesh.pipelines.centerlines import TubeOptions, mesh_centerlines
from cgamesh.pipelines.tubes import closed_and_oriented
from cgamesh.inputs.centerlines import Centerlines
from cgamesh.meshing.frusta import enclosing_sphere_scale, frusta, node_spheres


def _volume(mesh) -> float:
    c = mesh.positions[mesh.faces]
    return float(np.einsum("ij,ij->i", c[:, 0], np.cross(c[:, 1], c[:, 2])).sum() / 6.0)


@pytest.mark.parametrize("direction", [(0, 0, 1), (0, 0, -1), (1, 0, 0), (0, 1, 0), (0.3, -0.5, 0.8)])
def test_a_frustum_is_closed_outward_and_has_the_cone_volume(direction):
    a = np.array([1.0, -2.0, 0.5])
    d = np.asarray(direction, float) / np.linalg.norm(direction)
    (piece,) = frusta(np.stack([a, a + 3.0 * d]), np.array([1.0, 0.25]), 64, "f")
    assert closed_and_oriented(piece)
    exact = np.pi * 3.0 / 3.0 * (1.0 + 0.25 + 0.0625)
    polygon = exact * np.sin(2 * np.pi / 64) / (2 * np.pi / 64)  # inscribed 64-gons
    assert _volume(piece) == pytest.approx(polygon, rel=1e-9)
    # side normals are unit and orthogonal to the side's generator lines
    side = slice(0, 2 * 65)
    assert np.allclose(np.linalg.norm(piece.normals[side], axis=1), 1.0)
    generator = piece.positions[65:130] - piece.positions[0:65]
    assert np.allclose(np.einsum("ij,ij->i", generator, piece.normals[0:65]), 0.0, atol=1e-12)


def test_enclosing_spheres_contain_the_ball_strictly():
    scale = enclosing_sphere_scale(8)
    sphere = node_spheres(np.zeros((1, 3)), np.ones(1), 8, "s")
    c = sphere.positions[sphere.faces]
    n = np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0])
    ok = np.linalg.norm(n, axis=1) > 1e-12
    distance = np.einsum("ij,ij->i", n[ok], c[ok, 0]) / np.linalg.norm(n[ok], axis=1)
    assert distance.min() > 1.0 and scale < 1.2


def _bent_chain(radius: float) -> Centerlines:
    # a hairpin 1 wide: radius 0.8 folds (its rings cross), 0.05 does not
    points = np.array([[0.0, 0, 0], [4, 0, 0], [5, 0.3, 0], [5, 1.3, 0], [1, 1.6, 0]])
    parents = np.array([-1, 0, 1, 2, 3])
    return Centerlines(points=points, radii=np.full(5, radius), parents=parents, source="bent.swc")


def test_a_tube_bending_tighter_than_its_radius_is_caught_and_meshed_as_frusta():
    loose = mesh_centerlines(_bent_chain(0.05), TubeOptions(watertight=True, subdivide=3))
    tight = mesh_centerlines(_bent_chain(0.8), TubeOptions(watertight=True, subdivide=3))
    assert loose.skipped == () and tight.skipped == ()
    for built in (loose, tight):
        (mesh,) = built.meshes
        assert closed_and_oriented(mesh)
    assert tight.meshes[0].attributes["segment"].max() == 0.0


@pytest.mark.parametrize("radius, in_order", [(0.05, True), (0.8, False)])
def test_the_ring_order_check_fails_on_a_folding_tube_and_passes_a_thin_one(monkeypatch, radius, in_order):
    import cgamesh.pipelines.tubes as tubes

    seen = []
    original = tubes.rings_in_order
    monkeypatch.setattr(tubes, "rings_in_order", lambda mesh: seen.append(original(mesh)) or seen[-1])
    mesh_centerlines(_bent_chain(radius), TubeOptions(watertight=True, subdivide=3))
    assert seen == [in_order]
