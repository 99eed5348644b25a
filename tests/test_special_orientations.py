"""Parallel and antiparallel special cases of every rotor and frame helper.

Exact +-x, +-y, +-z directions, rotations by exactly pi, identical consecutive directions: each
helper (rotors.rotation_between, objects.perpendicular_unit and circle construction / read-out,
circles.transported_frames, the ribbon mesher, the tracer) gives finite, unit, orthogonal results
there, and a tube whose first circle faces -z (which once crashed rotation_between) meshes onto
its circles with every curve kind, at a resolution and to a tolerance.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from cgamesh.geometry.algebra import products, rotors
from cgamesh.geometry.objects import circle_euclidean, circle_from_center_normal_radius, perpendicular_unit
from cgamesh.inputs.scene import parse_scene
from cgamesh.meshing.ring_frames import transported_frames
from cgamesh.pipelines.scene import Resolution, mesh_surface

AXES = np.array([[1.0, 0, 0], [-1.0, 0, 0], [0, 1.0, 0], [0, -1.0, 0], [0, 0, 1.0], [0, 0, -1.0]])
CURVES = ("linear", "bezier", "rational_bezier", "kb", "catmull_rom")


def assert_rotates(rotor: np.ndarray, a: np.ndarray, b: np.ndarray) -> None:
    """rotor (..., 32) is a unit Euclidean rotor with R a ~R = b."""
    assert np.all(np.isfinite(rotor))
    norm = products.geometric(rotor, products.reverse(rotor), (0, 2), (0, 2), (0,))[..., 0]
    np.testing.assert_allclose(norm, 1.0, atol=1e-12)
    np.testing.assert_allclose(rotors.apply_to_euclidean(rotor, np.broadcast_to(a, np.shape(b))), b, atol=1e-12)


@pytest.mark.parametrize("i, j", list(itertools.product(range(6), range(6))))
def test_rotation_between_every_pair_of_axes(i, j):
    a, b = AXES[i], AXES[j]
    assert_rotates(rotors.rotation_between(a, b), a, b)
    assert_rotates(rotors.rotation_between(a[None], b[None]), a[None], b[None])


def test_rotation_between_one_vector_and_a_batch():
    """A fixed vector against a batch broadcasts (the first ring of a tube is carried from e3)."""
    e3 = np.array([0.0, 0.0, 1.0])
    assert_rotates(rotors.rotation_between(e3, AXES), e3, AXES)
    assert_rotates(rotors.rotation_between(e3, -e3[None]), e3, -e3[None])
    rotor = rotors.rotation_between(AXES, e3)
    assert rotor.shape == (6, 32)
    assert_rotates(rotor, AXES, np.broadcast_to(e3, AXES.shape))


@pytest.mark.parametrize("tilt", [1e-15, 1e-12, 1e-9, 1e-7, 1e-5])
def test_rotation_between_nearly_opposite_vectors(tilt, rng):
    a = rng.normal(size=(50, 3))
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b = -a + tilt * perpendicular_unit(a)
    b /= np.linalg.norm(b, axis=1, keepdims=True)
    rotor = rotors.rotation_between(a, b)
    assert np.all(np.isfinite(rotor))
    norm = products.geometric(rotor, products.reverse(rotor), (0, 2), (0, 2), (0,))[..., 0]
    np.testing.assert_allclose(norm, 1.0, atol=1e-12)
    # The plane of a nearly half turn is fixed only to about eps / tilt: so is the image of a.
    moved = rotors.apply_to_euclidean(rotor, a)
    assert np.abs(moved - b).max() <= 1e-15 / tilt + 1e-12


def test_perpendicular_unit_on_axes_and_diagonals():
    diagonals = np.array(list(itertools.product([-1.0, 1.0], repeat=3))) / np.sqrt(3.0)
    for n in (AXES, diagonals):
        u = perpendicular_unit(n)
        np.testing.assert_allclose(np.linalg.norm(u, axis=1), 1.0, atol=1e-15)
        np.testing.assert_allclose(np.einsum("ij,ij->i", u, n), 0.0, atol=1e-15)


@pytest.mark.parametrize("scale", [1.0, 1e-300, 5e-324, 1e300])
def test_circles_facing_each_axis_read_back(scale):
    """A circle's normal is a direction: any finite non-zero length gives the same circle."""
    centre = np.array([0.3, -0.2, 0.1])
    circles = circle_from_center_normal_radius(np.broadcast_to(centre, (6, 3)), AXES * scale, np.full(6, 0.4))
    c, n, r = circle_euclidean(circles)
    np.testing.assert_allclose(c, np.broadcast_to(centre, (6, 3)), atol=1e-14)
    np.testing.assert_allclose(n, AXES, atol=1e-14)  # right-handed: the normal as given
    np.testing.assert_allclose(r, 0.4, atol=1e-14)


