"""Centreline tubes meshed chunk by chunk as rows of the one circle mesher (cgamesh.meshing.batch_pass).

Two kinds of check on every input below. Against the definition of a tube: every node ring is
the node's circle (centre on the node, the node's radius, a planar ring), every ring between
two nodes has a radius within theirs (the radius spline is monotone on a span), normals are
unit; on a tube that cannot fold over itself (its radius small against its steps, no sharp
turn, consecutive rings clear of each other's planes: on the smallest navis neuron 127 of its
1,289 tubes) every normal is orthogonal to its ring and every triangle wound with its normals;
the skipped chains are named.
Invariance: a chain meshed among many gets the mesh it gets alone (every chain its own chunk)
-- positions, UVs, faces, welds, attributes and the skipped lines bit for bit, normals (and
the direction colours) within 1e-12 (a few units in the last place, from the order in which
BLAS sums the trigonometric fit of the normal field over arrays of different sizes).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from cgamesh.pipelines.centerlines import TubeOptions, mesh_centerlines
from cgamesh.inputs.centerlines import read_centerlines
from realdata_files import fornix, smallest_neuron

NORMAL_TOLERANCE = 1e-12
ROOT = Path(__file__).resolve().parents[1]


def alone(lines, options: TubeOptions):
    """The tubes with every chain in a chunk of its own (a batch of one)."""
    from cgamesh.meshing.batch_pass import chains as batch_chains

    saved = batch_chains.CHUNK_RINGS
    batch_chains.CHUNK_RINGS = 1
    try:
        return mesh_centerlines(lines, options)
    finally:
        batch_chains.CHUNK_RINGS = saved


def assert_true_tubes(lines, options: TubeOptions) -> None:
    """Every tube of a split run (one mesh per chain, the spheres apart) checked against the
    definition of a tube of the nodes it names (module doc)."""
    from dataclasses import replace

    built = mesh_centerlines(lines, replace(options, split=True, color_by="none"))
    columns = options.around + 1
    points = lines.points if options.up != "x" else lines.points[:, [1, 2, 0]]
    for mesh in built.meshes:
        if mesh.name.endswith(("_junctions", "_soma")):
            continue
        rings = mesh.positions.reshape(-1, columns, 3)[:, :-1]
        centre = rings.mean(axis=1)
        radius = np.linalg.norm(rings - centre[:, None], axis=2)
        size = np.abs(rings).max() + radius.max()
        assert np.all(np.ptp(radius, axis=1) <= 1e-9 * size), mesh.name  # on circles
        normal = np.cross(rings[:, 1] - rings[:, 0], rings[:, 2] - rings[:, 0])
        normal /= np.linalg.norm(normal, axis=1, keepdims=True)
        assert np.all(np.abs(np.einsum("kmi,ki->km", rings - centre[:, None], normal)) <= 1e-9 * size)  # planar
        node_radii = mesh.attributes["radius"].reshape(-1, columns)[:, 0]  # the nodes' radii, linear between
        step = options.subdivide + 1
        if len(rings) % step == 1 % step:  # every ring kept: one on every node
            np.testing.assert_allclose(radius[::step, 0], node_radii[::step], rtol=1e-9, atol=1e-12 * size)
            nodes = centre[::step]
            distance = np.linalg.norm(nodes[:, None, :] - points[None, :, :], axis=2).min(axis=1)
            assert np.all(distance <= 1e-9 * size), mesh.name  # node rings centred on nodes
            low = np.minimum(node_radii[::step][:-1], node_radii[::step][1:])
            high = np.maximum(node_radii[::step][:-1], node_radii[::step][1:])
            span = np.arange(len(rings) - 1) // step
            assert np.all(radius[:-1, 0] >= low[span] * (1 - 1e-9)) and np.all(radius[:-1, 0] <= high[span] * (1 + 1e-9))
        unit = mesh.normals.reshape(-1, columns, 3)[:, :-1]
        np.testing.assert_allclose(np.linalg.norm(unit, axis=2), 1.0, atol=1e-12)
        # a tube whose radius is large against its steps or its bend, or whose path turns sharply,
        # can fold over itself (neighbouring normals turn by more than a right angle there, and
        # where the field vanishes its direction is its limit along the circle); a tube clear of
        # all that has every normal orthogonal to its ring and every triangle wound with its normals
        chords = np.diff(centre, axis=0)
        chords = chords[np.linalg.norm(chords, axis=1) > 0.0]
        unit_chords = chords / np.linalg.norm(chords, axis=1, keepdims=True)
        folds = (np.einsum("kmi,kmi->km", unit[1:], unit[:-1]).min(initial=1.0) < 0.0
                 or np.einsum("kmi,kmi->km", unit, np.roll(unit, 1, axis=1)).min(initial=1.0) < 0.0
                 or np.einsum("ki,ki->k", unit_chords[1:], unit_chords[:-1]).min(initial=1.0) < 0.5  # a sharp turn
                 or radius.max() > 0.5 * np.linalg.norm(chords, axis=1).min(initial=np.inf) * (options.subdivide + 1)
                 or not _rings_in_order(rings, centre, normal))
        if not folds:
            around_tangent = np.roll(rings, -1, axis=1) - np.roll(rings, 1, axis=1)
            # orthogonal to the ring to O(h^2): the chord between the two neighbours of a vertex
            cosine = np.einsum("kmi,kmi->km", unit, around_tangent) / np.linalg.norm(around_tangent, axis=2)
            assert np.all(np.abs(cosine) <= 1e-9), mesh.name
            corners = mesh.positions[mesh.faces]
            geometric = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
            assert np.all(np.einsum("ti,ti->t", geometric, mesh.normals[mesh.faces].sum(axis=1)) >= 0.0), mesh.name


def _rings_in_order(rings, centre, normal) -> bool:
    """Whether each ring lies wholly on one side of the plane of the ring before it, and that one
    wholly on one side of its plane: consecutive rings that cross pass the surface through itself."""
    ahead = np.einsum("kmi,ki->km", rings[1:] - centre[:-1, None], normal[:-1])
    behind = np.einsum("kmi,ki->km", rings[:-1] - centre[1:, None], normal[1:])
    one_side = lambda side: (side.min(axis=1) > 0.0) | (side.max(axis=1) < 0.0)  # noqa: E731
    return bool(one_side(ahead).all() and one_side(behind).all())


def assert_same(lines, options: TubeOptions) -> None:
    """The tubes are tubes of their nodes, and a chain meshed among many gets the mesh it gets alone."""
    assert_true_tubes(lines, options)
    one = alone(lines, options)
    many = mesh_centerlines(lines, options)
    assert many.skipped == one.skipped
    assert len(many.meshes) == len(one.meshes)
    for a, b in zip(many.meshes, one.meshes):
        assert a.name == b.name
        np.testing.assert_array_equal(a.faces, b.faces)
        np.testing.assert_array_equal(a.positions, b.positions)
        np.testing.assert_array_equal(a.uvs, b.uvs)
        np.testing.assert_array_equal(a.weld, b.weld)
        np.testing.assert_array_equal(a.uv_lengths, b.uv_lengths)
        assert np.abs(a.normals - b.normals).max() <= NORMAL_TOLERANCE
        assert np.allclose(np.linalg.norm(a.normals, axis=1), 1.0, atol=1e-12)
        assert (a.colors is None) == (b.colors is None)
        if a.colors is not None:
            assert np.abs(a.colors - b.colors).max() <= NORMAL_TOLERANCE
        assert sorted(a.attributes) == sorted(b.attributes)
        for key in a.attributes:
            np.testing.assert_array_equal(a.attributes[key], b.attributes[key])


@pytest.mark.parametrize("color_by", ["none", "radius", "direction", "segment"])
@pytest.mark.parametrize("split", [False, True])
def test_neuron_junctions_and_soma(color_by, split):
    from dataclasses import replace

    lines = read_centerlines(str(smallest_neuron()))
    kinds = lines.kinds.copy()
    kinds[np.flatnonzero(lines.parents < 0)] = 1  # the root a soma: its chains take their outside radii
    lines = replace(lines, kinds=kinds)
    assert_same(lines, TubeOptions(color_by=color_by, split=split))


@pytest.mark.parametrize("split", [False, True])
def test_streamlines(split):
    lines = read_centerlines(str(fornix()))
    offsets = lines.offsets[:41]  # 40 streamlines keep the test short
    from cgamesh.api import tubes

    polylines = [lines.points[a:b] for a, b in zip(offsets[:-1], offsets[1:])]
    assert tubes(polylines, radii=0.5, units="mm", split=split, color_by="direction").surfaces
    sub = _polylines(polylines)
    assert_same(sub, TubeOptions(radius=0.5, split=split, color_by="direction"))


def _polylines(polylines, scalars=None):
    from cgamesh.inputs.centerlines import Centerlines

    points = np.concatenate(polylines)
    offsets = np.concatenate([[0], np.cumsum([len(p) for p in polylines])])
    return Centerlines(points=points, offsets=offsets, source="polylines", units="mm", scalars=scalars or {})


@pytest.mark.parametrize("split", [False, True])
def test_per_point_scalar(split):
    """Colouring by a field of the file: its attribute interpolated along every tube, a duplicate
    point in a chain, and a polyline of one point, as the per-chain path gives them."""
    rng = np.random.default_rng(7)
    polylines = [np.cumsum(rng.normal(size=(k, 3)), axis=0) * 3.0 for k in rng.integers(2, 9, size=30)]
    polylines[4][2] = polylines[4][1]
    polylines[9] = polylines[9][:1]
    lines = _polylines(polylines, {"fa": rng.random(sum(len(p) for p in polylines))})
    assert_same(lines, TubeOptions(radius=0.3, color_by="fa", split=split))
    built = mesh_centerlines(lines, TubeOptions(radius=0.3, color_by="fa", split=split))
    values = np.concatenate([m.attributes["scalar"] for m in built.meshes])
    assert values.min() >= lines.scalars["fa"].min() and values.max() <= lines.scalars["fa"].max()
    assert len(np.unique(values)) > 30  # interpolated between nodes, not one value per tube


def test_degenerate_chain_is_skipped_with_its_line():
    good = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.5, 0.0]])
    single_point = np.array([[5.0, 5.0, 5.0], [5.0, 5.0, 5.0]])  # one distinct point
    lines = _polylines([good, single_point, good + 3.0])
    assert_same(lines, TubeOptions(radius=0.2))
    built = mesh_centerlines(lines, TubeOptions(radius=0.2))
    assert len(built.skipped) == 1 and "streamline 1" in built.skipped[0]
    with pytest.raises(Exception, match="streamline 1"):
        mesh_centerlines(lines, TubeOptions(radius=0.2, strict=True))


AXES = [np.array(v, dtype=float) for v in ([1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1])]


@st.composite
def polyline(draw):
    count = draw(st.integers(2, 7))
    steps = []
    for _ in range(count - 1):
        if draw(st.booleans()):
            steps.append(AXES[draw(st.integers(0, 5))] * draw(st.sampled_from([0.0, 0.3, 1.0, 4.0])))
        else:
            steps.append(np.array(draw(st.lists(st.floats(-3.0, 3.0), min_size=3, max_size=3))))
    start = np.array(draw(st.lists(st.floats(-100.0, 100.0), min_size=3, max_size=3)))
    return start + np.concatenate([[np.zeros(3)], np.cumsum(steps, axis=0)])


@settings(max_examples=40, deadline=None)
@given(st.lists(polyline(), min_size=1, max_size=6), st.sampled_from([0.05, 0.5, 2.0]),
       st.sampled_from(["none", "direction", "radius"]), st.booleans())
# a step of about 1e-6 of the radius: rings the per-chain path leaves out as coincident (at
# radius 0.05, two of five rings kept) or finds nothing to mesh in (at 0.5)
@example([np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 5.96046448e-08]])], 0.05, "none", False)
@example([np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 5.96046448e-08]])], 0.5, "none", False)
@example([np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 5.96046448e-08]])], 0.05, "radius", True)
def test_random_polylines(polylines, radius, color_by, split):
    """Orientations along exact +-axes, duplicate points (zero steps), near-duplicate points,
    2-node chains, turns back."""
    lines = _polylines(polylines)
    try:
        alone(lines, TubeOptions(radius=radius))
    except Exception:  # nothing meshable: meshed together it is refused alike
        with pytest.raises(Exception):
            mesh_centerlines(lines, TubeOptions(radius=radius))
        return
    assert_same(lines, TubeOptions(radius=radius, color_by=color_by, split=split))


@settings(max_examples=25, deadline=None)
@given(st.integers(3, 40), st.integers(0, 2**31 - 1), st.booleans())
def test_random_trees(count, seed, split):
    """Trees with junctions: each node's parent is an earlier node."""
    from cgamesh.inputs.centerlines import Centerlines

    rng = np.random.default_rng(seed)
    parents = np.array([-1] + [int(rng.integers(0, i)) for i in range(1, count)])
    points = np.zeros((count, 3))
    for i in range(1, count):
        points[i] = points[parents[i]] + rng.choice([-1.0, 1.0]) * np.eye(3)[rng.integers(0, 3)] * rng.uniform(0.5, 3.0) \
            + (rng.normal(size=3) if rng.random() < 0.5 else 0.0)
    radii = rng.uniform(0.05, 0.4, size=count)
    lines = Centerlines(points=points, parents=parents, radii=radii, source="tree", units="um")
    assert_same(lines, TubeOptions(split=split, color_by="segment"))


