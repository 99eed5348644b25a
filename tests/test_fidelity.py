"""Tube fidelity (benchmarks/fidelity.py) at CI size: motor tubes stay inside the radius envelope.

On a shipped tractography file (dipy's cb_2.npz: streamlines sampled every 2-8 mm, here tubes
of radius 0.25 mm) and a realistic neuron (a seeded random skeleton: branches, uneven steps of
1 to 6 radii, turns up to 75 degrees, radii tapering with noise), against the chord-length
Catmull-Rom centreline through each unbranched chain (radius linear in arc length): at most
0.1% of the vertices bulge beyond 1.25 radii and none beyond 1.6, and no segment folds. Blade
interpolation of the same samples balloons, which shows the statistic can fail. Slow tests
hold navis' five example neurons (the benchmark's is 722817260.swc) to the same targets.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import cKDTree

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
import fidelity  # noqa: E402


def shipped_streamlines(count: int = 24) -> list[fidelity.Chain]:
    spec = importlib.util.find_spec("dipy")
    assert spec is not None, "dipy (test extra) ships the tractography file cb_2.npz"
    path = Path(spec.submodule_search_locations[0]) / "data" / "files" / "cb_2.npz"
    return fidelity.npz_streamlines(path, radius=0.25)[:count]


def realistic_neuron(seed: int = 1, nodes: int = 260) -> list[fidelity.Chain]:
    """Chains of a random skeleton grown like a neurite tree from a soma."""
    rng = np.random.default_rng(seed)
    points, radii, parents = [np.zeros(3)], [4.0], [-1]
    directions = [np.array([1.0, 0.0, 0.0])]
    tips = [0]
    while len(points) < nodes and tips:
        tip = tips.pop(rng.integers(len(tips)))
        for _ in range(2 if rng.random() < 0.18 else 1):
            turn = rng.normal(size=3)
            turn -= np.dot(turn, directions[tip]) * directions[tip]
            angle = np.radians(rng.uniform(0.0, 75.0))
            direction = np.cos(angle) * directions[tip] + np.sin(angle) * turn / np.linalg.norm(turn)
            radius = max(0.4, radii[tip] * rng.uniform(0.8, 1.05))
            points.append(points[tip] + rng.uniform(1.0, 6.0) * radius * direction)
            radii.append(radius)
            parents.append(tip)
            directions.append(direction)
            tips.append(len(points) - 1)
    children = [[] for _ in points]
    for k, p in enumerate(parents):
        if p >= 0:
            children[p].append(k)
    chains = []
    for start in range(1, len(points)):
        if len(children[parents[start]]) == 1 and parents[start] != 0:
            continue
        run = [parents[start], start]
        while len(children[run[-1]]) == 1:
            run.append(children[run[-1]][0])
        chains.append(fidelity.Chain(np.array([points[k] for k in run]), np.array([radii[k] for k in run])))
    return chains


@pytest.mark.parametrize("data", ["streamlines", "neuron"])
def test_motor_tubes_stay_inside_the_radius_envelope(data):
    chains = shipped_streamlines() if data == "streamlines" else realistic_neuron()
    assert sum(len(c.centres) - 1 for c in chains) >= 200
    result = fidelity.measure(chains, lambda c: fidelity.cgamesh_tube(c, "motor"), "catmull_rom")
    assert result.failed_chains == 0
    assert result.bulge_over_125 <= 0.001, result
    assert result.bulge_max <= 1.6, result
    assert result.folded == 0, result


def test_blade_tubes_of_the_same_streamlines_balloon():
    result = fidelity.measure(shipped_streamlines(8), lambda c: fidelity.cgamesh_tube(c, "blade"), "catmull_rom")
    assert result.bulge_over_125 > 0.2 and result.bulge_max > 3.0, result


def test_the_measure_sees_a_tube_too_wide_and_too_narrow():
    """A straight 2-sample chain meshed 1.3 times too wide: every vertex bulges 1.3; 0.5 times:
    every centreline sample's nearest vertex is half a radius away (a neck of 0.5)."""
    chain = fidelity.Chain(np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0]]), np.array([1.0, 1.0]))
    for factor in (1.3, 0.5):
        def build(c, factor=factor):
            tube = fidelity.cgamesh_tube(fidelity.Chain(c.centres, factor * c.radii), "motor")
            return tube
        result = fidelity.measure([chain], build, "natural")
        # the centreline is sampled every 0.2 radii: a vertex between two samples is measured up
        # to sqrt(d^2 + 0.1^2) from the nearer one
        assert factor - 1e-9 <= result.bulge_max <= np.hypot(factor, 0.1) + 1e-9
        assert result.neck_min == pytest.approx(factor, rel=3e-2)  # rings 1.25 radii apart


