"""Junction and soma spheres under a tolerance: each sphere gets the fewest vertices around
whose mesh stays within the tolerance of it (cgamesh.meshing.junctions.deviation_bound), and a
real-data tolerance run meshes them so."""

from __future__ import annotations

import os

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cgamesh.centerline_pipeline import TubeOptions, mesh_centerlines, spheres_around
from cgamesh.errors import InvalidInputError
from cgamesh.inputs.centerlines import read_centerlines
from cgamesh.meshing.junctions import around_within, deviation_bound, uv_spheres

PROPERTY = settings(max_examples=int(os.environ.get("CGAMESH_PROPERTY_EXAMPLES", "40")), deadline=None)


def sphere_deviation(mesh, centre, radius) -> float:
    """The largest distance from the sphere of 15 points in every triangle and its corners."""
    weights = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1], [4, 1, 1], [1, 4, 1], [1, 1, 4], [2, 2, 1],
                        [2, 1, 2], [1, 2, 2], [6, 1, 1], [1, 6, 1], [1, 1, 6], [3, 3, 1], [1, 3, 3]], float)
    weights /= weights.sum(axis=1, keepdims=True)
    points = np.einsum("sk,tkc->tsc", weights, mesh.positions[mesh.faces])
    return float(np.abs(np.linalg.norm(points - centre, axis=-1) - radius).max())


@PROPERTY
@given(around=st.integers(3, 400))
def test_the_bound_holds_over_the_triangles_and_is_nearly_reached(around):
    mesh = uv_spheres(np.zeros((1, 3)), np.ones(1), around)
    measured = sphere_deviation(mesh, np.zeros(3), 1.0)
    bound = deviation_bound(around)
    assert measured <= bound * (1.0 + 1e-9) + 1e-15
    assert measured >= 0.5 * bound  # the circumcircle's deepest point is near a triangle's middle


def test_the_bound_falls_as_the_count_grows():
    bounds = np.array([deviation_bound(m) for m in range(3, 600)])
    assert np.all(np.diff(bounds) < 0.0)


@PROPERTY
@given(radius=st.floats(1e-3, 1e3), relative=st.floats(1e-5, 0.5))
def test_the_count_is_the_fewest_meeting_the_tolerance(radius, relative):
    tolerance = relative * radius
    around = around_within(radius, tolerance)
    assert radius * deviation_bound(around) <= tolerance
    assert around == 4 or radius * deviation_bound(around - 1) > tolerance
    assert spheres_around(np.array([radius, radius / 2.0]), tolerance)[0] == around


# A soma of one node and a branch node with two children: one soma sphere, one junction sphere.
TREE = ("1 1 0 0 0 5 -1\n"
        "2 3 10 0 0 1 1\n"
        "3 3 20 0 0 1 2\n"
        "4 3 30 4 0 0.8 3\n"
        "5 3 30 -4 1 0.6 3\n")


@pytest.mark.parametrize("tolerance", [1e-2, 1e-3])
def test_a_tolerance_run_meshes_its_spheres_within_the_tolerance(tolerance, tmp_path):
    source = tmp_path / "tree.swc"
    source.write_text(TREE)
    built = mesh_centerlines(read_centerlines(str(source)), TubeOptions(tolerance=tolerance, split=True))
    spheres = {mesh.name.rsplit("_", 1)[-1]: mesh for mesh in built.meshes
               if mesh.name.endswith(("_junctions", "_soma"))}
    assert set(spheres) == {"junctions", "soma"}
    for name, centre, radius in (("soma", (0.0, 0.0, 0.0), 5.0), ("junctions", (20.0, 0.0, 0.0), 1.0)):
        mesh = spheres[name]
        around = around_within(radius, tolerance)
        assert mesh.vertex_count == uv_spheres(np.zeros((1, 3)), np.ones(1), around).vertex_count
        assert sphere_deviation(mesh, np.array(centre), radius) <= tolerance


def test_a_fixed_resolution_keeps_the_count_around(tmp_path):
    source = tmp_path / "tree.swc"
    source.write_text(TREE)
    built = mesh_centerlines(read_centerlines(str(source)), TubeOptions(around=8, split=True))
    spheres = [mesh for mesh in built.meshes if mesh.name.endswith(("_junctions", "_soma"))]
    assert [m.vertex_count for m in spheres] == [uv_spheres(np.zeros((1, 3)), np.ones(1), 8).vertex_count] * 2


def test_a_tolerance_too_small_for_a_sphere_is_refused_before_meshing(tmp_path):
    source = tmp_path / "tree.swc"
    source.write_text(TREE)
    with pytest.raises(InvalidInputError, match=r"tree\.swc: tolerance 1e-09 is too small for the junction and "
                                                r"soma spheres: a sphere of radius 5 needs more than 4096"):
        mesh_centerlines(read_centerlines(str(source)), TubeOptions(tolerance=1e-9))