@settings(max_examples=25, deadline=None)
@given(st.integers(3, 40), st.integers(0, 2**31 - 1), st.integers(1, 4), st.booleans())
def test_random_trees_with_a_soma(count, seed, soma_nodes, split):
    """Chains with nodes inside the soma (batched with the per-chain path's radii: each node
    inside takes its nearest outside node's) give the per-chain path's meshes."""
    from cgamesh.inputs.centerlines import Centerlines

    rng = np.random.default_rng(seed)
    parents = np.array([-1] + [int(rng.integers(0, i)) for i in range(1, count)])
    points = np.zeros((count, 3))
    for i in range(1, count):
        points[i] = points[parents[i]] + rng.choice([-1.0, 1.0]) * np.eye(3)[rng.integers(0, 3)] * rng.uniform(0.5, 3.0)
    radii = rng.uniform(0.05, 0.4, size=count)
    kinds = np.zeros(count, dtype=np.int64)
    soma = rng.choice(count, size=min(soma_nodes, count), replace=False)
    kinds[soma] = 1
    radii[soma] = rng.uniform(1.0, 3.0, size=len(soma))  # a soma far fatter than its neurites
    lines = Centerlines(points=points, parents=parents, radii=radii, kinds=kinds, source="tree", units="um")
    assert_same(lines, TubeOptions(split=split, color_by="radius"))


