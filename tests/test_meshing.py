"""cgamesh.meshing.circles: grid vertices on the true circles, analytic normals, winding, seams, UVs, caps.

The reference is computed independently, object by object, with clifford (the ``oracle``
fixture): the interpolant from the paper's curve formulas (``paper_weights``), projected with
eqs. 10-12 written out in clifford, read out with clifford's ``get_circle_in_euc``. Finite
differences of positions come from the reference circles too: the neighbours of a vertex x
on C(t) are the points of C(t +- h) in the plane through x normal to the circle's tangent.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest

from cgamesh.geometry.algebra import rotors
from cgamesh.meshing.circles import mesh_circle_surface
from cgamesh.pipelines.scene import build_surface
from cgamesh.inputs.scene import parse_scene
from cgamesh.geometry.surface import CircleRings

AROUND = 32
ALONG = 60  # 59 rings steps: prime, so no interior ring sits on a segment joint
H = 1e-5  # finite-difference step in t
NORMAL_DEGREES = 0.1


def _scene(curve, controls, extra="", name="tube"):
    lines = "\n".join(f"      - {c}" for c in controls)
    return f"cgamesh: 1\nsurfaces:\n  - name: {name}\n    type: circles\n    curve: {curve}\n{extra}    controls:\n{lines}\n"


def _circle(centre, normal, radius, weight=None):
    tail = f", weight: {weight!r}" if weight is not None else ""
    return f"{{center: {_vector(centre)}, normal: {_vector(normal)}, radius: {float(radius)!r}{tail}}}"


def _vector(v):
    return "[" + ", ".join(repr(float(x)) for x in v) + "]"


def _gentle_tube(count, step=1.0):
    """Circles along a gently bending path, normals along the path, radii well below the bends."""
    s = np.arange(count, dtype=np.float64)
    centres = np.stack([0.9 * np.sin(0.45 * s), 0.3 * np.sin(0.3 * s), 0.9 * s], axis=1) * step
    tangents = np.gradient(centres, axis=0)
    radii = 0.25 + 0.05 * np.cos(1.3 * s)
    return centres, tangents, radii


def _tube_controls(count, weights=None, step=1.0):
    centres, tangents, radii = _gentle_tube(count, step)
    return [_circle(c, n, r, None if weights is None else weights[i])
            for i, (c, n, r) in enumerate(zip(centres, tangents, radii))]


def _loop_controls(count=7):
    phi = 2 * np.pi * np.arange(count) / count
    centres = np.stack([2.0 * np.cos(phi), 2.0 * np.sin(phi), 0.3 * np.sin(2 * phi)], axis=1)
    normals = np.stack([-np.sin(phi), np.cos(phi), 0.3 * np.cos(2 * phi)], axis=1)
    radii = 0.35 + 0.08 * np.cos(phi)
    return [_circle(c, n, r) for c, n, r in zip(centres, normals, radii)]


TUBES = {
    # Linear splines crease at their controls; with circles 0.9 apart (more than their
    # diameters) the two sides' normals there differ by more than 90 degrees.
    "linear": _scene("linear", _tube_controls(3)),
    "linear_close": _scene("linear", _tube_controls(4, step=0.4)),
    "bezier3": _scene("bezier", _tube_controls(4)),
    "rational_bezier": _scene("rational_bezier", _tube_controls(4, [1.0, 2.5, 0.6, 1.0])),
    "kb": _scene("kb", _tube_controls(5), "    tension: 0.2\n    bias: -0.3\n    continuity: 0.25\n"),
    "catmull_rom": _scene("catmull_rom", _tube_controls(5)),
    "catmull_rom_closed": _scene("catmull_rom", _loop_controls(), "    closed: true\n"),
}


# --- the reference -------------------------------------------------------------------------------

def _weights_function(spec, paper_weights):
    kwargs = dict(tension=spec.tension, bias=spec.bias, continuity=spec.continuity, closed=spec.closed,
                  weights=[c.weight for c in spec.controls])
    return lambda t: paper_weights(spec.curve, len(spec.controls), np.asarray(t, dtype=np.float64), **kwargs)


def _points_in_normal_planes(x, tangent, centre, normal, radius):
    """The point of each circle (K,) nearest x (K, M, 3) in the plane through x normal to ``tangent``."""
    helper = np.where(np.abs(normal[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    a = np.cross(helper, normal)
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b = np.cross(normal, a)
    # (c + r (cos p a + sin p b) - x) . tangent = 0  <=>  A cos p + B sin p = -D
    A = radius[:, None] * np.einsum("kmi,ki->km", tangent, a)
    B = radius[:, None] * np.einsum("kmi,ki->km", tangent, b)
    D = np.einsum("kmi,kmi->km", centre[:, None] - x, tangent)
    phase, spread = np.arctan2(B, A), np.arccos(np.clip(-D / np.hypot(A, B), -1.0, 1.0))
    candidates = [
        centre[:, None] + radius[:, None, None] * (np.cos(p)[..., None] * a[:, None] + np.sin(p)[..., None] * b[:, None])
        for p in (phase + spread, phase - spread)
    ]
    closer = np.linalg.norm(candidates[0] - x, axis=-1) <= np.linalg.norm(candidates[1] - x, axis=-1)
    return np.where(closer[..., None], candidates[0], candidates[1])


@dataclass
class Meshed:
    """A meshed surface with its reference geometry on the (ring, column) grid."""

    name: str
    spec: object
    surface: object
    mesh: object
    t: np.ndarray  # (K,)
    positions: np.ndarray  # (K, M + 1, 3) grid
    normals: np.ndarray  # (K, M + 1, 3)
    centre: np.ndarray  # (K, 3) reference circles
    normal: np.ndarray  # (K, 3) unit, sign as clifford reads it
    radius: np.ndarray  # (K,)
    tangent: np.ndarray  # (K, M + 1, 3) unit circle tangents at the vertices
    along: np.ndarray  # (K, M + 1, 3) dx/dt by central differences of the reference circles
    size: float  # the diagonal of the surface's bounding box

    @property
    def grid_vertex_count(self):
        return self.positions.shape[0] * self.positions.shape[1]

    def fd_normals(self):
        """Unit tangent x dx/dt, each oriented away from its circle's centre."""
        n = np.cross(self.tangent, self.along)
        n /= np.linalg.norm(n, axis=-1, keepdims=True)
        return n * np.sign(np.einsum("kmi,kmi->km", n, self.positions - self.centre[:, None]))[..., None]


