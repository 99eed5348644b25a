"""Centreline inputs under a tolerance: each junction and soma sphere gets the fewest vertices
around whose mesh stays within the tolerance of it (cgamesh.meshing.junctions.deviation_bound),
and the whole run is priced against the memory budget before any mesh is made, a refusal naming
about the tolerance that would fit."""

from __future__ import annotations

import os
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import cgamesh.pipelines.scene
from direction_strategies import direction
from cgamesh.budget import ResourceLimitError
from cgamesh.pipelines.centerlines import TubeOptions, mesh_centerlines
from cgamesh.pipelines.spheres import spheres_around
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
                                                r"soma spheres: a sphere of radius (1|5) needs more than 4096"):
        mesh_centerlines(read_centerlines(str(source)), TubeOptions(tolerance=1e-9))


def test_a_tolerance_run_over_the_budget_is_refused_before_any_mesh_with_a_tolerance_that_fits(tmp_path,
                                                                                                 monkeypatch):
    source = tmp_path / "tree.swc"
    source.write_text(TREE)
    lines = read_centerlines(str(source))

    def no_mesh(*args, **kwargs):
        raise AssertionError("a mesh was made before the run was priced")

    with monkeypatch.context() as patch:
        patch.setattr(cgamesh.pipelines.scene, "mesh_planned", no_mesh)
        with pytest.raises(ResourceLimitError) as refusal:
            mesh_centerlines(lines, TubeOptions(tolerance=1e-4), max_memory="40M", outputs=["tree.glb"])
    message = str(refusal.value)
    assert message.startswith(f"{source} with tolerance 0.0001 asks for ")
    assert "the limit is 40 MiB (--max-memory)" in message
    fitting = float(re.search(r"a tolerance of about ([0-9.e+-]+) would fit$", message).group(1))
    assert 1e-4 < fitting < 1e-2
    built = mesh_centerlines(lines, TubeOptions(tolerance=fitting), max_memory="40M", outputs=["tree.glb"])
    assert sum(mesh.vertex_count for mesh in built.meshes) > 0


def test_a_tolerance_run_far_over_the_budget_is_refused_early(tmp_path):
    """Priced as its chains are planned: refused once the chains so far exceed the budget, the
    rest extrapolated from them, before the remaining chains are planned."""
    source = tmp_path / "chains.swc"
    rows, node = [], 1
    for chain in range(40):  # 40 chains of 6 nodes, each its own root
        for k in range(6):
            rows.append(f"{node} 3 {10.0 * k} {3.0 * chain} 0 1 {-1 if k == 0 else node - 1}")
            node += 1
    source.write_text("\n".join(rows) + "\n")
    labels = []
    with pytest.raises(ResourceLimitError, match=r"extrapolated from the first \d+ tubes planned\); the limit is "
                                                  r"40 MiB \(--max-memory\); a tolerance of about .* would fit"):
        mesh_centerlines(read_centerlines(str(source)), TubeOptions(tolerance=1e-5), max_memory="40M",
                         progress=lambda label, count=1: labels.append(label))
    assert 0 < len(labels) < 40


@settings(max_examples=int(os.environ.get("CGAMESH_PROPERTY_EXAMPLES", "40")) // 4 or 1, deadline=None)
@given(first=direction, second=direction, scale=st.sampled_from([1e-3, 1.0, 1e3]),
       radii=st.tuples(st.floats(0.2, 1.0), st.floats(0.05, 0.2), st.floats(0.05, 0.2)),
       relative=st.sampled_from([1e-2, 1e-3]))
def test_every_sphere_of_a_random_tree_is_within_the_tolerance(first, second, scale, radii, relative, tmp_path_factory):
    """A soma node and a branch node with two children in random directions (the exact axes
    among them), at sizes from 1e-3 to 1e3: each sphere's triangles lie within the tolerance."""
    first, second = np.asarray(first, float), np.asarray(second, float)
    first, second = first / np.linalg.norm(first), second / np.linalg.norm(second)
    soma, junction = radii[0] * scale, radii[1] * scale
    branch = np.array([4.0, 0.0, 0.0]) * scale
    rows = [f"1 1 0 0 0 {soma!r} -1", f"2 3 {2.0 * scale!r} 0 0 {junction!r} 1",
            f"3 3 {float(branch[0])!r} 0 0 {junction!r} 2"]
    for k, d in enumerate((first, second)):
        tip = (branch + 3.0 * scale * d).tolist()
        rows.append(f"{4 + k} 3 {tip[0]!r} {tip[1]!r} {tip[2]!r} {radii[2] * scale!r} 3")
    source = tmp_path_factory.mktemp("tree") / "tree.swc"
    source.write_text("\n".join(rows) + "\n")
    tolerance = relative * scale
    built = mesh_centerlines(read_centerlines(str(source)), TubeOptions(tolerance=tolerance, split=True))
    spheres = {mesh.name.rsplit("_", 1)[-1]: mesh for mesh in built.meshes
               if mesh.name.endswith(("_junctions", "_soma"))}
    assert sphere_deviation(spheres["soma"], np.zeros(3), soma) <= tolerance
    assert sphere_deviation(spheres["junctions"], branch, junction) <= tolerance