@pytest.mark.parametrize("closed", [False, True])
def test_transported_frames_through_axes_half_turns_and_repeats(closed):
    """Normals along every axis, turning by exactly pi, and repeating: unit axes in each plane."""
    normal = np.concatenate([AXES, AXES[::-1], AXES[[4, 4, 5, 5, 4]]])
    t = np.linspace(0.0, 1.0, len(normal))
    u, v = transported_frames(normal, closed, t)
    for axis in (u, v):
        assert np.all(np.isfinite(axis))
        np.testing.assert_allclose(np.linalg.norm(axis, axis=1), 1.0, atol=1e-12)
        np.testing.assert_allclose(np.einsum("ij,ij->i", axis, normal), 0.0, atol=1e-12)
    np.testing.assert_allclose(np.einsum("ij,ij->i", u, v), 0.0, atol=1e-12)


def tube_scene(curve: str, first: list, second: list, extra: str = "", third: list = (0, 0.5, 3)) -> str:
    weights = ", weight: 2" if curve == "rational_bezier" else ""
    third = list(third)
    return (f"cgamesh: 1\nsurfaces:\n  - name: t\n    type: circles\n    curve: {curve}\n{extra}    controls:\n"
            f"      - {{center: [0, 0, 0], normal: {first}, radius: 1{weights}}}\n"
            f"      - {{center: [0, 0, 2], normal: {second}, radius: 0.5}}\n"
            f"      - {{center: {third}, normal: {second}, radius: 0.5}}\n")


def assert_ends_on_their_circles(mesh, around: int) -> None:
    """The first ring lies on the first control circle (radius 1 about the origin, in z = 0)."""
    assert np.all(np.isfinite(mesh.positions)) and np.all(np.isfinite(mesh.normals))
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-12)
    first = mesh.positions[: around + 1]
    np.testing.assert_allclose(first[:, 2], 0.0, atol=1e-12)
    np.testing.assert_allclose(np.hypot(first[:, 0], first[:, 1]), 1.0, atol=1e-12)


@pytest.mark.parametrize("curve", CURVES)
def test_a_tube_whose_first_circle_faces_minus_z(curve):
    """The reported crash: IndexError in rotation_between, with every curve kind."""
    spec = parse_scene(tube_scene(curve, [0, 0, -1], [0, 0, -1])).surfaces[0]
    mesh = mesh_surface(spec, Resolution(around=12, along=24))
    assert_ends_on_their_circles(mesh, 12)


@pytest.mark.parametrize("curve", ["linear", "kb"])
def test_a_tube_whose_first_circle_faces_minus_z_to_a_tolerance(curve):
    spec = parse_scene(tube_scene(curve, [0, 0, -1], [0, 0, -1])).surfaces[0]
    mesh = mesh_surface(spec, Resolution(tolerance=1e-2))
    assert mesh.max_deviation <= 1e-2
    assert np.all(np.isfinite(mesh.positions)) and np.all(np.isfinite(mesh.normals))


@pytest.mark.parametrize("curve", CURVES)
@pytest.mark.parametrize("first, second", [(a.tolist(), b.tolist()) for a, b in itertools.product(AXES, AXES)
                                           if a[2] != 0 or b[2] != 0][::3])
def test_tubes_between_axis_aligned_circles(curve, first, second):
    """Circles facing exact axes, consecutive ones parallel, antiparallel or perpendicular.

    The third circle lies one unit along the second's normal: two disjoint circles in one plane
    (or sliding sideways in it) would interpolate through a line (tests/test_lines_through_infinity.py)."""
    third = (np.array([0.0, 0.0, 2.0]) + np.array(second)).tolist()
    spec = parse_scene(tube_scene(curve, first, second, third=third)).surfaces[0]
    mesh = mesh_surface(spec, Resolution(around=8, along=12))
    assert np.all(np.isfinite(mesh.positions)) and np.all(np.isfinite(mesh.normals))
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-12)


@pytest.mark.parametrize("direction", AXES.tolist())
def test_ribbons_along_each_axis(direction):
    """Point pairs whose segments lie along exact axes, turning by exactly pi between controls."""
    d = np.array(direction)
    side = perpendicular_unit(d[None])[0]
    pairs = [(np.zeros(3), d), (side + d, side), (2 * side, 2 * side + d)]  # the middle pair reversed
    controls = "".join(f"      - {{a: {a.tolist()}, b: {b.tolist()}}}\n" for a, b in pairs)
    text = f"cgamesh: 1\nsurfaces:\n  - name: r\n    type: point_pairs\n    curve: kb\n    controls:\n{controls}"
    mesh = mesh_surface(parse_scene(text).surfaces[0], Resolution(around=3, along=16))
    assert np.all(np.isfinite(mesh.positions)) and np.all(np.isfinite(mesh.normals))
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(mesh.positions[0], [0.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(mesh.positions[2], d, atol=1e-12)


def test_the_tracer_renders_a_tube_facing_minus_z():
    from cgamesh.tracer.evolved import RootFinder
    from cgamesh.tracer.render import render
    from cgamesh.tracer.world import build_world

    world = build_world(parse_scene(tube_scene("kb", [0, 0, -1], [0, 0, -1])), RootFinder("polynomial", 64))
    image = render(world, 24, 18, lambda *_: None)
    assert np.all(np.isfinite(image)) and image.max() > image.min()