def make_meshed(name, text, oracle, paper_weights, around=AROUND, along=ALONG, caps=False):
    spec = parse_scene(text, f"{name}.yaml").surfaces[0]
    surface = build_surface(spec)
    mesh = mesh_circle_surface(surface, around, along, caps=caps, closed=spec.closed)
    weights = _weights_function(spec, paper_weights)
    end = surface.segment_count
    t = np.linspace(0.0, end, along)
    grid = along * (around + 1)
    positions = mesh.positions[:grid].reshape(along, around + 1, 3)
    normals = mesh.normals[:grid].reshape(along, around + 1, 3)
    centre, normal, radius = oracle.surface_circles(surface.controls, weights(t), surface.frame)
    offset = positions - centre[:, None]
    tangent = np.cross(normal[:, None], offset)
    tangent /= np.linalg.norm(tangent, axis=-1, keepdims=True)
    ahead, behind = np.minimum(t + H, end), np.maximum(t - H, 0.0)
    neighbours = [
        _points_in_normal_planes(positions, tangent, *oracle.surface_circles(surface.controls, weights(s), surface.frame))
        for s in (ahead, behind)
    ]
    along_tangent = (neighbours[0] - neighbours[1]) / (ahead - behind)[:, None, None]
    size = float(np.linalg.norm(np.ptp(mesh.positions, axis=0)))
    return Meshed(name, spec, surface, mesh, t, positions, normals, centre, normal, radius, tangent,
                  along_tangent, size)


@pytest.fixture(scope="module", params=list(TUBES), ids=list(TUBES))
def tube(request, oracle, paper_weights):
    return make_meshed(request.param, TUBES[request.param], oracle, paper_weights)


