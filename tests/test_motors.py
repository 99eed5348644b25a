"""Motor interpolation (docs/interpolation.md): circles carried by a splined similarity motion.

Checked against the definitions, not against the code's own read-outs: rings against the
circles (c(t), n(t), r(t)) of the motion, blades against clifford's read-out, the motion
against the TRS versor of paper section 11, normals against finite differences of the mesh's
own positions, tangent continuity on the mesh, and the tracer against the mesh.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from normal_differences import assert_normals_match_differences

from cgamesh.errors import InvalidInputError
from cgamesh.geometry.algebra import rotors
from cgamesh.geometry.objects import circle_euclidean, circle_from_center_normal_radius
from cgamesh.inputs.scene import CircleControl, Location, SurfaceSpec, load_scene
from cgamesh.material import Material
from cgamesh.meshing.circles import mesh_circle_surface
from cgamesh.pipelines.scene import Resolution, build_surface, mesh_scene, mesh_surface
from cgamesh.tracer.evolved import TracedSurface
from cgamesh.tracer.roots import RootFinder
from cgamesh.tracer.verify import check_vertices
from cgamesh.tracer.world import surface_from_spec
from cgamesh_cli.main import main

HERE = Location("motor.yaml", 1, "surfaces[0]")
EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "motor_tube.yaml"
KINDS = ("linear", "bezier", "rational_bezier", "kb", "catmull_rom")
PROPERTIES = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
AXES = [tuple(float(v) for v in row) for row in np.vstack([np.eye(3), -np.eye(3)])]


def motor_spec(centres, normals, radii, curve="catmull_rom", closed=False, align=True, caps=False,
               weights=None, tension=0.0, bias=0.0, continuity=0.0, interpolation="motor") -> SurfaceSpec:
    weights = [1.0] * len(radii) if weights is None else weights
    controls = tuple(CircleControl(tuple(map(float, c)), tuple(map(float, n)), float(r), None, float(w), HERE)
                     for c, n, r, w in zip(centres, normals, radii, weights))
    return SurfaceSpec("motor", "circles", curve, tension, bias, continuity, closed, align, controls, 16, 32,
                       None, caps, Material(), HERE, interpolation=interpolation)


def circle_distance(points, centre, normal, radius):
    """Distances (K, M) of points (K, M, 3) from circles (K, 3), (K, 3), (K,)."""
    offset = points - centre[:, None, :]
    height = np.einsum("kmi,ki->km", offset, normal)
    in_plane = np.linalg.norm(offset - height[..., None] * normal[:, None, :], axis=-1)
    return np.hypot(height, in_plane - radius[:, None])


def bent_tube(rng, count, spacing=6.0, turn=0.6):
    """Sparse samples of a bending tube (steps of ``spacing`` radii), normals along the path."""
    direction = np.array([0.0, 0.0, 1.0])
    centres, normals = [], []
    point = np.zeros(3)
    for _ in range(count):
        centres.append(point.copy())
        normals.append(direction.copy())
        direction = direction + turn * rng.normal(size=3)
        direction /= np.linalg.norm(direction)
        point = point + spacing * rng.uniform(0.6, 1.4) * direction
    return np.array(centres), np.array(normals), rng.uniform(0.6, 1.2, size=count)


# --- the scene key ---------------------------------------------------------------------------------

def _scene(tmp_path, body: str) -> Path:
    path = tmp_path / "scene.yaml"
    path.write_text("cgamesh: 1\nsurfaces:\n" + body)
    return path


CIRCLES = """  - name: tube
    type: circles
    curve: linear
{extra}    controls:
      - {{center: [0, 0, 0], normal: [0, 0, 1], radius: 1}}
      - {{center: [0, 0, 4], normal: [0, 0, 1], radius: 2}}
