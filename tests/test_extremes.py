"""Numerical stability at the extremes: every case meshes correctly or fails with the documented error.

Correct means: no NaN anywhere; the grid's vertices lie on the circles C(t) that clifford
computes from the same controls (paper eqs. 10-12 written out in tests/conftest.py) within
1e-9 of the surface's size (or, for a tiny surface far from the origin, within the spacing of
float64 numbers at its coordinates); normals unit and, away from singular points of the surface, within
0.1 degree of the normal line that finite differences of the mesh's own positions give.
The documented failure is a DegenerateGeometryError (an InvalidInputError) whose one-line
message names the surface.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from normal_differences import assert_normals_match_differences

from cgamesh.errors import DegenerateGeometryError, InvalidInputError
from cgamesh.material import Material
from cgamesh.meshing.circles import mesh_circle_surface
from cgamesh.pipelines.scene import build_surface
from cgamesh.inputs.scene import CircleControl, Location, SurfaceSpec

ON_SURFACE = 1e-9  # relative to the surface's size
NORMAL_DEGREES = 0.1
HERE = Location("extremes.yaml", 1, "surfaces[0]")
EXAMPLES = settings(max_examples=20, suppress_health_check=[HealthCheck.too_slow], deadline=None)


def spec_of(centres, normals, radii, curve="kb", weights=None, align=True, closed=False,
            tension=0.0, bias=0.0, continuity=0.0) -> SurfaceSpec:
    weights = [1.0] * len(radii) if weights is None else weights
    controls = tuple(
        CircleControl(tuple(map(float, c)), tuple(map(float, n)), float(r), None, float(w), HERE)
        for c, n, r, w in zip(centres, normals, radii, weights)
    )
    return SurfaceSpec("extreme", "circles", curve, tension, bias, continuity, closed, align, controls,
                       8, 16, None, False, Material(), HERE)


def tube(scale: float, offset, count: int, rng: np.random.Generator, spacing: float = 1.5):
    """Controls of a gently bending tube: radii about ``scale``, centres ``spacing`` radii apart."""
    direction = np.array([0.0, 0.0, 1.0])
    centres, normals = [], []
    point = np.asarray(offset, dtype=np.float64)
    for _ in range(count):
        centres.append(point.copy())
        normals.append(direction.copy())
        direction = direction + 0.3 * rng.normal(size=3)
        direction /= np.linalg.norm(direction)
        point = point + spacing * scale * direction
    radii = scale * rng.uniform(0.7, 1.3, size=count)
    return np.array(centres), np.array(normals), radii


def weights_of(spec: SurfaceSpec, t, paper_weights):
    kind = spec.curve
    return paper_weights(kind, len(spec.controls), t, tension=spec.tension, bias=spec.bias,
                         continuity=spec.continuity, closed=spec.closed,
                         weights=[c.weight for c in spec.controls])


def assert_meshes_correctly(spec: SurfaceSpec, oracle, paper_weights, around=8, along=16):
    """Mesh the spec and check it against clifford and finite differences, or accept the documented error."""
    try:
        surface = build_surface(spec)
        mesh = mesh_circle_surface(surface, around, along, closed=spec.closed)
    except DegenerateGeometryError as error:
        message = str(error)
        assert "\n" not in message and "extreme" in message
        return None
    assert np.all(np.isfinite(mesh.positions)) and np.all(np.isfinite(mesh.normals))
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-12)

    size = surface.frame.scale
    t = np.linspace(0.0, surface.segment_count, along)
    rings = np.unique(np.linspace(0, along - 1, 5).astype(int))
    centres, normals, radii = oracle.surface_circles(surface.controls, weights_of(spec, t[rings], paper_weights),
                                                     surface.frame)
    grid = mesh.positions.reshape(along, around + 1, 3)[rings]
    offset = grid - centres[:, None, :]
    height = np.einsum("kmi,ki->km", offset, normals)
    in_plane = np.linalg.norm(offset - height[..., None] * normals[:, None, :], axis=-1)
    distance = np.hypot(height, in_plane - radii[:, None])
    # A float64 coordinate cannot be nearer than its own spacing: a surface of size 1e-4 placed
    # 1e5 from the origin is held to that spacing, not to 1e-9 of its size.
    representable = 4.0 * np.finfo(float).eps * np.abs(grid).max()
    assert distance.max() <= ON_SURFACE * size + representable, (
        f"{distance.max() / size:.2e} of the size off the surface")

    assert_normals_match_differences(surface, around, NORMAL_DEGREES)
    return mesh


@EXAMPLES
@given(log_scale=st.floats(-4.0, 4.0), distance=st.floats(0.0, 1e5), seed=st.integers(0, 2**32 - 1))
def test_any_size_anywhere(log_scale, distance, seed, oracle, paper_weights):
    rng = np.random.default_rng(seed)
    offset = distance * rng.normal(size=3) / math.sqrt(3.0)
    spec = spec_of(*tube(10.0**log_scale, offset, 4, rng))
    assert assert_meshes_correctly(spec, oracle, paper_weights) is not None


@EXAMPLES
@given(gap=st.floats(1e-9, 1e-3), seed=st.integers(0, 2**32 - 1))
@example(gap=1e-9, seed=4176973237)  # found by a random search: a step of 1e-3 moved the rings 4e-12
def test_nearly_identical_consecutive_controls(gap, seed, oracle, paper_weights):
    rng = np.random.default_rng(seed)
    centres, normals, radii = tube(1.0, (0.0, 0.0, 0.0), 3, rng)
    centres[1] = centres[0] + gap * rng.normal(size=3)
    normals[1] = normals[0] + gap * rng.normal(size=3)
    radii[1] = radii[0] * (1.0 + gap)
    assert assert_meshes_correctly(spec_of(centres, normals, radii, curve="linear"), oracle, paper_weights) is not None


@EXAMPLES
@given(tilt=st.floats(1e-6, 0.2), seed=st.integers(0, 2**32 - 1))
def test_consecutive_circles_in_nearly_opposite_planes(tilt, seed, oracle, paper_weights):
    """Normals almost opposite: with align the second circle is turned round and all is well."""
    rng = np.random.default_rng(seed)
    centres = np.array([[0.0, 0.0, 0.0], [0.2, 0.1, 1.0]])
    axis = rng.normal(size=3)
    axis -= axis[2] * np.array([0.0, 0.0, 1.0])
    normals = np.array([[0.0, 0.0, 1.0], -np.array([0.0, 0.0, 1.0]) + tilt * axis / np.linalg.norm(axis)])
    spec = spec_of(centres, normals, [1.0, 0.8], curve="linear")
    assert assert_meshes_correctly(spec, oracle, paper_weights) is not None


def test_opposite_orientations_without_align_fail_with_the_documented_error():
    spec = spec_of([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]], [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]], [1.0, 1.0],
                   curve="linear", align=False)
    with pytest.raises(DegenerateGeometryError) as raised:
        mesh_circle_surface(build_surface(spec), 8, 16)
    message = str(raised.value)
    assert "extreme" in message and "alpha = 0.5" in message and "\n" not in message


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(order=st.integers(2, 10), seed=st.integers(0, 2**32 - 1))
def test_bezier_orders_up_to_ten(order, seed, oracle, paper_weights):
    rng = np.random.default_rng(seed)
    spec = spec_of(*tube(1.0, (0.0, 0.0, 0.0), order + 1, rng, spacing=0.6), curve="bezier")
    assert_meshes_correctly(spec, oracle, paper_weights)


@pytest.mark.parametrize("tension, bias, continuity", [
    (1.0, 0.0, 0.0), (-1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, -1.0, 0.0), (0.0, 0.0, 1.0),
    (0.0, 0.0, -1.0), (1.0, 1.0, 1.0), (-1.0, -1.0, -1.0), (0.5, -1.0, 1.0),
])
def test_kochanek_bartels_parameters_at_their_limits(tension, bias, continuity, oracle, paper_weights):
    rng = np.random.default_rng(7)
    spec = spec_of(*tube(1.0, (3.0, -2.0, 1.0), 4, rng), tension=tension, bias=bias, continuity=continuity)
    assert_meshes_correctly(spec, oracle, paper_weights, along=19)  # rings exactly at the controls


@EXAMPLES
@given(weights=st.lists(st.floats(-3.0, 3.0), min_size=3, max_size=4), seed=st.integers(0, 2**32 - 1))
def test_rational_weights_from_a_thousandth_to_a_thousand(weights, seed, oracle, paper_weights):
    rng = np.random.default_rng(seed)
    centres, normals, radii = tube(1.0, (0.0, 0.0, 0.0), len(weights), rng, spacing=0.8)
    spec = spec_of(centres, normals, radii, curve="rational_bezier", weights=[10.0**w for w in weights])
    assert_meshes_correctly(spec, oracle, paper_weights)


@pytest.mark.parametrize("curve", ["linear", "kb", "catmull_rom"])
def test_rings_exactly_at_segment_ends(curve, oracle, paper_weights):
    rng = np.random.default_rng(11)
    spec = spec_of(*tube(1.0, (0.0, 0.0, 0.0), 5, rng), curve=curve)
    assert assert_meshes_correctly(spec, oracle, paper_weights, along=9) is not None  # t = 0, 0.5, 1, ...


def test_a_hundred_thousand_rings_stay_on_their_circles(oracle, paper_weights):
    """Very fine stepping: 1e5 TRS steps; no drift off the circles read from C(t) by clifford."""
    rng = np.random.default_rng(5)
    spec = spec_of(*tube(1.0, (0.0, 0.0, 0.0), 3, rng))
    surface = build_surface(spec)
    along, around = 100_000, 6
    mesh = mesh_circle_surface(surface, around, along)
    rings = np.array([0, 1, 50_000, along - 2, along - 1])
    t = np.linspace(0.0, surface.segment_count, along)[rings]
    centres, normals, radii = oracle.surface_circles(surface.controls, weights_of(spec, t, paper_weights),
                                                     surface.frame)
    grid = mesh.positions.reshape(along, around + 1, 3)[rings]
    offset = grid - centres[:, None, :]
    height = np.einsum("kmi,ki->km", offset, normals)
    in_plane = np.linalg.norm(offset - height[..., None] * normals[:, None, :], axis=-1)
    assert np.hypot(height, in_plane - radii[:, None]).max() <= 1e-12 * surface.frame.scale


def test_non_finite_controls_are_refused_before_any_geometry():
    spec = spec_of([[0.0, 0.0, 0.0], [0.0, 0.0, float("nan")]], [[0.0, 0.0, 1.0]] * 2, [1.0, 1.0])
    with pytest.raises(InvalidInputError):
        mesh_circle_surface(build_surface(spec), 8, 16)
