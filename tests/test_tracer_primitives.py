"""cgamesh.tracer: rays, meets, spheres, planes, discs, facets, reflections and the camera
against the paper's formulas written out with clifford, and against Euclidean geometry."""

from __future__ import annotations

import numpy as np
import pytest

from cgamesh.geometry.algebra import products
from cgamesh.geometry.algebra.conformal import N_INF, up
from cgamesh.tracer import cga
from cgamesh.tracer.camera import Camera, rotor_from_matrix
from cgamesh.tracer.png import encode_png, read_png, write_png
from cgamesh.tracer.primitives import Disc, Facets, Plane, Sphere
from cgamesh.tracer.rays import Rays


def random_rays(rng, count, spread=4.0, target=1.0):
    origins = rng.normal(size=(count, 3)) * spread
    aims = rng.normal(size=(count, 3)) * target
    return Rays.from_origin_direction(origins, aims - origins)


def unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


# --- the CGA building blocks against clifford ------------------------------------------------------

def test_fast_products_equal_the_algebras(rng):
    a, b = rng.normal(size=(6, 32)), rng.normal(size=(6, 32))
    for grades in (((3,), (3,), (4,)), ((3,), (4,), (2,)), ((1,), (2,), (1,)), ((0, 2, 4), (3,), (3,))):
        np.testing.assert_allclose(cga.product(a, b, *grades), products.geometric(a, b, *grades), atol=1e-12)
        np.testing.assert_allclose(cga.product(a[0], b, *grades), products.geometric(a[0], b, *grades), atol=1e-12)
    np.testing.assert_allclose(cga.outer(a, b, (2,), (1,)), products.outer(a, b, (2,), (1,)), atol=1e-12)
    np.testing.assert_allclose(cga.inner(a, b, (1,), (3,)), products.inner(a, b, (1,), (3,)), atol=1e-12)


def test_meet_is_eq3_written_with_clifford(g3c, oracle, rng):
    line = cga.line(rng.normal(size=3), unit(rng.normal(size=3)))
    circle = products.outer(products.outer(up(rng.normal(size=3)), up(rng.normal(size=3)), (1,), (1,)),
                            up(rng.normal(size=3)), (2,), (1,))
    sphere = cga.sphere(rng.normal(size=3), 1.3)
    for blade, grade in ((circle, 3), (sphere, 4)):
        x, y = oracle.mv(line), oracle.mv(blade)
        expected = (x * y)(10 - 3 - grade) * g3c.layout.pseudoScalar
        np.testing.assert_allclose(cga.meet(line, blade, 3, grade), expected.value, atol=1e-12)


def test_lines_are_the_wedge_of_their_points_and_read_out_direction(oracle, rng):
    o, d = rng.normal(size=3), unit(rng.normal(size=3))
    wedge = oracle.point(o) ^ oracle.point(o + d) ^ oracle.einf
    np.testing.assert_allclose(cga.line(o, d), wedge.value, atol=1e-12)
    np.testing.assert_allclose(cga.square(cga.line(o, d), 3), 1.0)
    np.testing.assert_allclose(cga.line_direction(3.0 * cga.line(o, d)), d)
    # Lines through one point: <L1 L2>_0 is the cosine of the angle between them.
    e = unit(rng.normal(size=3))
    np.testing.assert_allclose(cga.scalar_product(cga.line(o, d), cga.line(o, e), 3), d @ e, atol=1e-12)


def test_point_pair_split_is_eq5_in_ray_order(rng):
    rays = random_rays(rng, 50, spread=3.0, target=0.2)
    a, b, f2 = cga.split_point_pair(cga.meet(rays.lines, cga.sphere(np.zeros(3), 1.5), 3, 4))
    hit = f2 > 0
    assert hit.sum() > 20
    np.testing.assert_allclose(np.linalg.norm(a[hit], axis=1), 1.5)
    np.testing.assert_allclose(np.linalg.norm(b[hit], axis=1), 1.5)
    assert np.all(rays.parameter_of(a)[hit] < rays.parameter_of(b)[hit])  # A first along the ray
    assert np.all(np.isnan(a[~hit]))


# --- primitives against Euclidean formulas ---------------------------------------------------------

def euclidean_sphere_t(rays, centre, radius, t_min=0.0):
    oc = rays.origins - centre
    b = np.einsum("ni,ni->n", oc, rays.directions)
    disc = b * b - (np.einsum("ni,ni->n", oc, oc) - radius * radius)
    root = np.sqrt(np.where(disc >= 0, disc, np.nan))
    near, far = -b - root, -b + root
    return np.where(near >= t_min, near, np.where(far >= t_min, far, np.inf))  # NaN compares False


def test_sphere_hits_are_the_quadratic_formula(rng):
    centre, radius = np.array([0.3, -0.2, 0.5]), 1.1
    rays = random_rays(rng, 400)
    t = Sphere(tuple(centre), radius).intersect(rays, 0.0).t
    expected = euclidean_sphere_t(rays, centre, radius)
    assert np.isfinite(expected).sum() > 100
    np.testing.assert_array_equal(np.isfinite(t), np.isfinite(expected))
    np.testing.assert_allclose(t[np.isfinite(t)], expected[np.isfinite(expected)], rtol=1e-10, atol=1e-10)