"""


def test_the_scene_key_defaults_to_blade_and_accepts_motor(tmp_path):
    assert load_scene(_scene(tmp_path, CIRCLES.format(extra=""))).surfaces[0].interpolation == "blade"
    spec = load_scene(_scene(tmp_path, CIRCLES.format(extra="    interpolation: motor\n"))).surfaces[0]
    assert spec.interpolation == "motor"
    assert type(build_surface(spec)).__name__ == "MotorSurface"


def test_an_unknown_interpolation_is_a_one_line_error(tmp_path, capsys):
    path = _scene(tmp_path, CIRCLES.format(extra="    interpolation: screw\n"))
    assert main([str(path), "-o", str(tmp_path / "out.glb")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "scene.yaml:6: surfaces[0].interpolation" in err and "motor" in err
    assert not (tmp_path / "out.glb").exists()


def test_point_pairs_refuse_motor_saying_why(tmp_path, capsys):
    body = """  - name: ribbon
    type: point_pairs
    curve: linear
    interpolation: motor
    controls:
      - {a: [0, 0, 0], b: [1, 0, 0]}
      - {a: [0, 0, 1], b: [1, 0, 1]}
"""
    assert main([str(_scene(tmp_path, body)), "-o", str(tmp_path / "out.glb")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "surfaces[0].interpolation must be blade for type point_pairs" in err


# --- the motion ------------------------------------------------------------------------------------

@pytest.mark.parametrize("curve", KINDS)
def test_rates_and_blade_derivatives_match_central_differences(curve):
    rng = np.random.default_rng(3)
    spec = motor_spec(*bent_tube(rng, 5, spacing=3.0), curve=curve, weights=[1.0, 2.0, 0.5, 1.5, 1.0])
    surface = build_surface(spec)
    # off the nodes: a chord-length spline's t-rate changes there (its direction does not)
    t = (np.arange(surface.segment_count)[:, None] + np.array([0.17, 0.5, 0.83])).ravel()
    h = 1e-6
    state, plus, minus = (surface.path.evaluate(t + d) for d in (0.0, h, -h))
    for rate, name in ((state.d_centre, "centre"), (state.d_normal, "normal")):
        difference = (getattr(plus, name) - getattr(minus, name)) / (2 * h)
        np.testing.assert_allclose(rate, difference, atol=1e-6 * np.abs(rate).max())
    np.testing.assert_allclose(state.d_radius, (plus.radius - minus.radius) / (2 * h), atol=1e-7)
    sample = surface.sample(t)
    difference = (surface.sample(t + h).blades - surface.sample(t - h).blades) / (2 * h)
    np.testing.assert_allclose(sample.derivatives, difference, atol=1e-6 * np.abs(sample.derivatives).max())


def test_blades_are_the_motion_s_circles_by_clifford(oracle):
    rng = np.random.default_rng(4)
    surface = build_surface(motor_spec(*bent_tube(rng, 4), curve="kb", tension=0.3))
    t = np.linspace(0.0, surface.segment_count, 9)
    state = surface.path.evaluate(t)
    blades = surface.sample(t).blades
    for k in range(len(t)):
        centre, normal, radius = oracle.circle_euclidean(oracle.mv(blades[k]))
        np.testing.assert_allclose(centre, state.centre[k], atol=1e-12)
        assert abs(abs(np.dot(normal, state.normal[k])) - 1.0) < 1e-12
        assert radius == pytest.approx(state.radius[k], rel=1e-12)


def test_every_circle_is_the_unit_circle_carried_by_a_trs_versor(oracle):
    """C(t) = Z C_unit ~Z with Z = T(c) D(r) R, R e3 ~R = n (paper section 11): a similarity."""
    rng = np.random.default_rng(5)
    surface = build_surface(motor_spec(*bent_tube(rng, 4), curve="catmull_rom"))
    t = np.linspace(0.0, surface.segment_count, 7)
    state = surface.path.evaluate(t)
    versors = rotors.trs_versor(state.centre, rotors.rotation_between(np.array([0.0, 0.0, 1.0]), state.normal),
                                state.radius)
    unit = oracle.mv(circle_from_center_normal_radius(np.zeros(3), np.array([0.0, 0.0, 1.0]), 1.0))
    blades = surface.sample(t).blades
    for k in range(len(t)):
        z = oracle.mv(versors[k])
        carried = z * unit * ~z
        carried = carried / math.sqrt((carried * carried)[()])
        np.testing.assert_allclose(carried.value, blades[k], atol=1e-12)


@pytest.mark.parametrize("curve, closed", [("linear", False), ("kb", False), ("catmull_rom", False),
                                           ("kb", True), ("catmull_rom", True)])
def test_rings_pass_exactly_through_every_control_circle(curve, closed):
    rng = np.random.default_rng(6)
    centres, normals, radii = bent_tube(rng, 5)
    centres = centres + np.array([1e3, -2e3, 5e2])  # away from the origin too
    spec = motor_spec(centres, normals, radii, curve=curve, closed=closed, tension=0.2, bias=-0.3)
    surface = build_surface(spec)
    segments = surface.segment_count
    along = 4 * segments + 1  # rings exactly at every node
    mesh = mesh_circle_surface(surface, 24, along, closed=closed)
    grid = mesh.positions.reshape(along, 25, 3)[::4][:len(centres)]
    size = surface.frame.scale
    distance = circle_distance(grid, centres, normals / np.linalg.norm(normals, axis=1, keepdims=True), radii)
    assert distance.max() <= 1e-12 * size + 8 * np.finfo(float).eps * 2.5e3


def test_bezier_kinds_pass_through_their_end_controls():
    rng = np.random.default_rng(7)
    centres, normals, radii = bent_tube(rng, 4)
    for curve in ("bezier", "rational_bezier"):
        surface = build_surface(motor_spec(centres, normals, radii, curve=curve, weights=[1.0, 3.0, 0.2, 1.0]))
        state = surface.circles(np.array([0.0, 1.0]))
        np.testing.assert_allclose(state.centre, centres[[0, -1]], atol=1e-12 * surface.frame.scale)
        np.testing.assert_allclose(state.radius, radii[[0, -1]], rtol=1e-12)
        assert np.allclose(np.abs(np.einsum("ki,ki->k", state.normal, normals[[0, -1]])), 1.0, atol=1e-12)


# --- straight coaxial controls: no bulge ----------------------------------------------------------

@pytest.mark.parametrize("curve", KINDS)
def test_straight_coaxial_controls_give_a_straight_tube_moving_monotonically_between_radii(curve):
    radii = np.array([0.25, 0.3, 0.5, 0.5, 0.2])
    z = np.array([0.0, 4.0, 6.0, 14.0, 30.0])  # steps of 8 to 80 radii, uneven
    centres = np.stack([np.zeros(5), np.zeros(5), z], axis=1)
    normals = np.tile([0.0, 0.0, 1.0], (5, 1))
    normals[2] = -normals[2]  # a circle has no side: the motion must not turn it over
    surface = build_surface(motor_spec(centres, normals, radii, curve=curve))
    t = np.linspace(0.0, surface.segment_count, 2001)
    state = surface.circles(t)
    size = surface.frame.scale
    assert np.abs(state.centre[:, :2]).max() <= 1e-9 * size
    assert np.all(np.abs(state.normal[:, 2]) == pytest.approx(1.0, abs=1e-12))
    if curve in ("bezier", "rational_bezier"):
        assert state.radius.min() >= radii.min() * (1 - 1e-12) and state.radius.max() <= radii.max() * (1 + 1e-12)
        return
    for i in range(len(radii) - 1):
        span = state.radius[(t >= i) & (t <= i + 1)]
        steps = np.diff(span) * np.sign(radii[i + 1] - radii[i])
        assert np.all(steps >= -1e-15), f"radius not monotone on span {i}"
        assert span.min() >= min(radii[i], radii[i + 1]) * (1 - 1e-12)
        assert span.max() <= max(radii[i], radii[i + 1]) * (1 + 1e-12)


def test_the_blade_version_of_the_same_controls_bulges():
    """The comparison the motor fixes: two coaxial unit circles 4 apart give a middle circle of
    radius sqrt(1 + (d / 2r)^2) = sqrt(5) by blade interpolation, 1 by motor."""
    centres, normals = [[0, 0, 0], [0, 0, 4]], [[0, 0, 1], [0, 0, 1]]
    blade = build_surface(motor_spec(centres, normals, [1.0, 1.0], curve="linear", interpolation="blade"))
    motor = build_surface(motor_spec(centres, normals, [1.0, 1.0], curve="linear"))
    _, _, blade_radius = circle_euclidean(blade.sample(np.array([0.5])).blades)
    assert blade_radius[0] * blade.frame.scale == pytest.approx(math.sqrt(5.0), rel=1e-12)
    assert motor.circles(np.array([0.5])).radius[0] == pytest.approx(1.0, rel=1e-14)


# --- meshes over the input space -------------------------------------------------------------------

normal_strategy = st.one_of(st.sampled_from(AXES),
                            st.tuples(*(st.floats(-1.0, 1.0),) * 3).filter(lambda v: np.linalg.norm(v) > 0.1))


@PROPERTIES
@given(normals=st.lists(normal_strategy, min_size=4, max_size=4), curve=st.sampled_from(KINDS),
       closed=st.booleans(), caps=st.booleans(), align=st.booleans(), seed=st.integers(0, 2**32 - 1))
def test_meshes_lie_on_their_circles_with_unit_normals_matching_differences(normals, curve, closed, caps, align,
                                                                           seed):
    """Orientations include exact +-axes and antiparallel neighbours; without align a Bezier
    curve's normals may cancel, which must be the documented one-line error."""
    closed = closed and curve in ("kb", "catmull_rom")
    caps = caps and not closed
    rng = np.random.default_rng(seed)
    centres, _, radii = bent_tube(rng, 4, spacing=3.0)
    spec = motor_spec(centres, normals, radii, curve=curve, closed=closed, caps=caps, align=align,
                      weights=list(rng.uniform(0.3, 3.0, size=4)))
    surface = build_surface(spec)
    around, along = 12, 40
    try:
        surface.check_projection_exists()
    except InvalidInputError as error:
        assert not align and "motor" in str(error) and "\n" not in str(error)
        return
    mesh = mesh_circle_surface(surface, around, along, caps=caps, closed=closed)
    assert np.all(np.isfinite(mesh.positions)) and np.all(np.isfinite(mesh.normals))
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-12)
    t = np.linspace(0.0, surface.segment_count, along)
    state = surface.circles(t)
    grid = mesh.positions[: along * (around + 1)].reshape(along, around + 1, 3)
    assert circle_distance(grid, state.centre, state.normal, state.radius).max() <= 1e-12 * surface.frame.scale
    # normals orthogonal to the circle's tangent n x (x - c)
    normals_grid = mesh.normals[: along * (around + 1)].reshape(along, around + 1, 3)
    tangent = np.cross(state.normal[:, None, :], grid - state.centre[:, None, :])
    tangent /= np.linalg.norm(tangent, axis=-1, keepdims=True)
    assert np.abs(np.einsum("kmi,kmi->km", tangent, normals_grid)).max() <= 1e-9
    assert_normals_match_differences(surface, around)
    assert mesh.uvs.min() >= 0.0 and mesh.uvs.max() <= 1.0
    if closed:
        assert np.array_equal(grid[0], grid[-1])


