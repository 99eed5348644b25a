"""Junction spheres (exact normals, closed, outward) and merging meshes into one."""

from __future__ import annotations

import numpy as np
import pytest

from cgamesh.meshing.junctions import sphere_bands, uv_spheres
from cgamesh.meshing.merge import merge
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.meshing.weld import weld_by_position


@pytest.mark.parametrize("around", [3, 4, 8, 13])
def test_spheres_are_closed_outward_with_exact_normals(around):
    centres = np.array([[0.0, 0, 0], [1e5, -3, 2], [0.5, 0.5, 0.5]])
    radii = np.array([1.0, 1e-4, 1e4])
    mesh = uv_spheres(centres, radii, around)
    per = (around + 1) * (sphere_bands(around) + 1)
    assert mesh.vertex_count == 3 * per
    which = np.repeat(np.arange(3), per)
    offset = mesh.positions - centres[which]
    # within the float64 spacing at each sphere's coordinates (a tiny sphere far from the origin)
    spacing = 4 * np.finfo(float).eps * (np.abs(centres).max(axis=1) + radii)[which]
    assert np.all(np.abs(np.linalg.norm(offset, axis=1) - radii[which]) <= 1e-12 * radii[which] + spacing)
    assert np.all(np.abs(mesh.normals - offset / radii[which][:, None]).max(axis=1) <= 1e-12 + spacing / radii[which])
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-15)
    faces = mesh.weld[mesh.faces]
    assert np.all((faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2]))
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    directed = {tuple(e) for e in edges.tolist()}
    assert len(directed) == len(edges)  # each directed edge once ...
    assert all((b, a) in directed for a, b in directed)  # ... and its reverse too: closed, consistently wound
    # counter-clockwise seen from outside: each face's normal points away from its sphere's centre
    corner = mesh.positions[mesh.faces]
    normal = np.cross(corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0])
    assert np.all(np.einsum("fc,fc->f", normal, corner.mean(axis=1) - centres[which[mesh.faces[:, 0]]]) > 0)


def test_merge_offsets_faces_and_keeps_colours_and_shared_attributes():
    a = uv_spheres(np.zeros((1, 3)), np.ones(1), 4)
    b = uv_spheres(np.array([[0.0, 0, 2]]), np.ones(1), 4)  # touches a at one pole
    paint = lambda m, c, extra: SurfaceMesh(**{**m.__dict__, "colors": np.full((m.vertex_count, 3), c),
                                                "attributes": {"radius": np.full(m.vertex_count, c), **extra}})
    a2 = paint(a, 0.25, {"only_a": np.zeros(a.vertex_count)})
    b2 = paint(b, 0.75, {})
    merged = merge([a2, b2], "both")
    assert merged.vertex_count == a.vertex_count + b.vertex_count
    np.testing.assert_array_equal(merged.faces[: a.triangle_count], a.faces)
    np.testing.assert_array_equal(merged.faces[a.triangle_count:], b.faces + a.vertex_count)
    assert merged.faces.dtype == np.int32
    assert set(merged.attributes) == {"radius"}
    np.testing.assert_array_equal(merged.colors[:, 0], np.r_[np.full(a.vertex_count, 0.25), np.full(b.vertex_count, 0.75)])
    # no weld is stored (consumers derive it from the positions); the positional weld joins the
    # bit-identical pole the two spheres share
    assert merged.weld is None and merged.uv_lengths is None
    top_of_a = np.flatnonzero(np.all(merged.positions == [0.0, 0.0, 1.0], axis=1))
    assert len(top_of_a) == 2 * 5 and len(set(weld_by_position(merged.positions)[top_of_a].tolist())) == 1
    # without colours on every piece, none
    assert merge([a, b2], "mixed").colors is None


@pytest.mark.parametrize("color_by", ["direction", "radius"])
def test_spheres_merged_a_block_at_a_time_are_the_spheres_merged_whole(color_by, monkeypatch):
    """A merged run hands the junction and soma spheres over in blocks of SPHERE_BLOCK_VERTICES:
    the merged mesh is the one made from each group's whole mesh, bit for bit (blocks of 7
    spheres on a neuron with hundreds of junctions and a soma of twelve nodes, against one block)."""
    from dataclasses import replace

    import cgamesh.pipelines.centerlines as pipeline
    from cgamesh.inputs.centerlines import read_centerlines
    from realdata_files import smallest_neuron

    lines = read_centerlines(str(smallest_neuron()))
    kinds = lines.kinds.copy()
    kinds[:12] = pipeline.SOMA  # a soma of twelve nodes (this neuron's file has none)
    lines = replace(lines, kinds=kinds)
    options = pipeline.TubeOptions(radius=40.0, color_by=color_by)
    monkeypatch.setattr(pipeline, "SPHERE_BLOCK_VERTICES", 10**9)
    whole = pipeline.mesh_centerlines(lines, options, as_written=True).meshes[0]
    monkeypatch.setattr(pipeline, "SPHERE_BLOCK_VERTICES", 7 * 45)  # 45 vertices a sphere at 8 around
    blocks = pipeline.mesh_centerlines(lines, options, as_written=True).meshes[0]
    assert np.count_nonzero(lines.kinds == pipeline.SOMA) > 7  # the soma group is split as well
    for channel in ("positions", "normals", "uvs", "faces", "colors"):
        np.testing.assert_array_equal(getattr(blocks, channel), getattr(whole, channel))
    assert sorted(blocks.attributes) == sorted(whole.attributes)
    for key in whole.attributes:
        np.testing.assert_array_equal(blocks.attributes[key], whole.attributes[key])