def test_a_ray_from_inside_a_sphere_hits_its_far_side():
    rays = Rays.from_origin_direction(np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]]))
    assert Sphere((0.0, 0.0, 0.0), 2.0).intersect(rays, 0.0).t[0] == pytest.approx(2.0)


def test_plane_hits_are_the_euclidean_formula(rng):
    point, normal = np.array([0.1, 0.2, -0.3]), unit(np.array([0.2, -0.4, 1.0]))
    rays = random_rays(rng, 400)
    t = Plane(tuple(point), tuple(normal)).intersect(rays, 0.0).t
    expected = (point - rays.origins) @ normal / (rays.directions @ normal)
    expected = np.where(expected >= 0, expected, np.inf)
    np.testing.assert_array_equal(np.isfinite(t), np.isfinite(expected))
    np.testing.assert_allclose(t[np.isfinite(t)], expected[np.isfinite(expected)], rtol=1e-10)
    parallel = Rays.from_origin_direction(np.array([[0.0, 0.0, 5.0]]), np.array([[1.0, 2.0, 0.0]]) - 0.0 * normal)
    in_plane = Plane((0.0, 0.0, 5.0), (0.0, 0.0, 1.0))
    assert np.isinf(in_plane.intersect(parallel, 0.0).t[0])  # a ray in the plane: no finite hit


def test_disc_hits_are_plane_hits_within_the_radius(rng):
    centre, normal, radius = np.array([0.2, 0.1, 0.0]), unit(np.array([0.3, 0.1, 1.0])), 0.9
    rays = random_rays(rng, 600, spread=3.0, target=1.0)
    t = Disc(tuple(centre), tuple(normal), radius).intersect(rays, 0.0).t
    plane_t = (centre - rays.origins) @ normal / (rays.directions @ normal)
    inside = np.linalg.norm(rays.at(plane_t) - centre, axis=1) < radius
    expected = np.where((plane_t >= 0) & inside, plane_t, np.inf)
    assert np.isfinite(expected).sum() > 50
    np.testing.assert_array_equal(np.isfinite(t), np.isfinite(expected))
    np.testing.assert_allclose(t[np.isfinite(t)], expected[np.isfinite(expected)], rtol=1e-10)