@settings(max_examples=200, deadline=None)
@given(st.lists(st.lists(st.booleans(), min_size=1, max_size=9), min_size=1, max_size=6), st.integers(0, 2**31 - 1))
def test_outside_radii_are_the_per_chain_paths(inside_lists, seed):
    """Each node inside takes the radius of the nearest node of its chain outside, the earlier
    of two as near: pipelines.tubes.tube_spec's argmin, chain by chain."""
    from cgamesh.meshing.batch_pass.chains import _outside_radii

    counts = np.array([len(c) for c in inside_lists])
    inside = np.concatenate([np.array(c) for c in inside_lists])
    first = np.concatenate([[0], np.cumsum(counts)[:-1]])
    chain_of = np.repeat(np.arange(len(counts)), counts)
    radii = np.random.default_rng(seed).uniform(0.1, 5.0, size=len(inside))
    all_inside = np.bincount(chain_of, weights=inside, minlength=len(counts)) == counts
    replace = inside & ~all_inside[chain_of]  # as tube_pieces asks: chains with a node outside
    got = _outside_radii(radii, replace, first[chain_of], (first + counts - 1)[chain_of])
    for k, (a, c) in enumerate(zip(first, counts)):
        r, inner = radii[a:a + c], inside[a:a + c]
        if inner.all():
            np.testing.assert_array_equal(got[a:a + c], r)  # a chain inside the soma alone is left as it is
            continue
        outside = np.flatnonzero(~inner)
        nearest = outside[np.abs(np.arange(c)[:, None] - outside[None, :]).argmin(axis=1)]
        np.testing.assert_array_equal(got[a:a + c], r[nearest])