@pytest.fixture(scope="module")
def closed_tube(oracle, paper_weights):
    return make_meshed("catmull_rom_closed", TUBES["catmull_rom_closed"], oracle, paper_weights)


def _angles_degrees(a, b):
    return np.degrees(np.arccos(np.clip(np.einsum("...i,...i->...", a, b), -1.0, 1.0)))


def _face_normals(positions, faces):
    p = positions[faces]
    return np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])


# --- positions -----------------------------------------------------------------------------------

def test_the_reference_tubes_do_not_fold(tube):
    # The cases are meant to be well-behaved: every point moves forward along its circle's
    # normal (so the surface has no fold and its outward normal is away from the centre).
    sign = np.sign(np.einsum("ki,ki->k", tube.normal[1:], tube.centre[1:] - tube.centre[:-1]))[:, None]
    forward = np.einsum("kmi,ki->km", tube.along[1:], tube.normal[1:]) * sign
    assert forward.min() > 0.05 * np.abs(forward).max()


def test_grid_layout(tube):
    m = tube.mesh
    assert (m.positions.shape == (ALONG * (AROUND + 1), 3) and m.normals.shape == m.positions.shape
            and m.uvs.shape == (len(m.positions), 2) and m.faces.shape == (2 * (ALONG - 1) * AROUND, 3))


def test_every_vertex_lies_on_its_clifford_circle(tube):
    offset = tube.positions - tube.centre[:, None]
    radial = np.abs(np.linalg.norm(offset, axis=-1) - tube.radius[:, None])
    planar = np.abs(np.einsum("kmi,ki->km", offset, tube.normal))
    assert max(radial.max(), planar.max()) <= 1e-12 * tube.size  # measured ~2e-15


def test_columns_are_evenly_spaced_around_each_circle(tube):
    offset = tube.positions - tube.centre[:, None]
    chord = np.linalg.norm(np.diff(offset, axis=1), axis=-1)
    want = 2.0 * tube.radius[:, None] * math.sin(math.pi / AROUND)
    assert np.max(np.abs(chord - want)) <= 1e-9 * tube.size


def test_no_nan_or_infinity(tube):
    m = tube.mesh
    assert all(np.all(np.isfinite(a)) for a in (m.positions, m.normals, m.uvs))


def test_no_zero_area_triangles(tube):
    m = tube.mesh
    area = 0.5 * np.linalg.norm(_face_normals(m.positions, m.faces), axis=1)
    assert area.min() > 1e-9 * tube.size ** 2


def test_seam_column_repeats_the_first_bit_for_bit(tube):
    assert (np.array_equal(tube.positions[:, -1], tube.positions[:, 0])
            and np.array_equal(tube.normals[:, -1], tube.normals[:, 0]))


def test_closed_loop_last_ring_repeats_the_first_bit_for_bit(closed_tube):
    assert (np.array_equal(closed_tube.positions[-1], closed_tube.positions[0])
            and np.array_equal(closed_tube.normals[-1], closed_tube.normals[0]))


# --- normals -------------------------------------------------------------------------------------

def test_normals_are_unit(tube):
    assert np.max(np.abs(np.linalg.norm(tube.mesh.normals, axis=1) - 1.0)) <= 1e-12


def test_normals_are_orthogonal_to_the_circle_tangent(tube):
    assert np.max(np.abs(np.einsum("kmi,kmi->km", tube.normals, tube.tangent))) <= 1e-9


def test_normals_are_orthogonal_to_the_along_tangent(tube):
    along = tube.along / np.linalg.norm(tube.along, axis=-1, keepdims=True)
    assert np.max(np.abs(np.einsum("kmi,kmi->km", tube.normals, along))) <= math.sin(math.radians(NORMAL_DEGREES))


def test_normals_point_away_from_the_circle_centre_at_every_vertex(tube):
    # On a tube without folds the outward normal has a positive radial part everywhere.
    outward = np.einsum("kmi,kmi->km", tube.normals, tube.positions - tube.centre[:, None])
    inward = np.unique(np.nonzero(outward <= 0.0)[0])
    assert inward.size == 0, f"{np.count_nonzero(outward <= 0.0)} inward normals on rings {inward.tolist()} " \
                             f"(t = {tube.t[inward].min() if inward.size else 0:.4g} .. {tube.t[inward].max() if inward.size else 0:.4g})"


