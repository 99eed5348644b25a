"""cgamesh.tracer: rays against evolved surfaces, by both root finders, with their normals."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from cgamesh.inputs.scene import load_scene, parse_scene
from cgamesh.tracer import chebyshev
from cgamesh.tracer.evolved import RootFinder, TracedSurface
from cgamesh.tracer.rays import Rays
from cgamesh.tracer.sampled import sign_change_roots
from cgamesh.tracer.verify import line_angle
from cgamesh.tracer.world import surface_from_spec

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def traced(text: str, **kwargs) -> TracedSurface:
    return TracedSurface(surface_from_spec(parse_scene(text).surfaces[0]), **kwargs)


def unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def rays_at(rng, surface: TracedSurface, count: int, spread: float = 0.5) -> Rays:
    """Rays from a shell around the surface's bounding sphere towards points near its centre."""
    c, r = surface.bound_centre, surface.bound_radius
    origins = c + 3.0 * r * unit(rng.normal(size=(count, 3)))
    aims = c + spread * r * rng.normal(size=(count, 3))
    return Rays.from_origin_direction(origins, aims - origins)


# --- circles on one sphere trace as that sphere -------------------------------------------------------

SPHERE_CENTRE = np.array([0.4, -0.3, 0.2])
SPHERE_RADIUS = 1.5


def latitude(height: float) -> str:
    """A circle of the sphere above, in the plane at ``height`` above its centre along z."""
    c = SPHERE_CENTRE + [0.0, 0.0, height]
    r = np.sqrt(SPHERE_RADIUS**2 - height**2)
    return f"{{center: [{c[0]}, {c[1]}, {c[2]}], normal: [0, 0, 1], radius: {r}}}"


def sphere_band(curve: str, heights) -> str:
    controls = "\n".join(f"      - {latitude(h)}" for h in heights)
    return f"cgamesh: 1\nsurfaces:\n  - name: band\n    type: circles\n    curve: {curve}\n    controls:\n{controls}\n"


@pytest.mark.parametrize("curve, heights", [("linear", (-0.9, 1.1)), ("bezier", (-1.2, 0.2, 1.0)),
                                            ("kb", (-1.1, -0.2, 0.6, 1.2))])
@pytest.mark.parametrize("finder", [RootFinder("polynomial"), RootFinder("sampled", 512)])
def test_circles_on_one_sphere_trace_as_the_sphere(curve, heights, finder, rng):
    """Every interpolant of circles on a common sphere lies on it: the surface is the sphere's
    band between the end circles, so a ray hits the sphere's first point in the band."""
    surface = traced(sphere_band(curve, heights), finder=finder)
    rays = rays_at(rng, surface, 600, spread=0.6)
    hit = surface.intersect(rays, 0.0)
    oc = rays.origins - SPHERE_CENTRE
    b = np.einsum("ni,ni->n", oc, rays.directions)
    disc = b * b - (np.einsum("ni,ni->n", oc, oc) - SPHERE_RADIUS**2)
    root = np.sqrt(np.maximum(disc, 0.0))
    low, high = SPHERE_CENTRE[2] + min(heights[0], heights[-1]), SPHERE_CENTRE[2] + max(heights[0], heights[-1])
    expected = np.full(len(rays), np.inf)
    for t in (-b + root, -b - root):  # the nearer assignment wins
        z = rays.at(t)[:, 2]
        expected = np.where((disc > 0) & (t >= 0) & (z >= low) & (z <= high), t, expected)
    grazing = np.abs(disc) < 1e-6
    band_edge = np.min(np.abs(rays.at(-b - root)[:, 2, None] - [low, high]), axis=1) < 1e-6
    keep = ~grazing & ~band_edge
    assert np.isfinite(expected[keep]).sum() > 150
    np.testing.assert_array_equal(np.isfinite(hit.t[keep]), np.isfinite(expected[keep]))
    both = keep & np.isfinite(expected)
    tolerance = 1e-9 if finder.kind == "polynomial" else 1e-3
    np.testing.assert_allclose(hit.t[both], expected[both], atol=tolerance * SPHERE_RADIUS)
    if finder.kind == "polynomial":
        points = rays.take(both).at(hit.t[both])
        normals = surface.normals(points, hit.param[both])
        assert line_angle(normals, unit(points - SPHERE_CENTRE)).max() < 1e-7


# --- co-circular point pairs trace as their plane -------------------------------------------------------

CHORDS = """
cgamesh: 1
surfaces:
  - name: chords
    type: point_pairs
    curve: {curve}
    controls:
{controls}
"""


def chord(angle_a: float, angle_b: float) -> str:
    """A chord of the circle of radius 2 about (1, 0.5, -0.3) in the plane with normal (0.2, 0.3, 1)."""
    n = unit(np.array([0.2, 0.3, 1.0]))
    u = unit(np.cross(n, [1.0, 0.0, 0.0]))
    v = np.cross(n, u)
    centre = np.array([1.0, 0.5, -0.3])
    a, b = (centre + 2.0 * (np.cos(x) * u + np.sin(x) * v) for x in (angle_a, angle_b))
    return f"      - {{a: [{a[0]}, {a[1]}, {a[2]}], b: [{b[0]}, {b[1]}, {b[2]}]}}"