def test_progress_counts_every_chain_in_chunks():
    from cgamesh.meshing.batch_pass import chains as batch_chains

    lines = read_centerlines(str(smallest_neuron()))
    calls = []
    built = mesh_centerlines(lines, TubeOptions(), progress=lambda label, count=1: calls.append(count))
    assert sum(calls) == built.chains
    assert len(calls) < built.chains  # chunks, not one call per chain
    assert max(calls) > 1 and batch_chains.CHUNK_RINGS > 0


def test_progress_bar_draws_counts():
    import io
    import time

    from cgamesh import progress as progress_module

    class Terminal(io.StringIO):
        def isatty(self):
            return True

    stream = Terminal()
    bar = progress_module.Progress(100, stream=stream)
    bar.start = time.perf_counter() - 2.0  # past the silent first second
    bar.advance("chains 1-40", 40)
    bar.advance("chain 41", 1)
    assert bar.done == 41 and "41/100" in stream.getvalue()


def test_benchmark_runs_at_tiny_size():
    result = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "bench_realdata.py"), "--tiny", "--copies", "1",
                             "--neurons", "1"], capture_output=True, text=True, timeout=900)
    assert result.returncode == 0, result.stderr[-2000:]
    assert "Spline+tube" in result.stdout and "CPU" in result.stdout and "per-surface overhead" in result.stdout
    # the command's floor is measured, on the smallest input of each format the run reads
    assert "the command on a 2-node tree peaks at" in result.stdout
    assert "the command on one 2-point streamline peaks at" in result.stdout


@pytest.mark.parametrize("split", [False, True])
def test_a_turn_back_meshes_without_warnings_or_non_finite_values(split):
    """Found by a random search of the property above: a polyline that turns straight back
    (0 -> 1 -> 0) has a ring that stands still and a node tangent interpolated through zero;
    both used to go through a division by zero (numpy warnings on the command line)."""
    import warnings

    import cgamesh

    points = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.3], [0.0, 0.0, 0.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        meshes = cgamesh.tubes([points], radii=0.05, around=6, subdivide=2, color_by="direction", split=split)
    for name in ("positions", "normals", "uvs", "colors"):
        assert np.isfinite(getattr(meshes, name)).all(), name
    np.testing.assert_allclose(np.linalg.norm(meshes.normals, axis=1), 1.0, atol=1e-12)