def test_normals_sum_outward(tube):
    # The scene format's sign convention, for any circle surface.
    assert np.sum(np.einsum("kmi,kmi->km", tube.normals, tube.positions - tube.centre[:, None])) > 0.0


def test_normals_equal_outward_finite_difference_normals(tube):
    angles = _angles_degrees(tube.normals, tube.fd_normals())
    ring, column = np.unravel_index(np.argmax(angles), angles.shape)
    assert angles.max() <= NORMAL_DEGREES, f"{angles.max():.4g} degrees at ring {ring} (t = {tube.t[ring]:.4g}), " \
                                           f"column {column}; {np.count_nonzero(angles > NORMAL_DEGREES)} vertices off"


def test_triangles_wind_counter_clockwise_seen_from_their_normals(tube):
    m = tube.mesh
    dots = np.einsum("fi,fvi->fv", _face_normals(m.positions, m.faces), m.normals[m.faces])
    bad = np.flatnonzero(dots.min(axis=1) <= 0.0)
    assert bad.size == 0, f"{bad.size} triangles wind against their normals, between rings " \
                          f"{np.unique(m.faces[bad] // (AROUND + 1)).tolist()}"


# --- texture coordinates -------------------------------------------------------------------------

def test_uvs_are_in_the_unit_square(tube):
    uv = tube.mesh.uvs
    assert uv.min() >= 0.0 and uv.max() <= 1.0


def test_u_increases_around_and_v_along(tube):
    uv = tube.mesh.uvs[:tube.grid_vertex_count].reshape(ALONG, AROUND + 1, 2)
    assert (np.all(np.diff(uv[..., 0], axis=1) > 0.0) and np.all(np.diff(uv[..., 1], axis=0) > 0.0)
            and np.all(uv[:, 0, 0] == 0.0) and np.all(uv[:, -1, 0] == 1.0)
            and np.all(uv[0, :, 1] == 0.0) and np.all(uv[-1, :, 1] == 1.0))


def test_no_flipped_uv_triangles(tube):
    m = tube.mesh
    grid_faces = m.faces[np.all(m.faces < tube.grid_vertex_count, axis=1)]
    p = m.uvs[grid_faces]
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    signed = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    assert np.all(signed > 0.0) or np.all(signed < 0.0), \
        f"{np.count_nonzero(signed > 0)} UV triangles positive, {np.count_nonzero(signed < 0)} negative, " \
        f"{np.count_nonzero(signed == 0)} zero"


# --- the rotor stepping --------------------------------------------------------------------------

@pytest.mark.parametrize("name", ["linear", "bezier3", "kb"])
def test_rings_are_the_trs_versors_of_the_accumulated_rotations_applied_to_the_unit_circle(
        name, oracle, paper_weights):
    # Z_k = T(c_k) D(r_k) R_k with R_k = prod of the smallest rotations between consecutive ring
    # planes (R_0 takes e3 to the first normal); ring k = Z_k up(cos, sin, 0) ~Z_k in clifford.
    meshed = make_meshed(name, TUBES[name], oracle, paper_weights, around=12, along=40)
    rings = CircleRings.from_projection(meshed.surface.sample(meshed.t), meshed.surface.frame)
    e3 = np.array([0.0, 0.0, 1.0])
    steps = np.concatenate([rotors.rotation_between(e3, rings.normal[:1]),
                            rotors.rotation_between(rings.normal[:-1], rings.normal[1:])])
    versors = rotors.trs_versor(rings.centre, rotors.prefix_products(steps), rings.radius)
    theta = 2.0 * np.pi * np.arange(12) / 12
    unit_circle = [oracle.point([math.cos(a), math.sin(a), 0.0]) for a in theta]
    got = np.array([[oracle.down(Z * X * ~Z) for X in unit_circle] for Z in map(oracle.mv, versors)])
    assert np.max(np.abs(got - meshed.positions[:, :-1])) <= 1e-10 * meshed.size