def test_a_ray_in_a_discs_plane_enters_it_at_its_edge():
    """Section 4.1.3, Y = 0: the ray meets the disc where it first crosses the circle."""
    disc = Disc((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 1.0)
    rays = Rays.from_origin_direction(np.array([[-3.0, 0.6, 0.0], [-3.0, 1.5, 0.0]]), np.array([[1.0, 0.0, 0.0]] * 2))
    t = disc.intersect(rays, 0.0).t
    assert t[0] == pytest.approx(3.0 - np.sqrt(1.0 - 0.36), abs=1e-12)
    assert np.isinf(t[1])


def test_facets_from_cocircular_pairs_hit_inside_the_triangle_only(rng):
    """Section 7.4: alpha, beta in [0, 1] exactly when the plane point lies in the triangle."""
    triangle = np.array([[0.0, 0.0, 0.0], [1.5, 0.2, 0.1], [0.3, 1.2, -0.2]])
    facets = Facets(triangle[None])
    rays = random_rays(rng, 500, spread=3.0, target=0.8)
    t, weights = facets.intersect_pairs(rays, np.zeros(len(rays), dtype=int), 0.0)
    normal = np.cross(triangle[1] - triangle[0], triangle[2] - triangle[0])
    plane_t = (triangle[0] - rays.origins) @ normal / (rays.directions @ normal)
    p = rays.at(plane_t)
    # Barycentric coordinates by areas: all non-negative inside.
    areas = np.stack([np.cross(triangle[(k + 1) % 3] - p, triangle[(k + 2) % 3] - p) @ normal for k in range(3)], 1)
    inside = np.all(areas >= 0, axis=1) & (plane_t >= 0)
    assert 20 < inside.sum() < 480
    np.testing.assert_array_equal(np.isfinite(t), inside)
    np.testing.assert_allclose(t[inside], plane_t[inside], rtol=1e-10)
    np.testing.assert_allclose(weights[inside], areas[inside] / (normal @ normal), atol=1e-10)


# --- reflections and normals -----------------------------------------------------------------------

def reflect(d, n):
    return d - 2.0 * np.einsum("ni,ni->n", d, n)[:, None] * n


@pytest.mark.parametrize("make", [
    lambda: Sphere((0.2, 0.0, 0.1), 1.2),
    lambda: Plane((0.0, 0.0, -0.5), (0.1, 0.2, 1.0)),
    lambda: Disc((0.0, 0.0, 0.0), (0.3, -0.2, 1.0), 1.5),
])
def test_reflected_rays_and_normal_lines_are_the_mirror_and_the_surface_normal(make, rng):
    """Eqs. 7-8 / Phi L Phi give the mirrored ray through the hit, and N ~ L' - L the normal."""
    obj = make()
    rays = random_rays(rng, 300, spread=4.0, target=0.5)
    hit = obj.intersect(rays, 0.0)
    ok = np.isfinite(hit.t)
    rays, t = rays.take(ok), hit.t[ok]
    points = rays.at(t)
    reflected = cga.normalise_line(obj.reflect(rays, points, hit.param[ok]))
    n = obj.normals(points, hit.param[ok])
    np.testing.assert_allclose(cga.line_direction(reflected), reflect(rays.directions, n), atol=1e-9)
    # L' passes through the hit point: X ^ L' = 0.
    through = cga.outer(up(points), reflected, (1,), (3,))
    assert np.abs(through).max() < 1e-9 * np.abs(reflected).max() * (1 + np.abs(points).max() ** 2)
    normal_lines = cga.normalise_line(reflected - rays.lines)
    facing = n * -np.sign(np.einsum("ni,ni->n", n, rays.directions))[:, None]
    np.testing.assert_allclose(cga.line_direction(normal_lines), facing, atol=1e-8)


def test_sphere_reflection_by_eq7_equals_eq8(rng):
    sphere = Sphere((0.0, 0.1, 0.0), 1.0)
    rays = random_rays(rng, 100, spread=3.0, target=0.3)
    hit = sphere.intersect(rays, 0.0)
    ok = np.isfinite(hit.t)
    rays = rays.take(ok)
    x = up(rays.at(hit.t[ok]))
    inverted = cga.product(cga.product(sphere.blade, rays.lines, (4,), (3,)), sphere.blade,
                           (0, 1, 2, 3, 4, 5), (4,), (3,))
    eq7 = -cga.outer(cga.inner(x, inverted, (1,), (3,)), N_INF, (2,), (1,))
    eq8 = sphere.reflect(rays, rays.at(hit.t[ok]), hit.param[ok])
    np.testing.assert_allclose(cga.normalise_line(eq7), cga.normalise_line(eq8), atol=1e-9)


# --- camera ------------------------------------------------------------------------------------------

def test_rotor_from_matrix_rotates_the_basis_into_the_columns(rng):
    from cgamesh.geometry.algebra.rotors import apply_to_euclidean

    for _ in range(5):
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        q[:, 0] *= np.sign(np.linalg.det(q))
        np.testing.assert_allclose(apply_to_euclidean(rotor_from_matrix(q), np.eye(3)), q.T, atol=1e-12)


def test_camera_rays_start_at_the_camera_and_pass_through_their_pixel_centres(oracle):
    camera = Camera((3.0, -4.0, 2.0), (0.0, 0.5, 0.5), (0.0, 0.0, 1.0), focal_length=1.5, x_max=1.2, y_max=0.8)
    width, height = 6, 4
    rays = camera.rays(width, height)
    forward = unit(np.subtract(camera.look_at, camera.position))
    right = unit(np.cross(forward, camera.up))
    upward = np.cross(right, forward)
    column = np.tile(np.arange(width), height)
    row = np.repeat(np.arange(height), width)
    x = -0.6 * (1 - 2 * (column + 0.5) / width)
    z = -0.4 * (1 - 2 * (height - 1 - row + 0.5) / height)
    centres = np.asarray(camera.position) + 1.5 * forward + x[:, None] * right + z[:, None] * upward
    np.testing.assert_allclose(rays.origins, np.broadcast_to(camera.position, (24, 3)), atol=1e-12)
    np.testing.assert_allclose(rays.directions, unit(centres - camera.position), atol=1e-12)
    # L = X0 ^ P ^ n_inf (eq. 2), normalised, as clifford builds it.
    expected = oracle.point(camera.position) ^ oracle.point(centres[5]) ^ oracle.einf
    expected = expected / np.sqrt((expected * expected)[()])
    np.testing.assert_allclose(rays.lines[5], expected.value, atol=1e-10)
    # project() inverts the pixel mapping.
    pixels, depth = camera.project(centres, width, height)
    np.testing.assert_allclose(pixels, np.stack([column + 0.5, row + 0.5], axis=1), atol=1e-9)
    assert np.all(depth > 0)


# --- PNG ----------------------------------------------------------------------------------------------

def test_png_round_trip_and_a_decoder_reads_it(rng, tmp_path):
    image = rng.integers(0, 256, size=(7, 9, 3)).astype(np.uint8)
    path = tmp_path / "x.png"
    write_png(path, image)
    np.testing.assert_array_equal(read_png(path), image)
    from PIL import Image  # an independent decoder (matplotlib's dependency; tests only)

    np.testing.assert_array_equal(np.asarray(Image.open(path).convert("RGB")), image)
    floats = encode_png(np.full((2, 2, 3), 0.5))
    assert floats.startswith(b"\x89PNG")
