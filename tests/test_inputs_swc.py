"""SWC skeletons: the parser on real and malformed files, chains and junctions, tubes that meet
without notches, and real neurons through the command line into every format."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import realdata_files
from cgamesh.pipelines.centerlines import TubeOptions, mesh_centerlines
from cgamesh.errors import InvalidInputError
from cgamesh.inputs.swc import parse_swc, read_swc
from cgamesh.inputs.trees import split_tree
from cgamesh.meshing.weld import weld_by_position
from cgamesh_cli.main import main

GOOD = """# a small tree: a soma, a trunk that forks twice, ids out of order and a second root
1 1 0 0 0 2.0 -1
2 3 0 0 3 0.5 1
3 3 0 0 6 0.5 2
5 3 2 1 9 0.3 3
4 3 -2 0 8 0.4 3
6 3 3 2 11 0.25 5
7 3 1 3 12 0.25 5
10 2 20 0 0 0.6 -1
11 2 20 0 4 0.5 10
"""


def test_real_neurons_parse_into_one_record_a_line_with_trees():
    for path in realdata_files.neurons():
        records = [line for line in path.read_text().splitlines() if line.strip() and not line.startswith("#")]
        table = np.loadtxt(records)
        lines = read_swc(path)
        assert len(lines.points) == len(records)
        np.testing.assert_array_equal(lines.points, table[:, 2:5])
        np.testing.assert_array_equal(lines.radii, table[:, 5])
        roots = lines.parents < 0
        np.testing.assert_array_equal(roots, table[:, 6] < 0)
        # each parent index points at the node with the file's parent id
        np.testing.assert_array_equal(lines.ids[lines.parents[~roots]], table[~roots, 6])
        assert lines.units == "um"


def test_chains_cover_every_edge_once_and_break_exactly_at_junctions():
    for path in realdata_files.neurons()[:2]:
        parents = read_swc(path).parents
        chains = split_tree(parents)
        children = np.bincount(parents[parents >= 0], minlength=len(parents))
        edges = []
        for i in range(len(chains)):
            nodes = chains.chain(i)
            assert len(nodes) >= 2
            np.testing.assert_array_equal(parents[nodes[1:]], nodes[:-1])  # a path down the tree
            assert np.all(children[nodes[1:-1]] == 1)  # unbranched inside
            assert children[nodes[-1]] != 1  # ends at a leaf or a junction
            assert parents[nodes[0]] < 0 or children[nodes[0]] >= 2  # starts at a root or a junction
            edges.extend(nodes[1:].tolist())
        assert sorted(edges) == np.flatnonzero(parents >= 0).tolist()
        np.testing.assert_array_equal(chains.junctions, np.flatnonzero(children >= 2))


def test_several_roots_and_ids_out_of_order():
    lines = parse_swc(GOOD, "good.swc")
    chains = split_tree(lines.parents)
    as_ids = sorted(tuple(lines.ids[chains.chain(i)].tolist()) for i in range(len(chains)))
    assert as_ids == [(1, 2, 3), (3, 4), (3, 5), (5, 6), (5, 7), (10, 11)]
    assert lines.ids[chains.junctions].tolist() == [3, 5]


# name -> (SWC text, line the message must name, words it must contain)
MALFORMED = {
    "wrong_column_count": ("1 1 0 0 0 1 -1\n2 3 0 0 1 1\n", 2, "expected 7 columns"),
    "missing_parent": ("1 1 0 0 0 1 -1\n2 3 0 0 1 1 9\n", 2, "no node has"),
    "cycle": ("1 1 0 0 0 1 -1\n2 3 0 0 1 1 3\n3 3 0 0 2 1 2\n", 2, "cycle"),
    "duplicate_id": ("1 1 0 0 0 1 -1\n2 3 0 0 1 1 1\n2 3 0 0 2 1 1\n", 3, "unique node id"),
    "nan": ("1 1 0 0 0 1 -1\n2 3 0 nan 1 1 1\n", 2, "finite"),
    "negative_radius": ("1 1 0 0 0 1 -1\n2 3 0 0 1 -0.5 1\n", 2, "radius >= 0"),
    "not_a_number": ("1 1 0 0 0 1 -1\n2 3 0 0 one 1 1\n", 2, "expected a number for z"),
    "fractional_id": ("1 1 0 0 0 1 -1\n2.5 3 0 0 1 1 1\n", 2, "whole number for id"),
}


@pytest.mark.parametrize("name", sorted(MALFORMED))
def test_malformed_records_are_one_line_naming_file_and_line(tmp_path, name, capsys):
    text, line, words = MALFORMED[name]
    source = tmp_path / f"{name}.swc"
    source.write_text(text)
    output = tmp_path / "out.glb"
    assert main([str(source), "-o", str(output)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert err.startswith(f"cgamesh: error: {source}:{line}: "), err
    assert words in err
    assert not output.exists()


def test_zero_radius_needs_a_minimum_radius(tmp_path, capsys):
    source = tmp_path / "zero.swc"
    source.write_text("1 1 0 0 0 1 -1\n2 3 0 0 1 0 1\n3 3 0 0 2 1 2\n")
    assert main([str(source), "-o", str(tmp_path / "a.glb")]) == 2
    err = capsys.readouterr().err.strip()
    assert err == (f"cgamesh: error: {source}: node 2 (line 2): expected a radius > 0, got 0 (1 such); "
                   "give a minimum radius (--min-radius R)")
    assert main([str(source), "-o", str(tmp_path / "a.glb"), "--min-radius", "0.25", "-q"]) == 0
    lines = read_swc(source)
    built = mesh_centerlines(lines, TubeOptions(min_radius=0.25))
    assert built.meshes[0].attributes["radius"].min() == pytest.approx(0.25)


def tube_ends(lines, options: TubeOptions):
    """Per chain: its mesh (split) with the first and last node of the chain."""
    built = mesh_centerlines(lines, options)
    chains = split_tree(lines.parents)
    tubes = [m for m in built.meshes if not m.name.endswith(("_junctions", "_soma"))]
    assert len(tubes) == len(chains)
    return built, chains, tubes


def boundary_vertices(mesh):
    """Positions of the vertices on boundary edges of the mesh welded by position."""
    weld = weld_by_position(mesh.positions)
    faces = weld[mesh.faces]
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    unique, counts = np.unique(edges, axis=0, return_counts=True)
    return unique[counts == 1]


def test_junctions_close_the_tree_without_notches():
    """In the welded merged mesh the only boundary edges are the tubes' open ends, and every
    open end at a junction lies on its junction sphere, which covers it."""
    lines = parse_swc(GOOD, "good.swc")
    options = TubeOptions(around=12, subdivide=3)
    merged = mesh_centerlines(lines, options).meshes[0]
    boundary = boundary_vertices(merged)
    chains = split_tree(lines.parents)
    children = np.bincount(lines.parents[lines.parents >= 0], minlength=len(lines.parents))
    # every boundary vertex lies on the circle of a chain's first or last node; a chain leaving
    # the soma starts with its own radius (the soma's sphere covers it)
    ends, end_radii = [], []
    for i in range(len(chains)):
        nodes = chains.chain(i)
        ends += [nodes[0], nodes[-1]]
        end_radii += [lines.radii[nodes[1]] if lines.kinds[nodes[0]] == 1 else lines.radii[nodes[0]],
                      lines.radii[nodes[-1]]]
    ends, end_radii = np.array(ends), np.array(end_radii)
    position = merged.positions[np.unique(boundary)]
    distance = np.linalg.norm(position[:, None, :] - lines.points[ends][None], axis=2)
    on = np.abs(distance - end_radii[None]) <= 1e-9 * (1 + np.abs(lines.points).max())
    assert on.any(axis=1).all()
    # open boundary loops: 2 per chain (each chain's tube is open at both ends), around edges each
    assert len(boundary) == 2 * len(chains) * options.around
    # each junction has a closed sphere of its radius: the chains' ends there lie on it
    split = mesh_centerlines(lines, TubeOptions(around=12, split=True)).meshes
    spheres = {m.name.rsplit("_", 1)[1]: m for m in split if m.name.endswith(("_junctions", "_soma"))}
    assert len(boundary_vertices(spheres["junctions"])) == 0 and len(boundary_vertices(spheres["soma"])) == 0
    bands = options.around // 2
    for node in chains.junctions:
        on_sphere = np.abs(np.linalg.norm(spheres["junctions"].positions - lines.points[node], axis=1)
                           - lines.radii[node]) < 1e-12 * 20
        assert on_sphere.sum() == (options.around + 1) * (bands + 1)
        assert (ends == node).sum() == children[node] + (lines.parents[node] >= 0)
    soma = np.flatnonzero(lines.kinds == 1)
    np.testing.assert_allclose(np.linalg.norm(spheres["soma"].positions - lines.points[soma[0]], axis=1),
                               lines.radii[soma[0]], rtol=1e-12)
    # with caps every tube is closed, so the merged mesh has no boundary edge at all
    capped = mesh_centerlines(lines, TubeOptions(around=12, caps=True)).meshes[0]
    assert len(boundary_vertices(capped)) == 0


@pytest.mark.slow
def test_node_rings_pass_through_the_node_circles_of_a_real_neuron():
    """Every Kth + 1 ring of a chain's tube is its node's circle: centre, radius, plane."""
    path = realdata_files.smallest_neuron()
    lines = read_swc(path)
    options = TubeOptions(around=8, subdivide=2, split=True, min_radius=0.01)
    built, chains, tubes = tube_ends(lines, options)
    assert built.skipped == ()
    radii = np.maximum(lines.radii, 0.01)
    checked = 0
    for i in range(0, len(chains), 7):
        nodes = chains.chain(i)
        p = lines.points[nodes]
        keep = np.concatenate([[True], np.any(p[1:] != p[:-1], axis=1)])
        nodes, p = nodes[keep], p[keep]
        if (lines.kinds[nodes] == 1).any():
            continue
        rings = tubes[i].positions.reshape(-1, options.around + 1, 3)[:: options.subdivide + 1]
        assert len(rings) == len(nodes)
        from cgamesh.pipelines.tubes import node_tangents
        from cgamesh.meshing.node_normals import envelope_normals

        # the path's bisectors, turned at the few nodes whose rings would leave the envelope
        t = envelope_normals(p, radii[nodes], node_tangents(p), np.array([0]), np.array([len(p)]))
        offset = rings - p[:, None, :]
        scale = 1e-9 * np.abs(p).max()
        np.testing.assert_allclose(np.linalg.norm(offset, axis=2), np.broadcast_to(radii[nodes][:, None], offset.shape[:2]),
                                   atol=scale)
        assert np.abs(np.einsum("kjc,kc->kj", offset, t)).max() <= scale
        normals = tubes[i].normals
        np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-12)
        checked += 1
    assert checked > 100


@pytest.mark.slow
def test_a_real_neuron_through_the_command_line_into_every_format(tmp_path, gltf_validate):
    from export_checks import check_usd_file, pxr_or_skip
    from gltf_validator import assert_clean

    pxr_or_skip()
    source = realdata_files.smallest_neuron()
    formats = ["glb", "gltf", "usda", "usdc", "usd", "usdz", "obj", "ply", "stl"]
    outputs = [tmp_path / f"neuron.{ext}" for ext in formats]
    arguments = [str(source), "--subdivide", "1", "--color-by", "radius", "--min-radius", "0.5", "-q"]
    for output in outputs:
        arguments += ["-o", str(output)]
    result = subprocess.run([sys.executable, "-m", "cgamesh_cli.main", *arguments], capture_output=True, text=True,
                            timeout=600)
    assert result.returncode in (0, 3), result.stderr
    for output in outputs:
        assert output.stat().st_size > 0
    for ext in ("glb", "gltf"):
        assert_clean(gltf_validate(tmp_path / f"neuron.{ext}"))
    built = mesh_centerlines(read_swc(source), TubeOptions(subdivide=1, color_by="radius", min_radius=0.5))
    meshes = [(mesh, built.material) for mesh in built.meshes]
    for ext in ("usda", "usdc", "usdz"):
        check_usd_file(tmp_path / f"neuron.{ext}", meshes, up="z", meters_per_unit=1e-6)
    # closure on the real neuron: in the welded merged mesh every boundary edge is on an open end
    # of a tube (its vertices on the circle of its chain's first or last node), at most two rings
    # of `around` (8) edges per tube; ends that coincide exactly (collinear parent and child) weld
    merged = built.meshes[0]
    segment = merged.attributes["segment"]
    tubes = len(np.unique(segment[segment >= 0]))
    edges = boundary_vertices(merged)
    assert 0 < len(edges) <= 2 * tubes * 8
    lines = read_swc(source)
    radii = np.maximum(lines.radii, 0.5)
    chains = split_tree(lines.parents)
    vertices = np.unique(edges)
    ends = np.array([[chains.chain(int(k))[0], chains.chain(int(k))[-1]] for k in segment[vertices]])
    second = np.array([chains.chain(int(k))[1] for k in segment[vertices]])
    end_radii = np.stack([np.where(lines.kinds[ends[:, 0]] == 1, radii[second], radii[ends[:, 0]]),
                          radii[ends[:, 1]]], axis=1)
    distance = np.linalg.norm(merged.positions[vertices][:, None, :] - lines.points[ends], axis=2)
    assert np.abs(distance - end_radii).min(axis=1).max() <= 1e-9 * np.abs(lines.points).max()
    import trimesh

    ply = trimesh.load(tmp_path / "neuron.ply", process=False)
    np.testing.assert_allclose(ply.vertices.min(axis=0), built.meshes[0].positions.min(axis=0), rtol=1e-6)


def test_watertight_neuron_part_is_one_closed_manifold_meshlab_accepts(tmp_path):
    pymeshlab = pytest.importorskip("pymeshlab")
    from cgamesh.api import load

    source = tmp_path / "good.swc"
    source.write_text(GOOD)
    meshes = load(source, watertight=True, around=12)
    assert len(meshes.surfaces) == 1
    path = tmp_path / "good.ply"
    meshes.export(path)
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(path))
    ms.meshing_remove_duplicate_vertices()  # the file repeats vertices along UV seams and cut lines
    topology = ms.get_topological_measures()
    assert topology["boundary_edges"] == 0
    assert topology["non_two_manifold_edges"] == 0
    assert topology["non_two_manifold_vertices"] == 0
    ms.compute_selection_by_self_intersections_per_face()
    assert ms.current_mesh().selected_face_number() == 0
    # the union encloses at least the biggest piece: the soma of radius 2
    volume = ms.get_geometric_measures()["mesh_volume"]
    assert volume > 4.0 / 3.0 * np.pi * 2.0 ** 3 * 0.9


from hypothesis import given, settings, strategies as st  # noqa: E402


@st.composite
def random_trees(draw):
    """A forest of up to 60 nodes: each node's parent is an earlier node or -1; ids shuffled."""
    n = draw(st.integers(1, 60))
    parents = [-1] + [draw(st.integers(-1, i - 1)) if draw(st.booleans()) or i < 2 else i - 1 for i in range(1, n)]
    ids = draw(st.permutations(list(range(1, 3 * n + 1))))[:n]
    order = draw(st.permutations(list(range(n))))
    return np.array(parents), np.array(ids), np.array(order)


@settings(max_examples=60)
@given(random_trees())
def test_any_forest_in_any_record_order_parses_and_splits_into_its_edges(tree):
    parents, ids, order = tree
    n = len(parents)
    rows = [f"{ids[i]} 3 {i} {i % 7} {i % 3} 0.5 {ids[parents[i]] if parents[i] >= 0 else -1}" for i in order]
    lines = parse_swc("\n".join(rows) + "\n", "random.swc")
    # back in the original numbering: node index k of the file is original node order[k]
    original = order
    np.testing.assert_array_equal(np.where(lines.parents >= 0, original[np.maximum(lines.parents, 0)], -1),
                                  parents[original])
    chains = split_tree(lines.parents)
    covered = np.concatenate([chains.chain(i)[1:] for i in range(len(chains))]) if len(chains) else np.zeros(0)
    assert sorted(covered.tolist()) == np.flatnonzero(lines.parents >= 0).tolist()
    children = np.bincount(lines.parents[lines.parents >= 0], minlength=n)
    for i in range(len(chains)):
        nodes = chains.chain(i)
        assert np.all(children[nodes[1:-1]] == 1) and children[nodes[-1]] != 1
