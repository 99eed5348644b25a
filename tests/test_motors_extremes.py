"""Motor interpolation at the extremes (the cases of tests/test_extremes.py for blades): Bezier
orders up to ten, Kochanek-Bartels parameters at their limits, rational weights from a
thousandth to a thousand, nearly identical and nearly opposite consecutive controls, and a
hundred thousand TRS steps.

Correct means what it means there: no NaN; the grid's vertices on the motion's circles
(c(t), n(t), r(t)) evaluated directly at each ring's t, within 1e-9 of the surface's size (or
the spacing of float64 numbers at the coordinates); unit normals orthogonal to the circle's
tangent; away from singular points, normals within 0.1 degree of finite differences of the
mesh's own positions. Or the documented one-line error.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from normal_differences import assert_normals_match_differences
from test_motors import bent_tube, circle_distance, motor_spec

from cgamesh.errors import InvalidInputError
from cgamesh.meshing.circles import mesh_circle_surface
from cgamesh.pipelines.scene import build_surface

ON_SURFACE = 1e-9  # relative to the surface's size
EXAMPLES = settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def assert_meshes_correctly(spec, around=8, along=16):
    """Mesh a motor spec and check it as the module docstring says; the refusal is one line."""
    surface = build_surface(spec)
    try:
        surface.check_projection_exists()
    except InvalidInputError as error:
        assert "\n" not in str(error) and "motor" in str(error)
        return None
    mesh = mesh_circle_surface(surface, around, along, closed=spec.closed)
    assert np.all(np.isfinite(mesh.positions)) and np.all(np.isfinite(mesh.normals))
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-12)
    t = np.linspace(0.0, surface.segment_count, along)
    state = surface.circles(t)
    grid = mesh.positions[: along * (around + 1)].reshape(along, around + 1, 3)
    representable = 4.0 * np.finfo(float).eps * np.abs(grid).max()
    off = circle_distance(grid, state.centre, state.normal, state.radius).max()
    assert off <= ON_SURFACE * surface.frame.scale + representable, f"{off / surface.frame.scale:.2e} off"
    normals = mesh.normals[: along * (around + 1)].reshape(along, around + 1, 3)
    tangent = np.cross(state.normal[:, None, :], grid - state.centre[:, None, :])
    tangent /= np.linalg.norm(tangent, axis=-1, keepdims=True)
    assert np.abs(np.einsum("kmi,kmi->km", tangent, normals)).max() <= 1e-9
    assert_normals_match_differences(surface, around)
    return mesh


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(order=st.integers(2, 10), seed=st.integers(0, 2**32 - 1))
def test_bezier_orders_up_to_ten(order, seed):
    centres, normals, radii = bent_tube(np.random.default_rng(seed), order + 1, spacing=2.0, turn=0.3)
    assert assert_meshes_correctly(motor_spec(centres, normals, radii, curve="bezier")) is not None


@pytest.mark.parametrize("tension, bias, continuity", [
    (1.0, 0.0, 0.0), (-1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, -1.0, 0.0), (0.0, 0.0, 1.0),
    (0.0, 0.0, -1.0), (1.0, 1.0, 1.0), (-1.0, -1.0, -1.0), (0.5, -1.0, 1.0),
])
@pytest.mark.parametrize("closed", [False, True])
def test_kochanek_bartels_parameters_at_their_limits(tension, bias, continuity, closed):
    centres, normals, radii = bent_tube(np.random.default_rng(7), 5, spacing=3.0, turn=0.4)
    spec = motor_spec(centres + np.array([3.0, -2.0, 1.0]), normals, radii, curve="kb", closed=closed,
                      tension=tension, bias=bias, continuity=continuity)
    # 17 rings put one exactly on every control of the four or five segments
    assert assert_meshes_correctly(spec, along=21 if closed else 17) is not None


@EXAMPLES
@given(weights=st.lists(st.floats(-3.0, 3.0), min_size=3, max_size=5), seed=st.integers(0, 2**32 - 1))
def test_rational_weights_from_a_thousandth_to_a_thousand(weights, seed):
    centres, normals, radii = bent_tube(np.random.default_rng(seed), len(weights), spacing=2.0, turn=0.3)
    spec = motor_spec(centres, normals, radii, curve="rational_bezier", weights=[10.0**w for w in weights])
    assert assert_meshes_correctly(spec) is not None


@EXAMPLES
@given(gap=st.floats(1e-9, 1e-3), curve=st.sampled_from(["linear", "bezier", "kb", "catmull_rom"]),
       seed=st.integers(0, 2**32 - 1))
def test_nearly_identical_consecutive_controls(gap, curve, seed):
    rng = np.random.default_rng(seed)
    centres, normals, radii = bent_tube(rng, 4, spacing=3.0, turn=0.3)
    centres[2] = centres[1] + gap * rng.normal(size=3)
    tilted = normals[1] + gap * rng.normal(size=3)
    normals[2], radii[2] = tilted / np.linalg.norm(tilted), radii[1] * (1.0 + gap)
    assert_meshes_correctly(motor_spec(centres, normals, radii, curve=curve))


@EXAMPLES
@given(tilt=st.floats(1e-6, 0.2), curve=st.sampled_from(["linear", "kb", "catmull_rom"]),
       seed=st.integers(0, 2**32 - 1))
def test_consecutive_circles_in_nearly_opposite_planes(tilt, curve, seed):
    """With align (the default) a neighbour facing nearly the other way is flipped to face along."""
    rng = np.random.default_rng(seed)
    centres, normals, radii = bent_tube(rng, 4, spacing=3.0, turn=0.3)
    opposite = -normals[1] + tilt * rng.normal(size=3)
    normals[2] = opposite / np.linalg.norm(opposite)
    assert assert_meshes_correctly(motor_spec(centres, normals, radii, curve=curve)) is not None


@pytest.mark.parametrize("curve", ["linear", "kb"])
def test_a_hundred_thousand_rings_stay_on_their_circles(curve):
    """1e5 TRS steps: no drift off the motion's circles evaluated directly."""
    centres, normals, radii = bent_tube(np.random.default_rng(5), 3, spacing=3.0)
    surface = build_surface(motor_spec(centres, normals, radii, curve=curve))
    along, around = 100_000, 6
    mesh = mesh_circle_surface(surface, around, along)
    rings = np.array([0, 1, 50_000, along - 2, along - 1])
    state = surface.circles(np.linspace(0.0, surface.segment_count, along)[rings])
    grid = mesh.positions.reshape(along, around + 1, 3)[rings]
    assert circle_distance(grid, state.centre, state.normal, state.radius).max() <= 1e-12 * surface.frame.scale
