"""cgamesh.geometry.projection: interpolants projected to blades exactly as the paper's eqs. 10-12 in clifford."""

from __future__ import annotations

import numpy as np
import pytest

from cgamesh.geometry import objects
from cgamesh.geometry.curves.bezier import Bezier, RationalBezier
from cgamesh.geometry.curves.kochanek_bartels import KochanekBartels, catmull_rom
from cgamesh.geometry.curves.linear import Linear
from cgamesh.errors import DegenerateGeometryError
from cgamesh.geometry.frame import LocalFrame
from cgamesh.pipelines.scene import build_surface
from cgamesh.geometry.projection import margin, project, project_scalar, project_without_derivatives
from cgamesh.inputs.scene import parse_scene
from cgamesh.geometry.surface import EvolvedSurface

H = 1e-6  # central-difference step in t

# A bent tube's worth of circles: centre, normal, radius.
CIRCLES = [
    ((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 0.5),
    ((0.3, 0.2, 0.9), (0.3, 0.1, 1.0), 0.35),
    ((0.9, 0.0, 1.6), (1.0, 0.0, 0.7), 0.45),
    ((1.8, -0.3, 1.9), (1.0, -0.2, 0.1), 0.3),
    ((2.6, -0.1, 1.6), (1.0, 0.1, -0.5), 0.4),
]
# Point pairs across a twisting ribbon: a, b.
PAIRS = [
    ((0.0, -0.5, 0.0), (0.0, 0.5, 0.0)),
    ((0.4, -0.4, 0.6), (0.1, 0.5, 0.7)),
    ((1.0, -0.2, 1.0), (0.5, 0.4, 1.3)),
    ((1.6, 0.1, 1.1), (1.2, 0.2, 1.8)),
    ((2.0, 0.5, 0.9), (2.3, -0.3, 1.4)),
]
CURVES = {
    "linear": Linear(3),
    "bezier3": Bezier(4),
    "rational": RationalBezier((1.0, 2.5, 0.4, 1.5)),
    "kb": KochanekBartels(5, 0.25, -0.3, 0.4),
    "catmull_rom_closed": catmull_rom(4, closed=True),
}
IDS = list(CURVES)


def _controls(grade, count):
    if grade == 3:
        blades = np.stack([objects.circle_from_center_normal_radius(*c) for c in CIRCLES[:count]])
    else:
        blades = np.stack([objects.point_pair(a, b) for a, b in PAIRS[:count]])
    return objects.align_orientations(blades, grade)


def _surface(name, grade=3):
    curve = CURVES[name]
    frame = LocalFrame(origin=np.zeros(3), scale=1.0)
    return EvolvedSurface(name, grade, _controls(grade, curve.control_count), curve, frame)


def _samples(surface, rng, count=40):
    """Parameters away from segment joints (linear and KB are only C0 there)."""
    segment = rng.integers(0, surface.segment_count, count)
    return np.sort(segment + rng.uniform(0.02, 0.98, count))


def _interpolants(surface, t):
    return surface.curve.basis(t).evaluate(surface.controls)[0]


def _close(got, want, rtol=1e-12):
    return float(np.max(np.abs(np.asarray(got) - np.asarray(want)))) <= rtol * (1.0 + float(np.max(np.abs(want))))


@pytest.mark.parametrize("grade", [3, 2], ids=["circles", "point_pairs"])
@pytest.mark.parametrize("name", IDS)
def test_projected_objects_square_to_plus_one_in_clifford(oracle, rng, name, grade):
    blades = _surface(name, grade).sample(_samples(_surface(name, grade), rng)).blades
    one = oracle.mv(np.eye(32)[0])
    assert all(_close((oracle.mv(x) * oracle.mv(x)).value, one.value) for x in blades)


@pytest.mark.parametrize("grade", [3, 2], ids=["circles", "point_pairs"])
@pytest.mark.parametrize("name", IDS)
def test_projection_is_the_full_clifford_product_S_C_of_eqs_10_to_12(oracle, rng, name, grade):
    # All 32 coefficients: the full product S C' has nothing outside the object's grade, and
    # cgamesh's blade equals it.
    surface = _surface(name, grade)
    t = _samples(surface, rng)
    want = [oracle.project(oracle.mv(x)).value for x in _interpolants(surface, t)]
    assert _close(surface.sample(t).blades, np.array(want))


@pytest.mark.parametrize("grade", [3, 2], ids=["circles", "point_pairs"])
@pytest.mark.parametrize("name", IDS)
def test_projection_times_principal_sqrt_of_the_interpolants_square_gives_the_interpolant(oracle, rng, name, grade):
    # C = C' sqrt(C'^2)^-1, checked without an inverse: C sqrt(C'^2) = C' (all 32 coefficients).
    surface = _surface(name, grade)
    t = _samples(surface, rng, 20)
    blades = surface.sample(t).blades
    back = []
    for blade, x in zip(blades, _interpolants(surface, t)):
        root = oracle.sqrt_scalar_plus_four(oracle.mv(x) * oracle.mv(x))
        back.append((oracle.mv(blade) * root).value)
    assert _close(np.array(back), _interpolants(surface, t))


def test_oracle_sqrt_is_a_principal_square_root(oracle, rng):
    # The oracle's eq. 10 itself: sqrt(Sigma)^2 = Sigma with a positive scalar part.
    surface = _surface("bezier3")
    roots_ok = []
    for x in _interpolants(surface, _samples(surface, rng, 10)):
        sigma = oracle.mv(x) * oracle.mv(x)
        root = oracle.sqrt_scalar_plus_four(sigma)
        roots_ok.append(_close((root * root).value, sigma.value) and root[()] > 0.0)
    assert all(roots_ok)


@pytest.mark.parametrize("grade", [3, 2], ids=["circles", "point_pairs"])
@pytest.mark.parametrize("name", IDS)
def test_projection_derivative_equals_central_differences(rng, name, grade):
    surface = _surface(name, grade)
    t = _samples(surface, rng, 200)
    derivative = surface.sample(t).derivatives
    difference = (surface.sample(t + H).blades - surface.sample(t - H).blades) / (2 * H)
    assert _close(derivative, difference, 1e-7)


@pytest.mark.parametrize("grade", [3, 2], ids=["circles", "point_pairs"])
@pytest.mark.parametrize("name", IDS)
def test_angular_velocity_C_dC_is_a_pure_bivector(oracle, rng, name, grade):
    # C^2 = 1 for all alpha makes C dC = -dC C: no scalar and no 4-vector part (paper eq. 18-19).
    projection = _surface(name, grade).sample(_samples(_surface(name, grade), rng, 20))
    products = [(oracle.mv(c) * oracle.mv(d)).value for c, d in zip(projection.blades, projection.derivatives)]
    assert all(_close(p, oracle.mv(p)(2).value, 1e-10) for p in products)


def test_scalar_projection_equals_full_projection_for_cocircular_point_pairs():
    # Chords of one circle (paper section 7.3): Sigma has no 4-vector part.
    angles = np.array([[0.0, 2.0], [0.5, 3.0], [1.5, 4.5], [2.0, 5.5]])
    ring = np.stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)], axis=-1) * 1.3 + [0.2, -0.1, 0.4]
    controls = objects.align_orientations(objects.point_pair(ring[:, 0], ring[:, 1]), 2)
    basis = Bezier(4).basis(np.linspace(0.01, 0.99, 50))
    interpolant, derivative = basis.evaluate(controls)
    full = project(interpolant, derivative, 2, basis.weight_sum())
    scalar = project_scalar(interpolant, derivative, 2, basis.weight_sum())
    assert _close(scalar.blades, full.blades) and _close(scalar.derivatives, full.derivatives, 1e-10)


