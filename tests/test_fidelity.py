"""Tube fidelity (benchmarks/fidelity.py) at CI size: motor tubes stay inside the radius envelope.

On a shipped tractography file (dipy's cb_2.npz: streamlines sampled every 2-8 mm, here tubes
of radius 0.25 mm) and a realistic neuron (a seeded random skeleton: branches, uneven steps of
1 to 6 radii, turns up to 75 degrees, radii tapering with noise), against the chord-length
Catmull-Rom centreline through each unbranched chain (radius linear in arc length): at most
0.1% of the vertices bulge beyond 1.25 radii and none beyond 1.6, and no segment folds. Blade
interpolation of the same samples balloons, which shows the statistic can fail.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

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
