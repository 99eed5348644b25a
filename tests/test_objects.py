"""cgamesh.geometry.objects: circles and point pairs built, normalised, oriented and read out as the format says."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from cgamesh.geometry import objects
from cgamesh.pipelines.scene import build_surface
from cgamesh.inputs.scene import parse_scene
from cgamesh.geometry.surface import CircleRings


# --- strategies: valid objects by construction -------------------------------------------------

coordinates = st.floats(-5.0, 5.0, allow_nan=False, allow_infinity=False)
points = st.tuples(coordinates, coordinates, coordinates).map(np.array)
radii = st.floats(0.05, 5.0)


@st.composite
def unit_vectors(draw):
    """Unit vectors from spherical angles: never zero, covering the poles and the axes."""
    polar = draw(st.floats(0.0, math.pi))
    azimuth = draw(st.floats(0.0, 2.0 * math.pi))
    return np.array([math.sin(polar) * math.cos(azimuth), math.sin(polar) * math.sin(azimuth), math.cos(polar)])


@st.composite
def circles(draw):
    """(centre (3,), unit normal (3,), radius) of a real circle."""
    return draw(points), draw(unit_vectors()), draw(radii)


@st.composite
def point_pairs(draw):
    """(a, b): distinct end points at least 0.05 apart."""
    a = draw(points)
    return a, a + draw(st.floats(0.05, 5.0)) * draw(unit_vectors())


def _ccw_points(centre, normal, radius, phase):
    """Three points of the circle, counter-clockwise seen from the tip of ``normal``, from ``phase``."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(helper, normal)
    u /= np.linalg.norm(u)
    v = np.cross(normal, u)  # (u, v, normal) right-handed
    angles = phase + np.array([0.0, 2.0, 4.0]) * math.pi / 3.0
    return [centre + radius * (math.cos(a) * u + math.sin(a) * v) for a in angles]


def _clifford_circle(oracle, a, b, d):
    blade = oracle.point(a) ^ oracle.point(b) ^ oracle.point(d)
    return blade / math.sqrt((blade * blade)[()])


def _scale(centre, radius):
    return float(np.linalg.norm(centre) + radius)


def _conditioning(centre, radius):
    """(1 + |c| / r)^2: conformal coefficients mix x and x^2, so rounding grows with it."""
    return (1.0 + float(np.linalg.norm(centre)) / radius) ** 2


# --- construction and orientation --------------------------------------------------------------