# --- caps ----------------------------------------------------------------------------------------

@pytest.fixture(scope="module", params=["bezier3", "kb"])
def capped(request, oracle, paper_weights):
    return make_meshed(request.param, TUBES[request.param], oracle, paper_weights, caps=True)


def _caps(capped):
    """(vertex indices, face indices) of the start cap and the end cap."""
    m, start = capped.mesh, capped.grid_vertex_count
    per_cap = (len(m.positions) - start) // 2
    vertices = [np.arange(start, start + per_cap), np.arange(start + per_cap, len(m.positions))]
    faces = [np.flatnonzero(np.all(np.isin(m.faces, v), axis=1)) for v in vertices]
    return vertices, faces


def test_caps_are_flat_discs_in_the_end_circles_planes(capped):
    m = capped.mesh
    vertices, faces = _caps(capped)
    ok = []
    for ring, v, f in zip((0, -1), vertices, faces):
        offset = m.positions[v] - capped.centre[ring]
        in_plane = np.abs(offset @ capped.normal[ring]).max() <= 1e-9 * capped.size
        inside = np.linalg.norm(offset, axis=1).max() <= capped.radius[ring] * (1 + 1e-9)
        ok.append(in_plane and inside and len(f) == AROUND)
    assert all(ok)


def test_cap_normals_are_the_circle_normal_pointing_away_from_the_tube(capped):
    m = capped.mesh
    vertices, _ = _caps(capped)
    # Away from the tube: against the direction to the next ring at the start, along it at the end.
    away = [capped.centre[0] - capped.centre[1], capped.centre[-1] - capped.centre[-2]]
    ok = []
    for ring, v, direction in zip((0, -1), vertices, away):
        n = m.normals[v]
        parallel = np.abs(np.abs(n @ capped.normal[ring]) - 1.0).max() <= 1e-12
        ok.append(parallel and np.all(n @ direction > 0.0) and np.ptp(n, axis=0).max() == 0.0)
    assert all(ok)


def test_cap_triangles_wind_with_their_normals(capped):
    m = capped.mesh
    _, faces = _caps(capped)
    f = m.faces[np.concatenate(faces)]
    dots = np.einsum("fi,fvi->fv", _face_normals(m.positions, f), m.normals[f])
    assert dots.min() > 0.0


def test_cap_rims_are_the_end_rings(capped):
    m = capped.mesh
    vertices, _ = _caps(capped)
    rims = [m.positions[v] for v in vertices]
    # Each cap holds the ring's own vertices (same points, not re-computed ones) and its centre.
    assert all(
        any(np.array_equal(rim[:AROUND], ring[:AROUND]) for ring in (capped.positions[0], capped.positions[-1]))
        for rim in rims)


# --- accuracy at scale ---------------------------------------------------------------------------

DRIFT = """\
cgamesh: 1
surfaces:
  - name: drift
    type: circles
    curve: linear
    controls:
      - {center: [0.3, -0.2, 0.0], normal: [0.0, 0.0, 1.0], radius: 1.0}
      - {center: [0.3, -0.2, 0.5], normal: [0.0, 0.0, 1.0], radius: 1.0000001}
"""


def test_twenty_thousand_rings_keep_every_vertex_on_its_circle(oracle, paper_weights):
    # A scale change of 5e-12 per step: clifford's generate_dilation_rotor would treat each as
    # none (it ignores changes below 1e-5); the rings must not drift off their circles.
    along, around = 20000, 8
    spec = parse_scene(DRIFT, "drift.yaml").surfaces[0]
    surface = build_surface(spec)
    mesh = mesh_circle_surface(surface, around, along)
    t = np.linspace(0.0, 1.0, along)
    centre, normal, radius = oracle.surface_circles(surface.controls, _weights_function(spec, paper_weights)(t),
                                                    surface.frame)
    offset = mesh.positions.reshape(along, around + 1, 3) - centre[:, None]
    radial = np.abs(np.linalg.norm(offset, axis=-1) - radius[:, None])
    planar = np.abs(np.einsum("kmi,ki->km", offset, normal))
    assert max(radial.max(), planar.max()) <= 1e-12 * radius.max()