def navis_neurons() -> list[Path]:
    spec = importlib.util.find_spec("navis")
    assert spec is not None, "navis (test extra) ships the example neurons"
    files = sorted((Path(spec.submodule_search_locations[0]) / "data" / "swc").glob("*.swc"))
    assert len(files) == 5, files
    return files


@pytest.mark.slow
@pytest.mark.parametrize("path", navis_neurons(), ids=lambda p: p.stem)
def test_motor_tubes_of_every_shipped_neuron_stay_inside_the_envelope(path):
    """navis' five example neurons (the benchmark's is 722817260.swc; 1,300 chains and 575,000
    vertices each, 5-25 s apiece on a shared 2-core machine), with the ring normals cgamesh
    gives centreline inputs: at most 0.1% of the vertices beyond 1.25 radii, none beyond 1.6,
    no fold. (With the path's bisectors alone, a node of radius 68 at a 70-degree turn onto a
    span of 70 that thins to 20 reached 1.69 radii by itself, and one neuron 1.71.)"""
    chains = fidelity.swc_chains(path)
    result = fidelity.measure(chains, lambda c: fidelity.cgamesh_tube(c, "motor"), "catmull_rom")
    assert result.vertices > 500_000 and result.failed_chains == 0
    assert result.bulge_over_125 <= 0.001, result
    assert result.bulge_max <= 1.6, result
    assert result.folded == 0, result


def test_node_normals_turn_only_where_a_ring_would_leave_the_envelope(monkeypatch):
    """The benchmark neuron's worst node as a chain of its own (radius 68 at a 70-degree turn onto
    a span of 70 that thins to 20): its ring, perpendicular to the path, reaches 1.69 radii from
    the centreline, and so does the tube through it; the turned normal brings the tube within
    the target of 1.6 (1.34: the choice measures a model of the rings) without folding it. A chain
    whose radius is constant keeps the path's bisectors exactly."""
    centres = np.array([[5574.63, 22199.1, 15837.1], [5596.0, 22236.0, 15720.0], [5618.0, 22302.0, 15720.0],
                        [5618.0, 22324.0, 15720.0]])
    chain = fidelity.Chain(centres, np.array([62.7873, 68.3221, 20.1127, 11.0]))
    line = fidelity.centreline([chain], "catmull_rom")[0]
    bisector = fidelity.path_tangents(centres)
    turned = fidelity.node_normals(chain)
    assert np.degrees(np.arccos(np.clip(np.dot(turned[1], bisector[1]), -1.0, 1.0))) > 1.0
    np.testing.assert_array_equal(turned[[0, 3]], bisector[[0, 3]])  # chain ends keep their chords
    assert node_circle_bulge(chain, line, bisector).max() > 1.6  # the input as the path alone orients it
    result = fidelity.measure([chain], lambda c: fidelity.cgamesh_tube(c, "motor"), "catmull_rom")
    assert result.bulge_max <= 1.6 and result.folded == 0, result
    monkeypatch.setattr(fidelity, "node_normals", lambda c: fidelity.path_tangents(c.centres))
    plain = fidelity.measure([chain], lambda c: fidelity.cgamesh_tube(c, "motor"), "catmull_rom")
    assert plain.bulge_max > 1.6 and plain.bulge_max > result.bulge_max + 0.2, plain
    monkeypatch.undo()
    constant = fidelity.Chain(centres, np.full(4, 68.0))
    np.testing.assert_array_equal(fidelity.node_normals(constant), fidelity.path_tangents(centres))


def node_circle_bulge(chain: fidelity.Chain, line: fidelity.Centreline, normal: np.ndarray,
                      samples: int = 360) -> np.ndarray:
    """(n,) the largest bulge of each node's own circle (centre, radius, the given normal), densely sampled."""
    u = np.cross(normal, np.where(np.abs(normal[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]]))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(normal, u)
    a = np.linspace(0.0, 2.0 * np.pi, samples, endpoint=False)
    points = chain.centres[:, None, :] + chain.radii[:, None, None] * (
        np.cos(a)[None, :, None] * u[:, None, :] + np.sin(a)[None, :, None] * v[:, None, :])
    distance, nearest = cKDTree(line.points).query(points.reshape(-1, 3))
    return (distance / line.radius[nearest]).reshape(len(chain.centres), samples).max(axis=1)