@pytest.mark.parametrize("curve, chords", [("linear", [(0.1, 2.9), (1.2, 4.3)]),
                                           ("bezier", [(0.1, 2.9), (1.0, 3.5), (2.2, 5.0)])])
def test_cocircular_point_pairs_trace_as_their_plane(curve, chords, rng):
    surface = traced(CHORDS.format(curve=curve, controls="\n".join(chord(*c) for c in chords)))
    assert surface.surface.four_vector_free
    n = unit(np.array([0.2, 0.3, 1.0]))
    h = n @ np.array([1.0, 0.5, -0.3])
    rays = rays_at(rng, surface, 800, spread=0.5)
    hit = surface.intersect(rays, 0.0)
    found = np.isfinite(hit.t)
    assert found.sum() > 100
    points = rays.take(found).at(hit.t[found])
    plane_t = (h - rays.origins[found] @ n) / (rays.directions[found] @ n)
    np.testing.assert_allclose(hit.t[found], plane_t, rtol=1e-10)
    normals = surface.normals(points, hit.param[found])
    assert line_angle(normals, np.broadcast_to(n, normals.shape)).max() < 1e-8
    # Each hit lies on the chord of its own parameter.
    from cgamesh.geometry.objects import point_pair_endpoints

    a, b = point_pair_endpoints(surface.surface.sample(hit.param[found]).blades)
    a, b = surface.frame.to_world(a), surface.frame.to_world(b)
    s = np.einsum("ni,ni->n", points - a, b - a) / np.einsum("ni,ni->n", b - a, b - a)
    np.testing.assert_allclose(a + s[:, None] * (b - a), points, atol=1e-10)
    assert np.all((s > -1e-9) & (s < 1 + 1e-9))


# --- the two finders agree ---------------------------------------------------------------------------------

@pytest.mark.parametrize("example", ["fig08_linear", "fig08_cubic", "rational_tube", "kb_tube", "closed_loop",
                                     "fig10_quadratic_pairs", "traced_fig11_point_pairs"])
def test_polynomial_and_sampled_finders_agree_away_from_grazing(example, rng):
    spec = load_scene(EXAMPLES / f"{example}.yaml").surfaces[0]
    polynomial = TracedSurface(surface_from_spec(spec))
    sampled = polynomial.with_finder(RootFinder("sampled", 2048))
    rays = rays_at(rng, polynomial, 400)
    exact, rough = polynomial.intersect(rays, 0.0), sampled.intersect(rays, 0.0)
    found = np.isfinite(exact.t)
    assert found.sum() > 40
    # Away from grazing: the ray crosses the surface at more than a tiny angle.
    normals = np.zeros((len(rays), 3))
    normals[found] = polynomial.normals(rays.take(found).at(exact.t[found]), exact.param[found])
    crossing = np.abs(np.einsum("ni,ni->n", normals, rays.directions)) > 1e-3
    agree = ~found | crossing
    np.testing.assert_array_equal(np.isfinite(rough.t[agree]), found[agree])
    both = found & crossing
    assert np.abs(exact.t[both] - rough.t[both]).max() < 1e-4 * polynomial.bound_radius


def test_the_sampled_finder_finds_the_grazing_roots_its_sign_changes_miss():
    params = np.linspace(0.0, 1.0, 11)
    touching = (params - 0.52) ** 2 - 1e-4  # two roots between the same pair of samples
    _, roots = sign_change_roots(touching[None, :], params)
    np.testing.assert_allclose(np.sort(roots), [0.51, 0.53], atol=1e-12)
    _, roots = sign_change_roots(touching[None, :], params, grazing=False)
    assert roots.size == 0
    crossing = (params - 0.37) * (params + 2.0)  # a quadratic's sign change is solved exactly
    _, roots = sign_change_roots(crossing[None, :], params)
    np.testing.assert_allclose(roots, [0.37], atol=1e-12)


# --- normals ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("example", ["fig08_quadratic", "kb_tube", "rational_tube", "fig10_cubic_pairs",
                                     "ribbon_loop"])
def test_analytic_normals_agree_with_the_numerical_second_opinion(example, rng):
    surface = TracedSurface(surface_from_spec(load_scene(EXAMPLES / f"{example}.yaml").surfaces[0]))
    rays = rays_at(rng, surface, 300)
    hit = surface.intersect(rays, 0.0)
    on = np.isfinite(hit.t) & (hit.param >= 0.0)
    points = rays.take(on).at(hit.t[on])
    analytic = surface.normals(points, hit.param[on])
    numerical = surface.numerical_normals(points, hit.param[on])
    np.testing.assert_allclose(np.linalg.norm(analytic, axis=1), 1.0)
    assert np.percentile(line_angle(analytic, numerical), 99) < 1e-3


# --- the intersection polynomial ----------------------------------------------------------------------------