def test_unit_circle_with_normal_plus_z_is_e1_e2_minus_e1(g3c):
    g = g3c
    want = g.up(g.e1) ^ g.up(g.e2) ^ g.up(-g.e1)
    want = want / math.sqrt((want * want)[()])
    got = objects.circle_from_center_normal_radius([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 1.0)
    assert np.allclose(got, want.value, rtol=0.0, atol=1e-15)


@given(circles(), st.floats(0.0, 2.0 * math.pi))
def test_center_normal_radius_is_clifford_blade_of_ccw_points(oracle, circle, phase):
    centre, normal, radius = circle
    want = _clifford_circle(oracle, *_ccw_points(centre, normal, radius, phase)).value
    got = objects.circle_from_center_normal_radius(centre, normal, radius)
    assert np.max(np.abs(got - want)) <= 1e-12 * _conditioning(centre, radius) * np.max(np.abs(want))


@given(circles())
def test_normal_length_does_not_change_the_circle(circle):
    centre, normal, radius = circle
    unit = objects.circle_from_center_normal_radius(centre, normal, radius)
    long = objects.circle_from_center_normal_radius(centre, 7.5 * normal, radius)
    assert np.max(np.abs(unit - long)) <= 1e-12 * _conditioning(centre, radius) * np.max(np.abs(unit))


@given(circles(), st.floats(0.0, 2.0 * math.pi))
def test_circle_through_is_clifford_blade_in_given_order(oracle, circle, phase):
    centre, _, radius = circle
    a, b, d = _ccw_points(*circle, phase)
    # Reversed order: the opposite orientation, and still exactly A ^ B ^ D as given.
    want = _clifford_circle(oracle, d, b, a).value
    got = objects.circle_through(d, b, a)
    assert np.max(np.abs(got - want)) <= 1e-12 * _conditioning(centre, radius) * np.max(np.abs(want))


@given(point_pairs())
def test_point_pair_is_clifford_blade_normalised(oracle, pair):
    a, b = pair
    blade = oracle.point(a) ^ oracle.point(b)
    want = (blade / math.sqrt((blade * blade)[()])).value
    got = objects.point_pair(a, b)
    conditioning = _conditioning(a, np.linalg.norm(b - a))
    assert np.max(np.abs(got - want)) <= 1e-12 * conditioning * np.max(np.abs(want))


def _squares_to_one(oracle, blade):
    """X X = 1 in clifford, every one of the 32 coefficients of the product.

    Rounding in the up() points leaves the normalised blade X off the blade manifold by about
    eps |X|^2, so its square deviates by about eps |X|^4 (|X|^2 = sum of squared coefficients,
    which grows like (|c| / r)^2: hence LocalFrame, which keeps |c| ~ 1). Measured over this
    domain: at most 1.5e-15 |X|^4.
    """
    square = (oracle.mv(blade) * oracle.mv(blade)).value
    square[0] -= 1.0
    return float(np.max(np.abs(square))) <= 1e-14 * (1.0 + float(np.sum(blade * blade))) ** 2


@given(circles())
def test_circle_squares_to_plus_one_in_clifford(oracle, circle):
    assert _squares_to_one(oracle, objects.circle_from_center_normal_radius(*circle))


@given(point_pairs())
def test_point_pair_squares_to_plus_one_in_clifford(oracle, pair):
    assert _squares_to_one(oracle, objects.point_pair(*pair))


# --- read-outs ---------------------------------------------------------------------------------

@given(circles())
def test_circle_euclidean_round_trips_centre_normal_radius(circle):
    centre, normal, radius = circle
    got_centre, got_normal, got_radius = objects.circle_euclidean(
        objects.circle_from_center_normal_radius(centre, normal, radius))
    scale = _scale(centre, radius)
    assert (np.max(np.abs(got_centre - centre)) <= 1e-9 * scale
            and np.max(np.abs(got_normal - normal)) <= 1e-9 * scale / radius
            and abs(got_radius - radius) <= 1e-9 * scale)


@given(circles(), st.floats(0.0, 2.0 * math.pi))
def test_circle_euclidean_normal_is_right_handed_for_through_points(circle, phase):
    centre, normal, radius = circle
    _, got_normal, _ = objects.circle_euclidean(objects.circle_through(*_ccw_points(centre, normal, radius, phase)))
    assert np.dot(got_normal, normal) >= 1.0 - 1e-9 * _scale(centre, radius) / radius


@given(circles())
def test_circle_euclidean_equals_cliffords_get_circle_in_euc(oracle, circle):
    blade = objects.circle_from_center_normal_radius(*circle)
    want_centre, want_normal, want_radius = oracle.circle_euclidean(oracle.mv(blade))
    centre, normal, radius = objects.circle_euclidean(blade)
    scale = _scale(circle[0], circle[2])
    assert (np.max(np.abs(centre - want_centre)) <= 1e-9 * scale
            and abs(abs(np.dot(normal, want_normal)) - 1.0) <= 1e-9
            and abs(radius - want_radius) <= 1e-9 * scale)


@given(point_pairs())
def test_point_pair_endpoints_round_trip_in_order(pair):
    a, b = pair
    got_a, got_b = objects.point_pair_endpoints(objects.point_pair(a, b))
    scale = float(np.linalg.norm(a) + np.linalg.norm(b - a))
    assert np.max(np.abs(got_a - a)) <= 1e-9 * scale and np.max(np.abs(got_b - b)) <= 1e-9 * scale


# --- orientation alignment ---------------------------------------------------------------------

@given(st.lists(st.tuples(circles(), st.booleans()), min_size=2, max_size=6))
def test_align_orientations_only_negates_and_makes_consecutive_products_non_negative(oracle, items):
    blades = np.array([(-1.0 if flip else 1.0) * objects.circle_from_center_normal_radius(*c) for c, flip in items])
    aligned = objects.align_orientations(blades, objects.CIRCLE_GRADE)
    only_negated = np.array_equal(aligned[0], blades[0]) and all(
        np.array_equal(x, y) or np.array_equal(x, -y) for x, y in zip(aligned, blades))
    products = [(oracle.mv(x) * oracle.mv(y))[()] for x, y in zip(aligned[:-1], aligned[1:])]
    assert only_negated and min(products) >= 0.0


def test_align_orientations_negates_an_opposite_copy():
    circle = objects.circle_from_center_normal_radius([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 1.0)
    shifted = objects.circle_from_center_normal_radius([0.1, 0.0, 0.5], [0.0, 0.0, -1.0], 1.0)
    aligned = objects.align_orientations(np.stack([circle, shifted, -shifted]), objects.CIRCLE_GRADE)
    assert np.array_equal(aligned, np.stack([circle, -shifted, -shifted]))


# --- far from the origin: the local frame keeps the read-outs exact ----------------------------

def _far_scene(offset, radius):
    return f"""\
cgamesh: 1
surfaces:
  - name: far
    type: circles
    curve: linear
    controls:
      - {{center: [{offset!r}, {-offset / 3!r}, {offset / 7!r}], normal: [0.2, 0.3, 1.0], radius: {radius!r}}}
      - {{center: [{offset + 0.5!r}, {-offset / 3!r}, {offset / 7 + 2.0!r}], normal: [0.0, 1.0, 1.0], radius: {radius!r}}}
"""


@pytest.mark.parametrize("offset", [1e3, 1e5])
@pytest.mark.parametrize("radius", [1.0, 0.01])
def test_far_circle_reads_back_its_radius(offset, radius):
    # The error depends on the circle's size relative to its surface's frame (the conditioning
    # of the frame-local objects), never on the distance from the origin.
    surface = build_surface(parse_scene(_far_scene(offset, radius), "far.yaml").surfaces[0])
    rings = CircleRings.from_projection(surface.sample(np.array([0.0, 1.0])), surface.frame)
    relative_size = radius / surface.frame.scale
    assert np.max(np.abs(rings.radius - radius)) <= 1e-12 * radius * max(1.0, relative_size ** -2)


@pytest.mark.parametrize("offset", [1e3, 1e5])
def test_far_circle_reads_back_its_centre_and_normal(offset):
    surface = build_surface(parse_scene(_far_scene(offset, 1.0), "far.yaml").surfaces[0])
    rings = CircleRings.from_projection(surface.sample(np.array([0.0, 1.0])), surface.frame)
    centres = np.array([[offset, -offset / 3, offset / 7], [offset + 0.5, -offset / 3, offset / 7 + 2.0]])
    normals = np.array([[0.2, 0.3, 1.0], [0.0, 1.0, 1.0]])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    assert (np.max(np.abs(rings.centre - centres)) <= 1e-12 * offset
            and np.max(np.abs(rings.normal - normals)) <= 1e-12)