def test_normals_are_orthogonal_to_the_motion_s_point_velocity():
    """The normal is the circle's tangent crossed with the similarity's point velocity
    v(x) = c' + omega x (x - c) + (r'/r)(x - c): it is orthogonal to v."""
    rng = np.random.default_rng(8)
    surface = build_surface(motor_spec(*bent_tube(rng, 5), curve="catmull_rom"))
    along, around = 50, 16
    t = np.linspace(0.0, surface.segment_count, along)
    mesh = mesh_circle_surface(surface, around, along)
    state = surface.circles(t)
    grid = mesh.positions.reshape(along, around + 1, 3)
    normals = mesh.normals.reshape(along, around + 1, 3)
    velocity = state.velocity(grid)
    cosine = np.einsum("kmi,kmi->km", velocity, normals) / np.linalg.norm(velocity, axis=-1)
    assert np.abs(cosine).max() <= 1e-9


@pytest.mark.parametrize("curve, smooth", [("catmull_rom", True), ("kb", True), ("linear", False)])
def test_tangent_continuity_across_nodes_measured_on_the_mesh(curve, smooth):
    """Quads just before and just after a node: their planes meet at an angle that vanishes with
    the step for C1 curves (the mesh's own crease), and stays for linear ones."""
    rng = np.random.default_rng(9)
    surface = build_surface(motor_spec(*bent_tube(rng, 4, spacing=4.0, turn=0.8), curve=curve, bias=0.3))
    around = 24
    creases = []
    for step in (1e-3, 1e-4):
        t = np.array([1.0 - step, 1.0, 1.0 + step, 2.0 - step, 2.0, 2.0 + step])
        mesh = mesh_circle_surface(surface, around, t=t)
        grid = mesh.positions.reshape(6, around + 1, 3)
        worst = 0.0
        for node in (1, 4):
            before, after = grid[node] - grid[node - 1], grid[node + 1] - grid[node]
            along_ring = np.roll(grid[node], -1, axis=0) - np.roll(grid[node], 1, axis=0)
            n1, n2 = np.cross(along_ring, before), np.cross(along_ring, after)
            cosine = np.einsum("mi,mi->m", n1, n2) / (np.linalg.norm(n1, axis=1) * np.linalg.norm(n2, axis=1))
            worst = max(worst, float(np.degrees(np.arccos(np.clip(cosine[:-1], -1.0, 1.0))).max()))
        creases.append(worst)
    if smooth:
        assert creases[1] <= 0.05 and creases[1] <= 0.2 * creases[0] + 1e-3, creases
    else:
        assert creases[1] >= 1.0, creases