def test_polynomial_degrees_after_the_known_roots_are_divided_out():
    degrees = {}
    for example, index in (("fig08_linear", 0), ("fig08_quadratic", 0), ("kb_tube", 0), ("fig10_linear_pairs", 0),
                           ("fig10_cubic_pairs", 0), ("fig12_cocircular_chords", 0)):
        spec = load_scene(EXAMPLES / f"{example}.yaml").surfaces[index]
        degrees[example] = TracedSurface(surface_from_spec(spec)).polynomial_degree(0)
    # 12 d - 4 for circles, 6 d - 2 for pairs; d for co-circular pairs (no 4-vector part at all).
    assert degrees == {"fig08_linear": 8, "fig08_quadratic": 20, "kb_tube": 32, "fig10_linear_pairs": 4,
                       "fig10_cubic_pairs": 16, "fig12_cocircular_chords": 1}
    rational = TracedSurface(surface_from_spec(load_scene(EXAMPLES / "rational_tube.yaml").surfaces[0]))
    # A symmetric rational curve passes through a blade in its middle as well as at its ends.
    np.testing.assert_allclose(rational.known_roots(0), [0.0, 0.5, 1.0], atol=1e-9)
    assert rational.polynomial_degree(0) == 24 - 6


def test_chebyshev_roots_of_batches(rng):
    truth = np.sort(rng.uniform(-0.95, 0.95, size=(20, 6)), axis=1)
    u = chebyshev.nodes(6)
    values = np.prod(u[None, :, None] - truth[:, None, :], axis=2)
    roots = np.sort(chebyshev.roots(chebyshev.coefficients(values)), axis=1)
    np.testing.assert_allclose(roots, truth, atol=1e-9)
    value, derivative = chebyshev.evaluate(chebyshev.coefficients(values), np.full(20, 0.3))
    np.testing.assert_allclose(value, np.prod(0.3 - truth, axis=1), atol=1e-12)
    numeric = (np.prod(0.3 + 1e-6 - truth, axis=1) - np.prod(0.3 - 1e-6 - truth, axis=1)) / 2e-6
    np.testing.assert_allclose(derivative, numeric, atol=1e-7)


# --- frames and bounds -------------------------------------------------------------------------------------

def test_a_surface_far_from_the_origin_traces_like_the_same_surface_at_the_origin(rng):
    text = (EXAMPLES / "fig18_linear_surface.yaml").read_text()
    near = TracedSurface(surface_from_spec(parse_scene(text).surfaces[0]))
    shifted = text.replace("center: [0.0, 0.0, 0.0]", "center: [1000.0, -2000.0, 500.0]").replace(
        "center: [1.5, 0.0, 1.5]", "center: [1001.5, -2000.0, 501.5]")
    far = TracedSurface(surface_from_spec(parse_scene(shifted).surfaces[0]))
    rays = rays_at(rng, near, 200)
    moved = Rays.from_origin_direction(rays.origins + [1000.0, -2000.0, 500.0], rays.directions)
    a, b = near.intersect(rays, 0.0), far.intersect(moved, 0.0)
    np.testing.assert_array_equal(np.isfinite(a.t), np.isfinite(b.t))
    np.testing.assert_allclose(a.t[np.isfinite(a.t)], b.t[np.isfinite(b.t)], atol=1e-9)


@pytest.mark.parametrize("example", ["kb_tube", "fig14_bezier_orders", "ribbon_loop"])
def test_bounding_spheres_enclose_their_surfaces(example):
    from cgamesh.geometry.objects import circle_euclidean, point_pair_endpoints

    for spec in load_scene(EXAMPLES / f"{example}.yaml").surfaces:
        surface = TracedSurface(surface_from_spec(spec))
        t = np.linspace(0.0, surface.end, 4001)
        blades = surface.surface.sample(t).blades
        if surface.grade == 3:
            c, n, r = circle_euclidean(blades)
            u = unit(np.cross(n, [0.3, 0.5, 0.7]))
            v = np.cross(n, u)
            angles = np.linspace(0, 2 * np.pi, 24)[None, :, None]
            points = c[:, None] + r[:, None, None] * (np.cos(angles) * u[:, None] + np.sin(angles) * v[:, None])
        else:
            a, b = point_pair_endpoints(blades)
            points = a[:, None] + np.linspace(0, 1, 9)[None, :, None] * (b - a)[:, None]
        points = surface.frame.to_world(points.reshape(-1, 3))
        assert np.linalg.norm(points - surface.bound_centre, axis=1).max() <= surface.bound_radius


def test_the_tracer_never_imports_the_mesher():
    code = ("import sys, importlib, pkgutil, cgamesh.tracer as t\n"
            "for m in pkgutil.iter_modules(t.__path__): importlib.import_module('cgamesh.tracer.' + m.name)\n"
            "import cgamesh_cli.render, cgamesh_cli.verify\n"
            "bad = [m for m in ('cgamesh.meshing.normals', 'cgamesh.meshing.circles', 'cgamesh.meshing.ribbons', 'cgamesh.pipelines.scene',"
            " 'clifford', 'matplotlib') if m in sys.modules]\n"
            "print(bad)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
