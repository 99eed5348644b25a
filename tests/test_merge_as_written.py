"""A merged mesh held as the glTF writer stores it (float32 normals, colours, attributes) writes
the same bytes as the float64 merged mesh, and holds less (cgamesh.meshing.merge)."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cgamesh.pipelines.centerlines import TubeOptions, mesh_centerlines
from cgamesh.export.gltf import write_glb, write_gltf
from cgamesh.export.options import WriteOptions
from cgamesh.inputs.centerlines import Centerlines, read_centerlines
from cgamesh.meshing.junctions import uv_spheres
from cgamesh.meshing.merge import MergedMesh
from cgamesh.meshing.mesh import SurfaceMesh
from realdata_files import fornix, smallest_neuron


def _digest(path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _write(path, meshes, writer=write_glb) -> str:
    path.parent.mkdir(exist_ok=True)
    writer(path, [(m, _material()) for m in meshes], WriteOptions("z", 1e-3, "mm"))
    return _digest(path) if path.suffix == ".glb" else _digest(path) + _digest(path.with_suffix(".bin"))


def _material():
    from cgamesh.material import Material

    return Material()


def _merged(pieces, as_written, exact=()):
    merged = MergedMesh(sum(p.vertex_count for p in pieces), sum(p.triangle_count for p in pieces),
                        as_written=as_written, exact_attributes=exact)
    for piece in pieces:
        merged.append(piece)
    return merged.finish("merged")


# a normal's direction: random, or an exact +-axis (a component of exactly 0 and one of exactly 1)
directions = st.one_of(
    st.tuples(*[st.floats(-1.0, 1.0, allow_nan=False)] * 3).filter(lambda v: np.linalg.norm(v) > 1e-3),
    st.sampled_from([(1.0, 0.0, 0.0), (0.0, -1.0, 0.0), (0.0, 0.0, 1.0), (-1.0, 0.0, 0.0)]))


@settings(max_examples=40)
@given(st.lists(directions, min_size=3, max_size=30),
       st.floats(-4e-16, 4e-16),  # a mesher's normal is unit within a few float64 ulps
       st.lists(st.floats(-1e-12, 1.0 + 1e-12, allow_nan=False), min_size=3, max_size=3),
       st.floats(-1e30, 1e30, allow_nan=False), st.integers(1, 4))
def test_held_as_written_writes_the_same_bytes(tmp_path_factory, normals, off_unit, colour, value, pieces):
    folder = tmp_path_factory.mktemp("as_written")
    n = np.asarray(normals, dtype=np.float64)
    n = n / np.linalg.norm(n, axis=1, keepdims=True) * (1.0 + off_unit)
    count = len(n)
    rng = np.random.default_rng(count)
    meshes = []
    for k in range(pieces):  # pieces of different sizes: a normal's rounding must not depend on its piece
        v = count + k
        normals_k = np.resize(n, (v, 3))
        meshes.append(SurfaceMesh(
            name=f"p{k}", positions=rng.normal(size=(v, 3)) * 10.0 ** k, normals=normals_k,
            uvs=rng.random((v, 2)), faces=(np.arange(3 * (v - 2)) % v).reshape(-1, 3).astype(np.int32),
            colors=np.clip(np.resize(np.asarray(colour), (v, 3)) + rng.normal(size=(v, 3)) * 0.1, -1e-12,
                           1.0 + 1e-12),
            attributes={"radius": rng.random(v) * value, "segment": np.full(v, float(k))}))
    exact = _merged(meshes, as_written=False)
    held = _merged(meshes, as_written=True)
    assert held.normals.dtype == held.colors.dtype == np.float32
    assert all(a.dtype == np.float32 for a in held.attributes.values())
    assert exact.normals.dtype == np.float64
    np.testing.assert_array_equal(held.positions, exact.positions)
    np.testing.assert_array_equal(held.uvs, exact.uvs)
    # the writer's normal, rounded once from the float64 one over its length
    np.testing.assert_array_equal(held.normals, (exact.normals / np.linalg.norm(exact.normals, axis=1,
                                                                                keepdims=True)).astype(np.float32))
    for name, writer in (("mesh.glb", write_glb), ("mesh.gltf", write_gltf)):  # .gltf names its .bin
        assert _write(folder / "held" / name, [held], writer) == _write(folder / "exact" / name, [exact], writer)


def _fornix_part(streamlines: int) -> Centerlines:
    lines = read_centerlines(str(fornix()))
    return Centerlines(points=lines.points[: lines.offsets[streamlines]], offsets=lines.offsets[: streamlines + 1],
                       source="fornix.trk", units="mm", scalars={})


@pytest.mark.parametrize("color_by", ["none", "direction", "radius", "segment"])
def test_real_inputs_held_as_written_write_the_same_bytes(tmp_path, color_by):
    from dataclasses import replace

    inputs = (("fornix", _fornix_part(40), 0.5), ("neuron", read_centerlines(str(smallest_neuron())), None))
    for name, lines, radius in inputs:
        if name == "neuron":  # the root a soma: its chains go the per-chain way, and soma spheres join
            kinds = lines.kinds.copy()
            kinds[np.flatnonzero(lines.parents < 0)] = 1
            lines = replace(lines, kinds=kinds)
        options = TubeOptions(radius=radius, color_by=color_by, around=7, subdivide=2)
        held = mesh_centerlines(lines, options, as_written=True).meshes[0]
        exact = mesh_centerlines(lines, options).meshes[0]
        assert held.normals.dtype == np.float32 and exact.normals.dtype == np.float64
        # attributes colours are made from stay exact; the others are held as float32
        kept = () if color_by in ("none", "direction") else ("radius", "segment")
        for key, values in held.attributes.items():
            assert values.dtype == (np.float64 if key in kept else np.float32), (key, values.dtype)
        assert (held.colors is None) == (color_by == "none")
        assert _write(tmp_path / f"{name}_held.glb", [held]) == _write(tmp_path / f"{name}_exact.glb", [exact]), name


def test_held_as_written_holds_less():
    lines = _fornix_part(40)
    held = mesh_centerlines(lines, TubeOptions(radius=0.5), as_written=True).meshes[0]
    exact = mesh_centerlines(lines, TubeOptions(radius=0.5)).meshes[0]

    def nbytes(mesh):
        arrays = [mesh.positions, mesh.normals, mesh.uvs, mesh.faces, *mesh.attributes.values()]
        return sum(a.nbytes for a in arrays)

    # normals 24 -> 12 bytes a vertex, radius and segment 8 -> 4 each
    assert nbytes(exact) - nbytes(held) == 20 * held.vertex_count
    spheres = uv_spheres(np.zeros((2, 3)), np.ones(2), 6)
    assert _merged([spheres], as_written=True).normals.dtype == np.float32