# --- characteristic points and folds: surfaces on one sphere -------------------------------------

def _on_sphere(centre, radius, polar, azimuth):
    return centre + radius * np.array([math.sin(polar) * math.cos(azimuth), math.sin(polar) * math.sin(azimuth),
                                       math.cos(polar)])


SPHERE_CENTRE = np.array([0.2, -0.1, 0.3])
SPHERE_RADIUS = 1.3


def _through(points):
    return "{through: [" + ", ".join(_vector(p) for p in points) + "]}"


def _characteristic_scene():
    # Two circles of one sphere through the same two points A, B: every interpolated circle
    # passes through A and B (characteristic points) and lies on the sphere.
    a = _on_sphere(SPHERE_CENTRE, SPHERE_RADIUS, 0.4, 0.3)
    b = _on_sphere(SPHERE_CENTRE, SPHERE_RADIUS, 2.2, 1.9)
    first = _on_sphere(SPHERE_CENTRE, SPHERE_RADIUS, 1.2, -0.6)
    second = _on_sphere(SPHERE_CENTRE, SPHERE_RADIUS, 1.5, 0.9)
    return _scene("linear", [_through([a, first, b]), _through([a, second, b])], name="lune")


def _fold_scene():
    # Small circles of one sphere whose axes sweep along a great circle, each crossing its
    # neighbours: the surface covers a band of the sphere twice, folding along the band's edges.
    controls = []
    for polar in (-0.5, -0.25, 0.0, 0.25, 0.5):
        axis = np.array([math.sin(polar), 0.0, math.cos(polar)])
        angular_radius = 0.45
        controls.append(_circle(SPHERE_CENTRE + SPHERE_RADIUS * math.cos(angular_radius) * axis, axis,
                                SPHERE_RADIUS * math.sin(angular_radius)))
    return _scene("catmull_rom", controls, name="fold")


def _sphere_normals(positions):
    n = positions - SPHERE_CENTRE
    return n / np.linalg.norm(n, axis=-1, keepdims=True)


@pytest.fixture(scope="module", params=["characteristic", "fold"])
def on_sphere(request):
    text = _characteristic_scene() if request.param == "characteristic" else _fold_scene()
    spec = parse_scene(text, f"{request.param}.yaml").surfaces[0]
    return mesh_circle_surface(build_surface(spec), 48, 97)


def test_sphere_cases_lie_on_the_sphere(on_sphere):
    distance = np.linalg.norm(on_sphere.positions - SPHERE_CENTRE, axis=1)
    assert np.max(np.abs(distance - SPHERE_RADIUS)) <= 1e-9


def test_sphere_cases_have_finite_unit_normals(on_sphere):
    n = on_sphere.normals
    assert np.all(np.isfinite(n)) and np.all(np.isfinite(on_sphere.positions)) and np.max(
        np.abs(np.linalg.norm(n, axis=1) - 1.0)) <= 1e-12


def test_sphere_cases_normals_are_the_spheres_outward_normal(on_sphere):
    # Continuous across characteristic points and folds: one sheet of the sphere's field.
    assert _angles_degrees(on_sphere.normals, _sphere_normals(on_sphere.positions)).max() <= NORMAL_DEGREES


def test_sphere_cases_triangles_wind_counter_clockwise_seen_from_their_normals(on_sphere):
    # Also the triangles that straddle a fold or pass by a characteristic point.
    dots = np.einsum("fi,fvi->fv", _face_normals(on_sphere.positions, on_sphere.faces),
                     on_sphere.normals[on_sphere.faces])
    bad = np.flatnonzero(dots.min(axis=1) <= 0.0)
    assert bad.size == 0, f"{bad.size} of {len(dots)} triangles wind against their normals"


def test_sphere_cases_have_no_zero_area_triangles(on_sphere):
    area = 0.5 * np.linalg.norm(_face_normals(on_sphere.positions, on_sphere.faces), axis=1)
    assert area.min() > 1e-12


