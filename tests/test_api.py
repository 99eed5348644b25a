"""The Python API (cgamesh.load, cgamesh.tubes, Meshes), .npz inputs, and the real-data docs page,
whose code blocks run here as written."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import cgamesh
from cgamesh.errors import InvalidInputError
from cgamesh_cli.main import main

ROOT = Path(__file__).resolve().parent.parent
FORMATS = ["glb", "gltf", "usda", "usdc", "usd", "usdz", "obj", "ply", "stl"]


def _tree():
    points = np.array([[0.0, 0, 0], [0, 0, 2], [0, 0, 4], [1.5, 0, 6], [-1.5, 0.5, 6], [2, 1, 8]])
    parents = np.array([-1, 0, 1, 2, 2, 3])
    radii = np.array([0.5, 0.4, 0.4, 0.3, 0.3, 0.2])
    return points, parents, radii


def test_tubes_of_a_tree_and_of_polylines_give_plain_arrays():
    points, parents, radii = _tree()
    tree = cgamesh.tubes(points, radii=radii, parents=parents, around=10, subdivide=2)
    assert isinstance(tree, cgamesh.Meshes)
    v = len(tree.positions)
    assert tree.normals.shape == (v, 3) and tree.uvs.shape == (v, 2) and tree.faces.shape[1] == 3
    assert tree.faces.max() == v - 1 and tree.faces.dtype == np.int32
    np.testing.assert_allclose(np.linalg.norm(tree.normals, axis=1), 1.0, atol=1e-12)
    assert tree.colors is None
    assert set(tree.attributes) == {"radius", "segment"}
    # radii interpolated along tubes stay between the nodes' radii
    assert radii.min() - 1e-12 <= tree.attributes["radius"].min()
    assert tree.attributes["radius"].max() <= radii.max() + 1e-12
    # three chains (0-1-2, 2-3-5, 2-4) and one junction sphere
    assert sorted(np.unique(tree.attributes["segment"]).tolist()) == [0.0, 1.0, 2.0]
    lines = cgamesh.tubes([points[:3], points[3:]], radii=0.2, around=6, split=True)
    assert [mesh.name for mesh, _ in lines.surfaces] == ["tubes_streamline_0", "tubes_streamline_1"]


def test_load_reads_scene_files_too():
    from cgamesh.inputs.scene import load_scene
    from cgamesh.pipelines.scene import Resolution, mesh_scene

    meshes = cgamesh.load(ROOT / "examples" / "kb_tube.yaml", around=8, along=16)
    ((reference, material),) = mesh_scene(load_scene(ROOT / "examples" / "kb_tube.yaml"), Resolution(8, 16))
    np.testing.assert_array_equal(meshes.positions, reference.positions)
    np.testing.assert_array_equal(meshes.faces, reference.faces)
    assert meshes.surfaces[0][1] == material and meshes.up == "z"
    assert meshes.attributes == {}


def test_export_writes_every_format_and_to_trimesh_keeps_the_arrays(tmp_path, gltf_validate):
    from gltf_validator import assert_clean

    points, parents, radii = _tree()
    meshes = cgamesh.tubes(points, radii=radii, parents=parents, color_by="radius", around=8)
    for ext in FORMATS:
        path = tmp_path / f"tree.{ext}"
        written = meshes.export(path)
        assert written >= path.stat().st_size > 0
    assert_clean(gltf_validate(tmp_path / "tree.glb"))
    mesh = meshes.to_trimesh()
    np.testing.assert_array_equal(mesh.vertices, meshes.positions)
    np.testing.assert_array_equal(mesh.faces, meshes.faces)
    np.testing.assert_array_equal(mesh.visual.vertex_colors[:, :3], np.round(meshes.colors * 255))


def test_unknown_options_and_bad_arrays_are_one_line_errors():
    points, parents, radii = _tree()
    with pytest.raises(InvalidInputError, match="unknown option 'colour_by'"):
        cgamesh.tubes(points, radii=radii, parents=parents, colour_by="radius")
    with pytest.raises(InvalidInputError, match=r"points\[1\]: expected finite"):
        cgamesh.tubes([np.array([[0, 0, 0], [np.nan, 0, 0], [1, 1, 1.0]])], radii=1.0)
    with pytest.raises(InvalidInputError, match=r"parents\[0\]: expected a tree"):
        cgamesh.tubes(points, radii=radii, parents=np.array([5, 0, 1, 2, 2, 3]))
    with pytest.raises(InvalidInputError, match="expected a radius > 0"):
        cgamesh.tubes(points, radii=np.zeros(6), parents=parents)
    with pytest.raises(InvalidInputError, match="color-by must be one of"):
        cgamesh.tubes(points, radii=radii, parents=parents, color_by="fa")
    a, b = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0.0]]), np.array([[0, 1, 0], [1, 1, 0.0]])
    with pytest.raises(InvalidInputError, match="radii as numbers, one per point or 2 arrays"):
        cgamesh.tubes([a, b], radii=[np.ones(3), np.ones(2), np.ones(1)])  # ragged, one array too many
    with pytest.raises(InvalidInputError, match=r"radii: expected shape \(5,\), got \(8,\)"):
        cgamesh.tubes([a, b], radii=[np.ones(3), np.ones(5)])
    with pytest.raises(InvalidInputError, match="scalars|depth as numbers"):
        cgamesh.tubes([a, b], radii=1.0, scalars={"depth": ["x", "y"]})


def test_npz_files_through_the_command_line(tmp_path, capsys):
    points, parents, radii = _tree()
    tree = tmp_path / "tree.npz"
    np.savez(tree, points=points, parents=parents, radii=radii, depth=points[:, 2])
    lines = tmp_path / "lines.npz"
    np.savez(lines, points=points, offsets=np.array([0, 3]))
    assert main([str(tree), "-o", str(tmp_path / "tree.glb"), "--color-by", "depth", "--units", "um"]) == 0
    assert main([str(lines), "-o", str(tmp_path / "lines.obj"), "--radius", "0.1", "--split"]) == 0
    out = capsys.readouterr().out
    assert f"{tmp_path / 'tree.glb'}: 3 segments, 1 mesh, " in out
    assert f"{tmp_path / 'lines.obj'}: 2 streamlines, 2 meshes, " in out
    bad = tmp_path / "bad.npz"
    np.savez(bad, points=points, offsets=np.array([0, 3]), radii=-radii)
    assert main([str(bad), "-o", str(tmp_path / "bad.glb")]) == 2
    assert capsys.readouterr().err.strip() == (f"cgamesh: error: {bad}: radii[0]: expected a finite radius >= 0, "
                                               f"got {-radii[0]}")


def test_scene_files_refuse_the_real_data_options(tmp_path, capsys):
    assert main([str(ROOT / "examples" / "kb_tube.yaml"), "-o", str(tmp_path / "a.glb"), "--radius", "1"]) == 2
    assert "--radius applies to centreline inputs" in capsys.readouterr().err


def test_importing_cgamesh_and_reading_swc_stays_light(tmp_path):
    source = tmp_path / "n.swc"
    source.write_text("1 1 0 0 0 1 -1\n2 3 0 0 3 0.5 1\n3 3 0 1 6 0.5 2\n4 3 1 0 6 0.5 2\n")
    probe = ("import sys, cgamesh; before = set(sys.modules); from cgamesh_cli.main import main; "
             f"status = main([{str(source)!r}, '-o', {str(tmp_path / 'n.glb')!r}, '-q']); "
             "heavy = sorted(m for m in sys.modules if m.split('.')[0] in "
             "('clifford', 'numba', 'nibabel', 'trx', 'manifold3d', 'pxr', 'trimesh', 'dipy', 'navis', 'scipy')); "
             "print(status, heavy, sorted(m for m in before if m.startswith('cgamesh.')))")
    result = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120, check=True)
    assert result.stdout.strip() == "0 [] []", result.stdout + result.stderr


@pytest.mark.slow
def test_the_real_data_docs_page_runs_as_written(tmp_path, monkeypatch):
    page = (ROOT / "docs" / "real-data.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", page, flags=re.S)
    assert len(blocks) >= 3
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    for block in blocks:
        exec(compile(block, "docs/real-data.md", "exec"), namespace)
    for name in ("neuron.glb", "fornix.usdz", "helices.ply"):
        assert (tmp_path / name).stat().st_size > 0
    assert namespace["fornix"].meters_per_unit == 1e-3
    assert namespace["neuron"].units == "nm"


from hypothesis import given, settings, strategies as st  # noqa: E402

AXES = [np.array(v, dtype=float) for v in ([1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1])]


@st.composite
def polylines(draw):
    """Polylines of 2-8 points whose steps are exact +-axes or general directions, sizes 1e-3 to 1e3."""
    scale = 10.0 ** draw(st.integers(-3, 3))
    steps = []
    for _ in range(draw(st.integers(1, 7))):
        if draw(st.booleans()):
            steps.append(AXES[draw(st.integers(0, 5))])
        else:
            v = np.array([draw(st.floats(-1, 1)) for _ in range(3)])
            steps.append(v if np.linalg.norm(v) > 0.2 else AXES[0])
    points = np.cumsum(np.vstack([np.zeros(3), steps]), axis=0) * scale
    radius = scale * draw(st.sampled_from([0.01, 0.1, 0.3]))
    return points, radius


@settings(max_examples=40)
@given(polylines())
def test_node_rings_lie_on_the_node_circles_for_any_polyline(case):
    """Whatever carries the rings between nodes, every node's ring is its circle; a polyline
    that cannot be meshed is reported, never silently dropped."""
    from cgamesh.pipelines.tubes import node_tangents

    points, radius = case
    meshes = cgamesh.tubes([points], radii=radius, around=6, subdivide=2, split=True)
    assert len(meshes.surfaces) + len(meshes.skipped) == 1
    if meshes.skipped:
        assert meshes.skipped[0].startswith("tubes: streamline 0: ")
        return
    rings = meshes.positions.reshape(-1, 7, 3)[::3]
    assert len(rings) == len(points)
    offset = rings - points[:, None, :]
    size = np.abs(points).max() + radius
    np.testing.assert_allclose(np.linalg.norm(offset, axis=2), radius, atol=1e-9 * size)
    assert np.abs(np.einsum("kjc,kc->kj", offset, node_tangents(points))).max() <= 1e-9 * size
    assert np.isfinite(meshes.normals).all()
    np.testing.assert_allclose(np.linalg.norm(meshes.normals, axis=1), 1.0, atol=1e-12)