# --- turns, orientation, coincident nodes ---------------------------------------------------------

def test_a_half_turn_in_one_span_turns_towards_the_direction_of_travel():
    """Antiparallel normals on one span (align false keeps them): the middle ring's normal is the
    chord between the centres, and no ring loses its plane."""
    spec = motor_spec([[0, 0, 0], [0, 3, 0]], [[1, 0, 0], [-1, 0, 0]], [0.5, 0.5], curve="linear", align=False)
    surface = build_surface(spec)
    state = surface.circles(np.linspace(0.0, 1.0, 101))
    np.testing.assert_allclose(state.normal[50], [0.0, 1.0, 0.0], atol=1e-12)
    assert np.all(state.normal[:, 1] >= -1e-12)  # one way round, never back
    mesh = mesh_circle_surface(surface, 16, 64)
    assert np.all(np.isfinite(mesh.normals))


def test_align_keeps_rings_across_sharp_bends_instead_of_folding_them_back():
    """Two 100-degree turns in a row, normals along the path (bisectors at the nodes): nodes 1 and 2
    are 100 degrees apart. The shortest rotation would turn node 2 over and tilt the rings back
    by 80 degrees across the path; the motion keeps every normal on the side of travel."""
    heading = np.radians([0.0, 100.0, 200.0])
    steps = 4.0 * np.stack([np.cos(heading), np.sin(heading), np.zeros(3)], axis=1)
    centres = np.vstack([np.zeros(3), np.cumsum(steps, axis=0)])
    bisectors = np.radians([0.0, 50.0, 150.0, 200.0])
    normals = np.stack([np.cos(bisectors), np.sin(bisectors), np.zeros(4)], axis=1)
    for curve in ("linear", "catmull_rom"):
        surface = build_surface(motor_spec(centres, normals, [0.4] * 4, curve=curve))
        np.testing.assert_allclose(surface.circles(np.arange(4.0)).normal, normals, atol=1e-12)
        # every ring's normal keeps a positive component along the path's direction of travel
        t = np.linspace(0.0, 3.0, 301)
        state = surface.circles(t)
        assert np.all(np.einsum("ki,ki->k", state.normal, state.d_centre) > 0.0)