# --- where the projection does not exist ---------------------------------------------------------

OPPOSITE = """\
cgamesh: 1
surfaces:
  - name: opposite_pair
    type: circles
    curve: linear
    align: false
    controls:
      - {center: [0.5, 0, 0], normal: [0, 0, 1], radius: 1.0}
      - {center: [0.5, 0, 0], normal: [0, 0, -1], radius: 1.0}
"""


def test_opposite_controls_without_alignment_have_a_vanishing_margin():
    surface = build_surface(parse_scene(OPPOSITE, "opposite.yaml").surfaces[0])
    t = np.linspace(0.0, 1.0, 1001)
    basis = surface.curve.basis(t)
    interpolant, derivative = basis.evaluate(surface.controls)
    margin = project(interpolant, derivative, 3, basis.weight_sum()).margin
    assert margin[0] > 0.5 and margin[-1] > 0.5 and margin.min() <= 1e-12 and abs(t[np.argmin(margin)] - 0.5) < 1e-9


def test_check_projection_exists_names_the_surface_and_alpha():
    surface = build_surface(parse_scene(OPPOSITE, "opposite.yaml").surfaces[0])
    with pytest.raises(DegenerateGeometryError) as caught:
        surface.check_projection_exists()
    message = str(caught.value)
    assert "opposite_pair" in message and "alpha = 0.5" in message and "\n" not in message


