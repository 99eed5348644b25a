"""cgamesh verify on every valid extreme scene that tests/test_extremes.py covers.

Each case is meshed and checked by the mesher's own measures (test_extremes'
``assert_meshes_correctly``: vertices on clifford's circles, normals against finite
differences); where it meshes, the scene is written as a file, exported to GLB by the
command line and verified against the tracer at the default thresholds. The tracer then
has to agree: radii from 1e-4 to 1e4, centres up to 1e5 from the origin, nearly identical
consecutive controls, nearly opposite planes, Bezier orders up to 10, Kochanek-Bartels
parameters at +-1, rational weights from 1e-3 to 1e3, rings exactly at segment ends.
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cgamesh_cli.main import main
from test_extremes import assert_meshes_correctly, spec_of, tube

EXAMPLES = settings(max_examples=12, suppress_health_check=[HealthCheck.too_slow], deadline=None)


def scene_text(centres, normals, radii, curve="kb", weights=None, around=8, along=16, **kb) -> str:
    """The scene file of one circle surface (every number written exactly, by repr)."""

    def vector(values) -> str:
        return "[" + ", ".join(repr(float(x)) for x in values) + "]"

    lines = ["cgamesh: 1", "surfaces:", "  - name: extreme", "    type: circles", f"    curve: {curve}"]
    lines += [f"    {key}: {float(value)!r}" for key, value in kb.items()]
    lines += [f"    resolution: {{around: {around}, along: {along}}}", "    controls:"]
    for k, (c, n, r) in enumerate(zip(centres, normals, radii)):
        weight = "" if weights is None else f", weight: {float(weights[k])!r}"
        lines.append(f"      - {{center: {vector(c)}, normal: {vector(n)}, radius: {float(r)!r}{weight}}}")
    return "\n".join(lines) + "\n"


def assert_verify_agrees(oracle, paper_weights, centres, normals, radii, curve="kb", weights=None,
                         around=8, along=16, **kb) -> bool:
    """The mesher's checks, then ``cgamesh verify`` at its default thresholds; False when the
    case is the documented degenerate error (nothing to verify)."""
    spec = spec_of(centres, normals, radii, curve=curve, weights=weights, **kb)
    if assert_meshes_correctly(spec, oracle, paper_weights, around=around, along=along) is None:
        return False
    with tempfile.TemporaryDirectory() as folder:
        scene = Path(folder) / "extreme.yaml"
        glb = Path(folder) / "extreme.glb"
        scene.write_text(scene_text(centres, normals, radii, curve, weights, around, along, **kb))
        assert main([str(scene), "-o", str(glb), "-q"]) == 0
        assert main(["verify", str(scene), str(glb), "-q"]) == 0, scene.read_text()
    return True


@EXAMPLES
@given(log_scale=st.floats(-4.0, 4.0), distance=st.floats(0.0, 1e5), seed=st.integers(0, 2**32 - 1))
def test_any_size_anywhere(log_scale, distance, seed, oracle, paper_weights):
    rng = np.random.default_rng(seed)
    offset = distance * rng.normal(size=3) / math.sqrt(3.0)
    assert assert_verify_agrees(oracle, paper_weights, *tube(10.0**log_scale, offset, 4, rng))


@pytest.mark.parametrize("log_scale, distance", [(-4.0, 1e5), (4.0, 1e5), (-4.0, 0.0), (4.0, 0.0), (0.0, 1e5)])
def test_the_corners_of_size_and_distance(log_scale, distance, oracle, paper_weights):
    rng = np.random.default_rng(17)
    offset = distance * np.array([1.0, -1.0, 1.0]) / math.sqrt(3.0)
    assert assert_verify_agrees(oracle, paper_weights, *tube(10.0**log_scale, offset, 4, rng),
                                around=64, along=128)


@EXAMPLES
@given(gap=st.floats(1e-9, 1e-3), seed=st.integers(0, 2**32 - 1))
def test_nearly_identical_consecutive_controls(gap, seed, oracle, paper_weights):
    rng = np.random.default_rng(seed)
    centres, normals, radii = tube(1.0, (0.0, 0.0, 0.0), 3, rng)
    centres[1] = centres[0] + gap * rng.normal(size=3)
    normals[1] = normals[0] + gap * rng.normal(size=3)
    radii[1] = radii[0] * (1.0 + gap)
    assert assert_verify_agrees(oracle, paper_weights, centres, normals, radii, curve="linear")


@EXAMPLES
@given(tilt=st.floats(1e-6, 0.2), seed=st.integers(0, 2**32 - 1))
def test_consecutive_circles_in_nearly_opposite_planes(tilt, seed, oracle, paper_weights):
    rng = np.random.default_rng(seed)
    axis = rng.normal(size=3)
    axis -= axis[2] * np.array([0.0, 0.0, 1.0])
    normals = np.array([[0.0, 0.0, 1.0], -np.array([0.0, 0.0, 1.0]) + tilt * axis / np.linalg.norm(axis)])
    assert assert_verify_agrees(oracle, paper_weights, [[0.0, 0.0, 0.0], [0.2, 0.1, 1.0]], normals, [1.0, 0.8],
                                curve="linear")


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(order=st.integers(2, 10), seed=st.integers(0, 2**32 - 1))
def test_bezier_orders_up_to_ten(order, seed, oracle, paper_weights):
    rng = np.random.default_rng(seed)
    assert_verify_agrees(oracle, paper_weights, *tube(1.0, (0.0, 0.0, 0.0), order + 1, rng, spacing=0.6),
                         curve="bezier")


@pytest.mark.parametrize("tension, bias, continuity", [
    (1.0, 0.0, 0.0), (-1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, -1.0, 0.0), (0.0, 0.0, 1.0),
    (0.0, 0.0, -1.0), (1.0, 1.0, 1.0), (-1.0, -1.0, -1.0), (0.5, -1.0, 1.0),
])
def test_kochanek_bartels_parameters_at_their_limits(tension, bias, continuity, oracle, paper_weights):
    rng = np.random.default_rng(7)
    assert assert_verify_agrees(oracle, paper_weights, *tube(1.0, (3.0, -2.0, 1.0), 4, rng), along=19,
                                tension=tension, bias=bias, continuity=continuity)


@EXAMPLES
@given(weights=st.lists(st.floats(-3.0, 3.0), min_size=3, max_size=4), seed=st.integers(0, 2**32 - 1))
def test_rational_weights_from_a_thousandth_to_a_thousand(weights, seed, oracle, paper_weights):
    rng = np.random.default_rng(seed)
    centres, normals, radii = tube(1.0, (0.0, 0.0, 0.0), len(weights), rng, spacing=0.8)
    assert_verify_agrees(oracle, paper_weights, centres, normals, radii, curve="rational_bezier",
                         weights=[10.0**w for w in weights])


@pytest.mark.parametrize("weights", [[1e-3, 1e3, 1e-3], [1e3, 1e-3, 1e3, 1e-3], [1e3, 1.0, 1e-3]])
def test_rational_weights_at_their_bounds(weights, oracle, paper_weights):
    rng = np.random.default_rng(23)
    centres, normals, radii = tube(1.0, (0.0, 0.0, 0.0), len(weights), rng, spacing=0.8)
    assert assert_verify_agrees(oracle, paper_weights, centres, normals, radii, curve="rational_bezier",
                                weights=weights)


@pytest.mark.parametrize("curve", ["linear", "kb", "catmull_rom"])
def test_rings_exactly_at_segment_ends(curve, oracle, paper_weights):
    rng = np.random.default_rng(11)
    assert assert_verify_agrees(oracle, paper_weights, *tube(1.0, (0.0, 0.0, 0.0), 5, rng), curve=curve, along=9)