@pytest.mark.parametrize("gap", [0.0, 1e-9, 1e-6])
def test_coincident_and_nearly_coincident_nodes_mesh_without_nan(gap):
    rng = np.random.default_rng(10)
    centres, normals, radii = bent_tube(rng, 4)
    centres[2] = centres[1] + gap * np.array([0.3, -0.2, 0.9])
    normals[2], radii[2] = normals[1], radii[1] * (1 + gap)
    spec = motor_spec(centres, normals, radii, curve="catmull_rom", caps=True)
    mesh = mesh_surface(spec, Resolution(around=12, along=48))
    assert np.all(np.isfinite(mesh.positions)) and np.all(np.isfinite(mesh.normals))
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-12)


# --- tolerance, tracer, exports --------------------------------------------------------------------

def test_tolerance_driven_meshing_meets_its_tolerance_on_motor_surfaces():
    rng = np.random.default_rng(11)
    spec = motor_spec(*bent_tube(rng, 5), curve="catmull_rom")
    surface = build_surface(spec)
    tolerance = 1e-3 * surface.frame.scale
    mesh = mesh_surface(spec, Resolution(tolerance=tolerance))
    assert mesh.max_deviation <= tolerance
    # and independently: dense points of the mesh's triangles lie near the motion's circles
    corners = mesh.positions[mesh.faces]
    centroids = corners.mean(axis=1)
    t = np.linspace(0.0, surface.segment_count, 4001)
    state = surface.circles(t)
    nearest = np.full(len(centroids), np.inf)
    for k in range(0, len(t), 200):
        part = slice(k, k + 200)
        distance = circle_distance(np.broadcast_to(centroids, (len(t[part]),) + centroids.shape),
                                   state.centre[part], state.normal[part], state.radius[part])
        nearest = np.minimum(nearest, distance.min(axis=0))
    assert nearest.max() <= 1.05 * tolerance


