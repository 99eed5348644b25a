"""--watertight on a real neuron (navis' hemibrain skeleton 722817260, the issue's example)
through the command line, the written PLY checked by MeshLab (pymeshlab) after welding
identical positions, and MeshLab's self-intersection flags decided exactly."""

from __future__ import annotations

import numpy as np
import pytest
from exact_intersections import confirmed_intersections
from realdata_files import neurons

from cgamesh.inputs.swc import read_swc
from cgamesh_cli.main import main

pymeshlab = pytest.importorskip("pymeshlab", reason="SKIPPED, NOT CHECKED: pymeshlab is not installed")
pytest.importorskip("manifold3d", reason="SKIPPED, NOT CHECKED: manifold3d is not installed")

pytestmark = pytest.mark.slow  # about 10 s of meshing and union, and MeshLab's checks


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    source = next(p for p in neurons() if p.stem == "722817260")
    target = tmp_path_factory.mktemp("watertight") / "neuron.ply"
    code = main([str(source), "-o", str(target), "--watertight", "--min-radius", "0.5", "-q"])
    meshes = pymeshlab.MeshSet()
    meshes.load_new_mesh(str(target))
    meshes.meshing_remove_duplicate_vertices()
    topology = meshes.get_topological_measures()
    meshes.compute_selection_by_self_intersections_per_face()
    mesh = meshes.current_mesh()
    welded = (np.array(mesh.vertex_matrix()), np.array(mesh.face_matrix()),
              np.flatnonzero(mesh.face_selection_array()))  # copies: the MeshSet owns the mesh
    roots = int(np.count_nonzero(read_swc(source).parents < 0))
    return code, topology, welded, roots


def test_a_real_neuron_is_one_closed_two_manifold_surface_per_tree(written):
    code, topology, (_, faces, _), roots = written
    assert code == 0  # no tube skipped: a folding one is meshed as frusta between node spheres
    assert len(faces) > 100_000
    assert topology["boundary_edges"] == 0
    assert topology["non_two_manifold_edges"] == 0
    assert topology["non_two_manifold_vertices"] == 0
    assert topology["connected_components_number"] == roots == 1


@pytest.mark.xfail(strict=True, reason="known: float32 rounding of the written positions (steps of 0.004 at "
                   "35,000 units) still makes a few sliver triangles of the union cross their neighbours; "
                   "the float64 union has none")
def test_a_real_neuron_has_no_exactly_confirmed_self_intersections(written):
    _, _, (points, faces, flagged), _ = written
    assert confirmed_intersections(points, faces, flagged) == []