@pytest.mark.parametrize("kind", ["circles", "pairs"])
def test_margin_alone_equals_the_projections_margin(kind):
    surface = _surface("kb", 3 if kind == "circles" else 2)
    basis = surface.curve.basis(np.linspace(0.0, surface.segment_count, 97))
    interpolant, derivative = basis.evaluate(surface.controls)
    size = basis.weight_sum()
    assert np.array_equal(margin(interpolant, surface.grade, size),
                          project(interpolant, derivative, surface.grade, size).margin)
    if kind == "pairs":
        assert np.array_equal(margin(interpolant, surface.grade, size, scalar=True),
                              project_scalar(interpolant, derivative, surface.grade, size).margin)


@pytest.mark.parametrize("grade", [3, 2], ids=["circles", "point_pairs"])
@pytest.mark.parametrize("name", IDS)
def test_blades_without_derivatives_are_the_projections_bit_for_bit(name, grade):
    """The tolerance plan reads blades alone: they must be the very bits ``sample`` gives (the plan's
    rings, and so the meshes, must not depend on which reader ran), and the margin too."""
    surface = _surface(name, grade)
    t = np.linspace(0.0, surface.segment_count, 301)
    assert np.array_equal(surface.sample_blades(t), surface.sample(t).blades)
    basis = surface.curve.basis(t)
    interpolant, derivative = basis.evaluate(surface.controls)
    size = basis.weight_sum()
    for scalar, projector in ((False, project), (True, project_scalar)):
        blades, margins = project_without_derivatives(interpolant, grade, size, scalar)
        full = projector(interpolant, derivative, grade, size)
        assert np.array_equal(blades, full.blades, equal_nan=True) and np.array_equal(margins, full.margin)


def test_blades_without_derivatives_refuse_where_sample_refuses():
    surface = build_surface(parse_scene(OPPOSITE, "opposite.yaml").surfaces[0])
    with pytest.raises(DegenerateGeometryError, match="alpha = 0.5"):
        surface.sample_blades(np.array([0.25, 0.5]))


def test_the_scan_is_skipped_only_where_rings_are_as_dense_as_it():
    surface = build_surface(parse_scene(OPPOSITE, "opposite.yaml").surfaces[0])
    # Coarse rings step over alpha = 0.5: the scan still finds it.
    with pytest.raises(DegenerateGeometryError, match="alpha = 0.5"):
        surface.check_projection_exists(sampled=np.linspace(0.0, 1.0, 4))
    # Rings denser than the scan leave it nothing to add; sampling them refuses alpha = 0.5.
    dense = np.linspace(0.0, 1.0, 257)
    surface.check_projection_exists(sampled=dense)
    with pytest.raises(DegenerateGeometryError, match="alpha = 0.5"):
        surface.sample(dense)


def test_sample_refuses_where_the_projection_vanishes():
    surface = build_surface(parse_scene(OPPOSITE, "opposite.yaml").surfaces[0])
    with pytest.raises(DegenerateGeometryError):
        surface.sample(np.array([0.25, 0.5]))


def test_alignment_removes_the_opposite_orientation():
    """Aligned, the two controls are one circle: a surface of no area, refused with its place."""
    with pytest.raises(DegenerateGeometryError, match=r"o\.yaml:3: surfaces\[0\]\.controls: every control is the same"):
        build_surface(parse_scene(OPPOSITE.replace("align: false", "align: true"), "o.yaml").surfaces[0])
    # A larger second circle of the opposite orientation: aligned, the interpolation exists.
    text = OPPOSITE.replace("align: false", "align: true").replace("normal: [0, 0, -1], radius: 1.0",
                                                                   "normal: [0, 0, -1], radius: 2.0")
    surface = build_surface(parse_scene(text, "o.yaml").surfaces[0])
    surface.check_projection_exists()
    blades = surface.sample(np.linspace(0.0, 1.0, 11)).blades
    assert np.all(np.isfinite(blades))
    assert _close(blades[[0, -1]], surface.controls)


def test_margin_is_one_at_blade_controls():
    # At a control the interpolant is already a normalised blade: Sigma = 1, beta = 1, g = 2.
    surface = _surface("linear")
    basis = surface.curve.basis(np.array([0.0, 1.0, 2.0]))
    interpolant, derivative = basis.evaluate(surface.controls)
    assert np.allclose(project(interpolant, derivative, 3, basis.weight_sum()).margin, 1.0, rtol=0, atol=1e-12)