@pytest.mark.parametrize("kind, samples", [("polynomial", 64), ("sampled", 64), ("sampled", 16)])
def test_tracer_hits_the_mesh_vertices_of_a_motor_surface(kind, samples):
    """Every vertex found, on the surface, normals agreeing, with either finder: the sampled one
    at its default 64 samples per segment and at 16, far fewer than the mesh's rings (the ray
    along a vertex normal meets the tube twice within a fraction of a step: a pair of roots
    that the samples only touch, polished apart by deflation)."""
    rng = np.random.default_rng(12)
    spec = motor_spec(*bent_tube(rng, 4), curve="kb", caps=True, continuity=0.2)
    mesh = mesh_surface(spec, Resolution(around=16, along=64))
    traced = TracedSurface(surface_from_spec(spec), caps=True, finder=RootFinder(kind, samples))
    check = check_vertices(traced, mesh.positions, mesh.normals)
    assert not np.any(check.missed)
    assert np.nanmax(check.distance) <= 1e-9 and np.nanmax(check.angle) <= 0.1


def closed_loop(count: int = 5, loop_radius: float = 6.0):
    """Controls around a ring of radius ``loop_radius`` (a torus-like loop), normals along it,
    radii varying between 0.6 and 1.2, the plane of the loop tilted off every axis."""
    angle = 2.0 * np.pi * np.arange(count) / count
    axis, turn = np.array([0.6, 0.8, 0.0]), 0.7  # Rodrigues: a turn of 0.7 rad about a tilted axis
    cross = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    tilt = np.eye(3) + np.sin(turn) * cross + (1.0 - np.cos(turn)) * cross @ cross
    centres = loop_radius * np.stack([np.cos(angle), np.sin(angle), 0.2 * np.sin(2 * angle)], axis=1) @ tilt.T
    normals = np.stack([-np.sin(angle), np.cos(angle), np.zeros(count)], axis=1) @ tilt.T
    return centres, normals, 0.9 + 0.3 * np.sin(3 * angle)


MOTOR_VERIFY_CASES = [(curve, False) for curve in KINDS] + [(curve, True) for curve in ("kb", "catmull_rom")]


@pytest.mark.parametrize("curve, closed", MOTOR_VERIFY_CASES)
def test_verify_with_the_sampled_finder_passes_motor_surfaces(curve, closed):
    """The whole of ``verify`` (every vertex traced, distance, angle, settling, sign breaks,
    outward) with ``--root-finder sampled`` at its default samples passes the mesh of every
    curve kind's motor surface, open with caps and closed; and it can fail: the same mesh with
    its rings pushed out by 1% fails the distance threshold."""
    from cgamesh.tracer.verify import check_mesh

    if closed:
        centres, normals, radii = closed_loop()
    else:
        centres, normals, radii = bent_tube(np.random.default_rng(21), 4)
    weights = [1.0, 3.0, 0.5, 1.0] if curve == "rational_bezier" else None
    spec = motor_spec(centres, normals, radii, curve=curve, closed=closed, caps=not closed, weights=weights,
                      tension=0.3 if curve == "kb" else 0.0, continuity=-0.2 if curve == "kb" else 0.0)
    mesh = mesh_surface(spec, Resolution(around=16, along=48))
    traced = TracedSurface(surface_from_spec(spec), caps=not closed, finder=RootFinder("sampled"))
    report = check_mesh(traced, mesh)
    assert report.passed, report
    assert report.missed == 0.0 and report.sign_breaks == 0 and report.outward
    surface = build_surface(spec)
    t = np.repeat(np.linspace(0.0, surface.segment_count, 48), 17)
    grid = mesh.positions[:48 * 17]
    state = surface.circles(t)
    pushed = mesh.positions.copy()
    pushed[:48 * 17] = grid + 0.01 * (grid - state.centre)
    assert not check_mesh(traced, dataclasses.replace(mesh, positions=pushed)).passed