def test_fold_case_really_folds(oracle):
    # Guard for the fold test above: consecutive circles of the fold case cross each other.
    spec = parse_scene(_fold_scene(), "fold.yaml").surfaces[0]
    surface = build_surface(spec)
    rings = CircleRings.from_projection(surface.sample(np.array([1.5, 1.52])), surface.frame)
    gap = np.linalg.norm(rings.centre[1] - rings.centre[0])
    assert gap < rings.radius.sum() and gap > abs(rings.radius[1] - rings.radius[0])


@pytest.mark.parametrize("around", [64, 63], ids=["both-on-columns", "one-on-a-column"])
def test_a_vertex_exactly_on_a_characteristic_point_takes_the_limit_along_its_circle(around):
    # The first circle lies in the xy plane, so its ring starts at u = e1: column 0 sits on
    # A = (1, 0, 0), which every interpolated circle passes through (as does B = -A). There
    # X . (C dC/dalpha) = 0 and the raw normal is 0/0; the vertex takes the limit along its
    # circle. With an even count B = -A sits on a column too. Both controls are great circles
    # of the unit sphere, and so is every circle between them: every normal, those at A and B
    # included, is the sphere's outward normal.
    text = _scene("linear", [_circle([0, 0, 0], [0, 0, 1], 1.0),
                             _through([[1, 0, 0], [0, 0.6, 0.8], [-1, 0, 0]])], name="pencil")
    mesh = mesh_circle_surface(build_surface(parse_scene(text, "pencil.yaml").surfaces[0]), around, 9)
    assert np.abs(mesh.positions[0] - [1.0, 0.0, 0.0]).max() <= 1e-15
    assert np.all(np.isfinite(mesh.normals)) and np.abs(np.linalg.norm(mesh.normals, axis=1) - 1.0).max() <= 1e-12
    assert _angles_degrees(mesh.normals, mesh.positions).max() <= NORMAL_DEGREES
    # Every ring meets at A (and B): the triangles collapsed there are dropped, the rest wind
    # counter-clockwise seen from their normals.
    geometric = _face_normals(mesh.positions, mesh.faces)
    assert np.linalg.norm(geometric, axis=1).min() > 1e-12
    assert np.einsum("fi,fvi->fv", geometric, mesh.normals[mesh.faces]).min() > 0.0


def test_unit_normals_equal_the_normalised_expansion_and_take_the_limit_at_a_zero(rng):
    from cgamesh.meshing import normals as normal_field

    theta = 2.0 * np.pi * np.arange(257) / 256
    coefficients = rng.standard_normal((70, 7, 3))  # more rings than one block holds
    coefficients[:, 0] += 4.0 * np.sign(coefficients[:, 0])  # well away from zero
    # Ring 5: N = (sin t, 1 - cos t, 0) vanishes at t = 0 with dN/dt = (1, 0, 0).
    coefficients[5] = 0.0
    coefficients[5, 2, 0] = 1.0  # sin t
    coefficients[5, 0, 1], coefficients[5, 1, 1] = 1.0, -1.0  # 1 - cos t
    speed = np.full(70, 2.0)
    unit, smallest, near = normal_field.unit_normals(coefficients, theta, speed, 1e-6)

    raw = normal_field.expand(coefficients, normal_field.trig_basis(theta))
    length = np.linalg.norm(raw, axis=-1)
    away = length > 1e-8  # all but ring 5 at t = 0 and t = 2 pi
    assert np.count_nonzero(~away) == 2
    np.testing.assert_allclose(unit[away], (raw / np.where(away, length, 1.0)[..., None])[away], rtol=0, atol=1e-14)
    assert near[0].tolist() == [5, 5] and near[1].tolist() == [0, 256]
    np.testing.assert_allclose(unit[5, [0, -1]], [[1.0, 0.0, 0.0]] * 2, atol=1e-15)
    # Each ring's least |N|; at ring 5's zeros |dN/dt| = 1 stands in for |N|.
    length[5, [0, -1]] = 1.0
    np.testing.assert_allclose(smallest, length.min(axis=1), rtol=1e-14)