def test_verify_command_takes_the_sampled_finder_on_the_motor_example(tmp_path, capsys):
    glb = tmp_path / "motor.glb"
    assert main([str(EXAMPLE), "-o", str(glb), "--around", "16", "--along", "64", "-q"]) == 0
    capsys.readouterr()
    assert main(["verify", str(EXAMPLE), str(glb), "--root-finder", "sampled"]) == 0, capsys.readouterr().out
    out = capsys.readouterr().out
    assert out.count(" pass") == 2 and "FAIL" not in out


def test_the_motor_example_renders_and_verifies(tmp_path, capsys):
    glb = tmp_path / "motor.glb"
    assert main([str(EXAMPLE), "-o", str(glb), "--around", "16", "--along", "64", "-q"]) == 0
    assert main(["verify", str(EXAMPLE), str(glb)]) == 0, capsys.readouterr().out
    image = tmp_path / "motor.png"
    assert main(["render", str(EXAMPLE), "-o", str(image), "--size", "64x48", "-q"]) == 0
    from cgamesh.tracer.png import read_png

    pixels = read_png(image)
    assert np.count_nonzero(pixels.reshape(-1, pixels.shape[-1]).max(axis=1) > 0.0) > 20


def test_the_motor_example_exports_usd_that_passes_the_checker(tmp_path):
    from export_checks import check_usd_file, pxr_or_skip

    pxr_or_skip()
    scene = load_scene(EXAMPLE)
    meshes = mesh_scene(scene, Resolution(16, 64))
    for suffix in (".usda", ".usdz"):
        out = tmp_path / f"motor{suffix}"
        assert main([str(EXAMPLE), "-o", str(out), "--around", "16", "--along", "64", "-q"]) == 0
        check_usd_file(out, meshes, up=scene.up, meters_per_unit=scene.meters_per_unit)


def test_motor_surfaces_are_refused_where_the_normal_spline_vanishes():
    """Bezier normals that cancel (+z to -z, align false keeps them): (1 - 2t) e3 is zero at t = 1/2,
    a one-line error naming the surface, as a vanishing projection is for blade surfaces."""
    spec = motor_spec([[0, 0, 0], [0, 0, 1]], [[0, 0, 1], [0, 0, -1]], [1.0, 1.0], curve="bezier", align=False)
    with pytest.raises(InvalidInputError) as raised:
        mesh_surface(spec, Resolution(around=8, along=16))
    message = str(raised.value)
    assert "motor" in message and "alpha = 0.5" in message and "\n" not in message


@pytest.mark.parametrize("interpolation", ["blade", "motor"])
def test_a_first_circle_facing_exactly_down_meshes(interpolation):
    """The first ring's frame turns e3 onto its normal; exactly -e3 is a half turn (regression)."""
    spec = motor_spec([[0, 0, 0], [0, 0, -2]], [[0, 0, -1], [0, 0, -1]], [1.0, 1.0], curve="linear",
                      interpolation=interpolation)
    mesh = mesh_surface(spec, Resolution(around=8, along=4))
    assert np.all(np.isfinite(mesh.positions)) and np.all(np.isfinite(mesh.normals))


@PROPERTIES
@given(log_scale=st.floats(-4.0, 4.0), distance=st.floats(0.0, 1e5), curve=st.sampled_from(KINDS),
       seed=st.integers(0, 2**32 - 1))
def test_any_size_anywhere(log_scale, distance, curve, seed):
    """Radii from 1e-4 to 1e4, centres up to 1e5 from the origin: vertices on the motion's circles
    within 1e-9 of the size (or the spacing of float64 numbers at the coordinates), unit normals."""
    rng = np.random.default_rng(seed)
    scale = 10.0**log_scale
    centres, normals, radii = bent_tube(rng, 4, spacing=3.0)
    offset = distance * rng.normal(size=3) / math.sqrt(3.0)
    surface = build_surface(motor_spec(scale * centres + offset, normals, scale * radii, curve=curve))
    along, around = 16, 8
    mesh = mesh_circle_surface(surface, around, along)
    assert np.all(np.isfinite(mesh.positions)) and np.all(np.isfinite(mesh.normals))
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-12)
    state = surface.circles(np.linspace(0.0, surface.segment_count, along))
    grid = mesh.positions.reshape(along, around + 1, 3)
    representable = 4.0 * np.finfo(float).eps * np.abs(grid).max()
    distance_off = circle_distance(grid, state.centre, state.normal, state.radius).max()
    assert distance_off <= 1e-9 * surface.frame.scale + representable


def test_the_tracer_traces_motor_surfaces_without_the_mesher():
    """The tracer is the mesher's independent referee: rendering a motor scene imports no meshing."""
    import subprocess
    import sys

    code = ("import sys; from cgamesh.inputs.scene import load_scene; from cgamesh.tracer.world import build_world; "
            "from cgamesh.tracer.render import render; "
            f"world = build_world(load_scene({str(EXAMPLE)!r})); render(world, 16, 12); "
            "print(sorted(m for m in sys.modules if m.startswith('cgamesh.meshing')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_centreline_inputs_are_meshed_with_motor_interpolation(tmp_path):
    """Streamlines, skeletons and arrays default to motor: two samples 10 radii apart give rings
    of the sample radius all along (blade circles would balloon to sqrt(1 + 5^2) = 5.1 radii
    half-way), through the Python API and an SWC file alike."""
    import cgamesh
    from cgamesh.pipelines.centerlines import TubeOptions, mesh_centerlines
    from cgamesh.inputs.swc import read_swc

    points = np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [20.0, 3.0, 0.0]])
    meshes = cgamesh.tubes([points], radii=1.0, around=8, subdivide=7, split=True)
    rings = meshes.positions.reshape(-1, 9, 3)[:, :-1]
    radius = np.linalg.norm(rings - rings.mean(axis=1, keepdims=True), axis=2)
    np.testing.assert_allclose(radius, 1.0, rtol=1e-9)
    swc = tmp_path / "two.swc"
    swc.write_text("1 3 0 0 0 1 -1\n2 3 10 0 0 1 1\n3 3 20 3 0 1 2\n")
    built = mesh_centerlines(read_swc(swc), TubeOptions(around=8, subdivide=7, split=True))
    grid = built.meshes[0].positions[: 17 * 9].reshape(17, 9, 3)[:, :-1]
    np.testing.assert_allclose(np.linalg.norm(grid - grid.mean(axis=1, keepdims=True), axis=2), 1.0, rtol=1e-9)


def test_a_linear_motor_span_between_equal_controls_is_dropped_as_for_blade():
    """A repeated control on a linear curve is one circle, not a span of no area (the input-space
    property found a zero normal there: a ring on the stationary span, with numpy warnings as
    errors): the surface is that of the controls without the repeat, ring for ring."""
    import warnings

    centres = [[0, 0, 0], [0, 0, 0], [1.34, 0, 0.67], [2.4, 0, 1.73]]
    normals = [[1, 0, 0]] * 4
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        repeated = mesh_surface(motor_spec(centres, normals, [1.0] * 4, curve="linear", align=False),
                                Resolution(around=3, along=2))
        single = mesh_surface(motor_spec(centres[1:], normals[1:], [1.0] * 3, curve="linear", align=False),
                              Resolution(around=3, along=2))
    np.testing.assert_allclose(repeated.positions, single.positions, atol=1e-12)
    np.testing.assert_allclose(repeated.normals, single.normals, atol=1e-12)
