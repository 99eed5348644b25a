"""cgamesh.meshing.ribbons: point-pair surfaces meshed as ruled ribbons, checked against clifford.

Positions and normals are compared with ribbons rebuilt in clifford from the scene's numbers
(controls, alignment, interpolant, projection, eq. 5 end points: conftest's ``oracle`` and
``paper_weights``), never with cgamesh's own algebra. On random ribbons (every curve kind, open
and closed, directions on the exact axes, sizes 1e-6 to 1e6) the one mesher is checked against
the readable definition (``EvolvedSurface.sample``'s point pairs, central differences of their
end points) and for its invariants, and a batch of many surfaces against each surface alone.
"""

from __future__ import annotations

import math
import os
import warnings
from pathlib import Path

import numpy as np
import pygltflib
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from direction_strategies import coordinate, direction, sphere_direction

from cgamesh.export.options import WriteOptions
from cgamesh.geometry import objects
from cgamesh.geometry.algebra import rotors
from cgamesh.geometry.algebra.conformal import up
from cgamesh.errors import CgameshError, DegenerateGeometryError, NonFiniteInputError
from cgamesh.export.gltf import write_glb
from cgamesh.pipelines.scene import Resolution, build_surface, mesh_surface
from cgamesh.geometry.projection import project
from cgamesh.geometry.objects import point_pair_endpoints
from cgamesh.meshing.ribbons import PairRings, mesh_ribbon_surface, mesh_ribbons
from cgamesh.inputs.scene import load_scene, parse_scene
from cgamesh_cli.main import main
from gltf_validator import assert_clean

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
RIBBONS = ["fig10_linear_pairs", "fig10_quadratic_pairs", "fig10_cubic_pairs", "fig12_cocircular_chords",
           "ribbon_loop"]
H = 1e-5  # central-difference step in t


def _spec(name, index=0):
    return load_scene(EXAMPLES / f"{name}.yaml").surfaces[index]


def _clifford_pairs(oracle, spec, t, paper_weights):
    """World end points (a, b) (A, 3) of S P'(t), everything in clifford from the scene's numbers."""
    controls = []
    for control in spec.controls:
        blade = oracle.point(control.a) ^ oracle.point(control.b)
        blade = blade / math.sqrt((blade * blade)[()])
        if spec.align and controls and (controls[-1] * blade)[()] < 0.0:
            blade = -blade
        controls.append(blade)
    weights = paper_weights(spec.curve, len(controls), t, spec.tension, spec.bias, spec.continuity,
                            spec.closed)
    einf = oracle.einf
    starts, ends = [], []
    for row in weights:
        pair = oracle.project(sum((float(w) * c for w, c in zip(row, controls)), 0 * einf))
        direction = pair | einf  # paper eq. 5 with P^2 = 1
        starts.append(oracle.down((1 - pair) * direction))
        ends.append(oracle.down((1 + pair) * direction))
    return np.array(starts), np.array(ends)


def _grid(mesh, along, around):
    return mesh.positions.reshape(along, around, 3), mesh.normals.reshape(along, around, 3)


# --- geometry of the interpolation -------------------------------------------------------------

def test_linear_interpolation_keeps_the_end_points_on_the_sphere_through_the_controls(g3c, oracle):
    # Paper section 7.2: the end points of every S((1 - alpha) P1 + alpha P2) lie on P1 ^ P2.
    spec = _spec("fig10_linear_pairs")
    (a1, b1), (a2, b2) = [(c.a, c.b) for c in spec.controls]
    sphere = oracle.point(a1) ^ oracle.point(b1) ^ oracle.point(a2) ^ oracle.point(b2)
    dual = sphere.dual()
    dual = dual / -(dual | g3c.einf)[()]  # X . dual = -(|x - c|^2 - r^2) / 2 for X = up(x)
    centre = oracle.euclidean(dual)
    radius_sq = float((dual * dual)[()])
    positions, _ = _grid(mesh_surface(spec, Resolution(5, 41)), 41, 5)
    edges = positions[:, [0, -1]].reshape(-1, 3)
    assert np.abs(np.sum((edges - centre) ** 2, axis=1) - radius_sq).max() <= 1e-10 * radius_sq
    assert np.ptp(positions[:, 2], axis=0).max() > 0.5  # and the ribbon really moves


@pytest.mark.parametrize("name", RIBBONS[:3] + ["ribbon_loop"])
def test_vertices_sit_on_the_clifford_segment_of_their_pair_at_their_fraction(oracle, paper_weights, name):
    spec = _spec(name)
    along, around = 17, 6
    t = np.linspace(0.0, build_surface(spec).segment_count, along)
    a, b = _clifford_pairs(oracle, spec, t, paper_weights)
    positions, _ = _grid(mesh_surface(spec, Resolution(around, along)), along, around)
    s = np.linspace(0.0, 1.0, around)
    expected = a[:, None, :] + s[None, :, None] * (b - a)[:, None, :]
    length = np.linalg.norm(b - a, axis=1)[:, None]
    assert np.all(np.linalg.norm(positions - expected, axis=-1) <= 1e-9 * length)


def test_each_trs_rotor_carries_a_ruling_onto_the_next():
    # Section 11: T(a_{k+1}) D(|d_{k+1}| / |d_k|) R_k T(-a_k), R_k the smallest rotation between
    # the rulings, maps x_kj to x_{k+1,j}: the grid is the rotors' composition.
    spec = _spec("fig10_cubic_pairs")
    along, around = 12, 5
    positions, _ = _grid(mesh_surface(spec, Resolution(around, along)), along, around)
    a, d = positions[:, 0], positions[:, -1] - positions[:, 0]
    length = np.linalg.norm(d, axis=1)
    turn = rotors.rotation_between(d[:-1] / length[:-1, None], d[1:] / length[1:, None])
    versor = rotors.trs_versor(a[1:], turn, length[1:] / length[:-1])
    to_origin = rotors.translator(-a[:-1])
    matrix = rotors.versor_matrix(versor) @ rotors.versor_matrix(to_origin)
    moved = np.einsum("kij,kmj->kmi", matrix, up(positions[:-1])[..., 1:6])
    carried = moved[..., :3] / (moved[..., 4] - moved[..., 3])[..., None]
    assert np.abs(carried - positions[1:]).max() <= 1e-12 * length.max()


def test_cocircular_chords_need_no_projection_and_stay_chords(g3c, oracle):
    for index, centre in enumerate(([0.0, 0.0, 0.0], [2.0, 0.0, 0.0])):
        spec = _spec("fig12_cocircular_chords", index)
        ends = [oracle.point(p) for c in spec.controls for p in (c.a, c.b)]
        for i in range(0, len(ends), 2):
            for j in range(i + 2, len(ends), 2):
                wedge = ends[i] ^ ends[i + 1] ^ ends[j] ^ ends[j + 1]
                assert np.abs(wedge.value).max() <= 1e-12  # P_i ^ P_j = 0: one circle
        surface = build_surface(spec)
        assert surface.four_vector_free
        t = np.linspace(0.0, surface.segment_count, 101)
        basis = surface.curve.basis(t)
        general = project(*basis.evaluate(surface.controls), 2, basis.weight_sum())
        cheap = surface.sample(t)
        assert np.abs(cheap.blades - general.blades).max() <= 1e-12
        difference = np.abs(cheap.derivatives - general.derivatives).max()
        assert difference <= 1e-10 * np.abs(general.derivatives).max()
        positions, normals = _grid(mesh_surface(spec, Resolution(7, 96)), 96, 7)
        edges = positions[:, [0, -1]]
        assert np.abs(np.linalg.norm(edges - centre, axis=-1) - 1.0).max() <= 1e-12
        assert np.abs(positions[..., 2]).max() <= 1e-12
        # Flat, so the continuous field is one constant normal, also across the fold of the second.
        assert np.abs(np.abs(normals[..., 2]) - 1.0).max() <= 1e-12
        assert np.unique(np.sign(normals[..., 2])).size == 1
    assert not build_surface(_spec("fig10_linear_pairs")).four_vector_free


# --- normals ---------------------------------------------------------------------------------

@pytest.mark.parametrize("name", ["fig10_cubic_pairs", "ribbon_loop"])
def test_normals_are_unit_across_both_tangents_and_match_finite_differences_inside(oracle, paper_weights,
                                                                                   name):
    spec = _spec(name)
    along, around = 14, 7
    segments = build_surface(spec).segment_count
    # Interior rings, none on a joint of the spline (its second derivative jumps there).
    t = np.linspace(0.0, segments, along)[1:-1]
    a, b = _clifford_pairs(oracle, spec, t, paper_weights)
    a_plus, b_plus = _clifford_pairs(oracle, spec, t + H, paper_weights)
    a_minus, b_minus = _clifford_pairs(oracle, spec, t - H, paper_weights)
    s = np.linspace(0.0, 1.0, around)[None, :, None]
    ruling = (b - a)[:, None, :]
    da, db = (a_plus - a_minus) / (2 * H), (b_plus - b_minus) / (2 * H)
    along_t = da[:, None, :] + s * (db - da)[:, None, :]
    expected = np.cross(np.broadcast_to(ruling, along_t.shape), along_t)  # (b - a) x dx/dt
    expected /= np.linalg.norm(expected, axis=-1, keepdims=True)
    _, normals = _grid(mesh_surface(spec, Resolution(around, along)), along, around)
    normals = normals[1:-1]
    assert np.abs(np.linalg.norm(normals, axis=-1) - 1.0).max() <= 1e-12
    ruling_unit = (b - a) / np.linalg.norm(b - a, axis=1)[:, None]
    assert np.abs(np.einsum("kmc,kc->km", normals, ruling_unit)).max() <= 1e-9
    assert np.abs(np.einsum("kmc,kmc->km", normals, along_t)).max() <= 1e-6 * np.abs(along_t).max()
    # Same side as documented ((b - a) x dx/dt: no fold here), within 0.1 degree everywhere.
    assert np.einsum("kmc,kmc->km", normals, expected).min() >= math.cos(math.radians(0.1))


PINCH = """\
cgamesh: 1
surfaces:
  - name: pinch   # a generic pinch point (cross-cap) at t = 0.246, s = 0.403
    type: point_pairs
    curve: bezier
    controls:
      - {a: [0.21, 0.53, 0.76], b: [0.14, -0.15, 0.03]}
      - {a: [-0.72, 0.80, 0.58], b: [-0.02, 0.53, 1.24]}
      - {a: [0.50, -0.05, 1.90], b: [-0.40, 0.22, 1.57]}
      - {a: [-0.02, 0.80, 2.15], b: [0.08, 0.01, 2.75]}
"""


PINCHED_LOOP = """\
cgamesh: 1
surfaces:
  - name: pinched_loop   # a closed kb band that twists through pinch points
    type: point_pairs
    curve: kb
    closed: true
    controls:
      - {a: [2.401, 0.000, -0.188], b: [2.599, 0.000, 0.588]}
      - {a: [1.739, 1.015, 0.177], b: [1.972, 1.248, 0.906]}
      - {a: [0.300, 1.463, -0.376], b: [0.300, 1.737, 0.376]}
      - {a: [-1.139, 1.015, -0.906], b: [-1.372, 1.248, -0.177]}
      - {a: [-1.801, 0.000, -0.588], b: [-1.999, 0.000, 0.188]}
      - {a: [-1.372, -1.248, -0.106], b: [-1.139, -1.015, 0.623]}
      - {a: [0.300, -1.901, -0.264], b: [0.300, -1.299, 0.264]}
      - {a: [1.972, -1.248, -0.623], b: [1.739, -1.015, 0.106]}
"""


@pytest.mark.parametrize("source, around, along", [
    (PINCHED_LOOP, 16, 256), (PINCH, 11, 81), (PINCH, 21, 201)], ids=["loop", "pinch_11x81", "pinch_21x201"])
def test_neighbours_with_agreeing_tangent_planes_never_disagree_away_from_pinch_points(source, around, along):
    # The field N = (b - a) x dx/dt winds around a pinch point: where |N| < |b - a| |x'| / 10 a
    # coarse grid cannot avoid a reversal. Elsewhere, a reversal between neighbours whose normal
    # lines agree would be a wrong sign flip (a pinch point taken for a fold, or a ring flipped).
    spec = parse_scene(source, "pinch.yaml").surfaces[0]
    positions, normals = _grid(mesh_surface(spec, Resolution(around, along)), along, around)
    surface = build_surface(spec)
    rings = PairRings.from_projection(surface.sample(np.linspace(0.0, surface.segment_count, along)),
                                      surface.frame)
    s = np.linspace(0.0, 1.0, around)[None, :, None]
    d = (rings.b - rings.a)[:, None, :]
    velocity = rings.da[:, None, :] + s * (rings.db - rings.da)[:, None, :]
    strength = np.linalg.norm(np.cross(d, velocity), axis=-1) / (
        np.linalg.norm(d, axis=-1) * np.linalg.norm(velocity, axis=-1).max(axis=1, keepdims=True))
    assert strength.min() < 0.05  # the ribbon does pass close to pinch points
    for step in ((1, 0), (0, 1)):
        here, there = normals[: along - step[0], : around - step[1]], normals[step[0]:, step[1]:]
        cosine = np.einsum("kmc,kmc->km", here, there)
        weak = np.minimum(strength[: along - step[0], : around - step[1]], strength[step[0]:, step[1]:])
        assert np.all(cosine[(np.abs(cosine) > 0.5) & (weak > 0.1)] > 0.0)
    if spec.closed:  # the seam repeats the first ruling exactly
        np.testing.assert_array_equal(positions[-1], positions[0])
        np.testing.assert_array_equal(normals[-1], normals[0])


def test_zeros_of_the_normal_take_the_limit_along_the_ruling():
    # A fan (every pair shares a) has N = 0 along the whole a edge; tension 1 stops the rings
    # at the controls (zero velocity). Both still give unit normals and no zero-area triangle
    # (those with two corners at the apex are dropped).
    text = """\
cgamesh: 1
surfaces:
  - name: fan
    type: point_pairs
    curve: kb
    tension: 1.0
    controls:
      - {a: [0, 0, 0], b: [1, 0, 0]}
      - {a: [0, 0, 0], b: [0.3, 1, 0.4]}
      - {a: [0, 0, 0], b: [-0.5, 0.5, 1]}
"""
    mesh = mesh_surface(parse_scene(text, "fan.yaml").surfaces[0], Resolution(9, 33))
    normals = mesh.normals.reshape(33, 9, 3)
    assert np.all(np.isfinite(normals)) and np.abs(np.linalg.norm(normals, axis=-1) - 1.0).max() <= 1e-12
    # A fan is a cone: N = s N_b, one direction along each ruling, which the apex takes as its limit.
    assert np.einsum("kc,kmc->km", normals[:, 0], normals).min() > 1.0 - 1e-12
    corners = mesh.positions[mesh.faces]
    geometric = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    assert np.linalg.norm(geometric, axis=1).min() > 1e-9
    assert np.einsum("ti,ti->t", geometric, mesh.normals[mesh.faces].sum(axis=1)).min() > 0.0


# --- export --------------------------------------------------------------------------------------

@pytest.mark.parametrize("name", RIBBONS)
def test_ribbon_examples_export_double_sided_and_validate(tmp_path, gltf_validate, name):
    scene = load_scene(EXAMPLES / f"{name}.yaml")
    meshes = [(mesh_surface(spec, Resolution(6, 24)), spec.material) for spec in scene.surfaces]
    assert all(mesh.double_sided for mesh, _ in meshes)
    output = tmp_path / f"{name}.glb"
    write_glb(output, meshes, WriteOptions(scene.up, scene.meters_per_unit, scene.units))
    assert_clean(gltf_validate(output))
    document = pygltflib.GLTF2().load(str(output))
    assert document.materials and all(material.doubleSided for material in document.materials)


# --- degenerate input ----------------------------------------------------------------------------

def test_point_pair_constructor_refuses_coincident_and_non_finite_end_points():
    with pytest.raises(DegenerateGeometryError, match="must differ"):
        objects.point_pair([1.0, 2.0, 3.0], [1.0, 2.0, 3.0])
    with pytest.raises(NonFiniteInputError):
        objects.point_pair([1.0, np.nan, 3.0], [0.0, 0.0, 0.0])


CHORDS = """\
cgamesh: 1
surfaces:
  - name: crossing_chords
    type: point_pairs
    curve: linear
    align: {align}
    controls:
      - {{a: [1, 0, 0], b: [0, 1, 0]}}
      - {{a: [-1, 0, 0], b: [0, -1, 0]}}
"""


def test_a_non_real_interpolated_pair_is_refused_naming_surface_and_alpha(g3c, oracle):
    # Unaligned chords: P1 . P2 = -3, so P'(1/2)^2 = -1 with P' ^ P' = 0: no real pair there.
    spec = parse_scene(CHORDS.format(align="false"), "chords.yaml").surfaces[0]
    p1, p2 = [oracle.point(c.a) ^ oracle.point(c.b) for c in spec.controls]
    middle = 0.5 * (p1 / math.sqrt((p1 * p1)[()]) + p2 / math.sqrt((p2 * p2)[()]))
    assert (middle * middle)[()] < -0.5 and np.abs((middle ^ middle).value).max() <= 1e-12
    with pytest.raises(DegenerateGeometryError) as caught:
        mesh_surface(spec, Resolution(4, 16))
    message = str(caught.value)
    assert message.startswith("chords.yaml:") and "'crossing_chords'" in message
    assert "alpha = 0.5" in message and "\n" not in message
    mesh_surface(parse_scene(CHORDS.format(align="true"), "chords.yaml").surfaces[0], Resolution(4, 16))


def test_a_negative_square_in_general_position_still_projects_to_real_pairs(oracle):
    # Off a common circle the 4-vector part of Sigma keeps the projection real: P'(1/2)^2 < 0 here.
    text = CHORDS.format(align="false").replace("[-1, 0, 0], b: [0, -1, 0]", "[1, 0.3, 1], b: [0, 0, 1]")
    text = text.replace("[1, 0, 0], b: [0, 1, 0]", "[0, 0, 0], b: [1, 0, 0]")
    spec = parse_scene(text, "general.yaml").surfaces[0]
    p1, p2 = [oracle.point(c.a) ^ oracle.point(c.b) for c in spec.controls]
    middle = 0.5 * (p1 / math.sqrt((p1 * p1)[()]) + p2 / math.sqrt((p2 * p2)[()]))
    assert (middle * middle)[()] < -0.5
    surface = build_surface(spec)
    rings = PairRings.from_projection(surface.sample(np.linspace(0.0, 1.0, 11)), surface.frame)
    assert np.linalg.norm(rings.b - rings.a, axis=1).min() > 0.1


@pytest.mark.parametrize("bad, expected", [
    ("{a: [0, 0, 0], b: [0, 0, 0]}", "must differ from a"),
    ("{a: [0, 0, .nan], b: [1, 0, 0]}", "controls[1].a"),
    ("{a: [2, 0, 0], b: [3, 0, 0]}", "no area"),  # collinear with the first: a line, not a ribbon
], ids=["coincident", "nan", "collinear"])
def test_cli_reports_degenerate_ribbons_on_one_line_and_writes_nothing(tmp_path, capsys, bad, expected):
    scene = tmp_path / "bad.yaml"
    scene.write_text(CHORDS.format(align="true").replace("{a: [-1, 0, 0], b: [0, -1, 0]}", bad)
                     .replace("{a: [1, 0, 0], b: [0, 1, 0]}", "{a: [0, 0, 0], b: [1, 0, 0]}"))
    output = tmp_path / "out.glb"
    assert main([str(scene), "-o", str(output), "-q"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("cgamesh: error: ") and err.count("\n") == 1 and expected in err
    assert not output.exists()


def test_cli_reports_a_non_real_interpolation_and_writes_nothing(tmp_path, capsys):
    scene = tmp_path / "chords.yaml"
    scene.write_text(CHORDS.format(align="false"))
    output = tmp_path / "out.glb"
    assert main([str(scene), "-o", str(output), "-q"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "crossing_chords" in err and "alpha = 0.5" in err
    assert not output.exists()


# --- the one mesher on random ribbons: the definition, its invariants, a batch against alone ------

PROPERTY = settings(max_examples=int(os.environ.get("CGAMESH_PROPERTY_EXAMPLES", "40")), deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])
CURVES = ("linear", "bezier", "rational_bezier", "kb", "catmull_rom")


@st.composite
def ribbon_shapes(draw):
    """What the surfaces of one batch share: curve kind and parameters, closed, control count,
    vertices across, rulings along."""
    curve = draw(st.sampled_from(CURVES))
    closed = curve in ("kb", "catmull_rom") and draw(st.booleans())
    count = draw(st.integers(3 if closed else 2, 5))
    kb = tuple(draw(st.sampled_from((0.0, 0.5, -1.0, 1.0))) for _ in range(3)) if curve == "kb" else None
    weights = [10.0 ** draw(st.floats(-1.0, 1.0)) for _ in range(count)] if curve == "rational_bezier" else None
    return curve, closed, count, kb, weights, draw(st.sampled_from((2, 3, 8, 16))), draw(st.sampled_from((2, 3, 9, 40)))


@st.composite
def ribbon_surfaces(draw, shape, name="s"):
    """The YAML of a point-pair surface of ``shape``: pairs about a random walk of size 1e-6 to 1e6
    (up to 1e3 sizes from the origin), their directions on the exact axes or anywhere, turning from
    control to control (sometimes against the previous one), sometimes a control repeated."""
    curve, closed, count, kb, weights, around, along = shape
    scale = 10.0 ** draw(st.integers(-6, 6))
    point = np.array(draw(st.tuples(coordinate, coordinate, coordinate))) * scale * 10.0 ** draw(st.integers(0, 3))
    step = np.array(draw(direction))
    lines = []
    for i in range(count):
        across = np.array(draw(direction))
        half = scale * draw(st.floats(0.2, 1.0))
        weight = f", weight: {weights[i]!r}" if weights else ""
        lines.append(f"{{a: {(point - half * across).tolist()}, b: {(point + half * across).tolist()}{weight}}}")
        step = step + 0.5 * np.array(draw(sphere_direction))
        point = point + scale * draw(st.floats(0.3, 1.5)) * step / max(np.linalg.norm(step), 1e-3)
    if draw(st.integers(0, 4)) == 0:
        lines[1:1] = [lines[0]] if not weights else []  # a repeated control (rational: as many weights)
    tbc = f"    tension: {kb[0]}\n    bias: {kb[1]}\n    continuity: {kb[2]}\n" if kb else ""
    return (f"  - name: {name}\n    type: point_pairs\n    curve: {curve}\n{tbc}    closed: {str(closed).lower()}\n"
            f"    align: {draw(st.sampled_from(('true', 'true', 'false')))}\n"
            f"    resolution: {{around: {around}, along: {along}}}\n    controls:\n"
            + "".join(f"      - {line}\n" for line in lines))


@st.composite
def ribbon_batches(draw):
    """Scenes of 1 to 6 ribbons of one shape."""
    shape = draw(ribbon_shapes())
    bodies = [draw(ribbon_surfaces(shape, f"s{i}")) for i in range(draw(st.integers(1, 6)))]
    return "cgamesh: 1\nsurfaces:\n" + "".join(bodies)


def _built(text):
    """(spec, surface) of every surface of the scene its builder accepts."""
    built = []
    for spec in parse_scene(text, "random.yaml").surfaces:
        try:
            built.append((spec, build_surface(spec)))
        except CgameshError:
            pass
    return built


def _alone(spec, surface):
    """mesh_ribbon_surface's mesh, or its error; numpy warnings are errors."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            return mesh_ribbon_surface(surface, spec.around, spec.along, closed=spec.closed)
        except CgameshError as error:
            return error


def _local_ends(surface, t):
    """End points (A, 3) of the interpolated pairs in the surface's working frame (the definition:
    EvolvedSurface.sample and eq. 5)."""
    return point_pair_endpoints(surface.sample(t).blades)


def _tangents_along(surface, t, h=1e-6):
    """d a/dt, d b/dt (A, 3), local frame: central differences of the end points over +-h,
    one-sided (second order) at the curve's ends and at the joints of segments, where the basis
    takes the derivative from the segment that starts there."""
    joint = (np.abs(t - np.round(t)) < 1e-12) & (t < surface.segment_count)
    end = t >= surface.segment_count
    sign = np.where(end, -1.0, 1.0)
    steps = np.where(joint | end, sign * h, h)[:, None]
    centre = ~(joint | end)
    out = []
    for which in (0, 1):
        plus = _local_ends(surface, np.where(centre, t + h, t + sign * h))[which]
        minus = _local_ends(surface, np.where(centre, t - h, t))[which]
        twice = _local_ends(surface, np.where(centre, t, t + 2 * sign * h))[which]
        here = _local_ends(surface, t)[which]
        one_sided = (-3.0 * here + 4.0 * plus - twice) / (2.0 * steps)
        out.append(np.where(centre[:, None], (plus - minus) / (2.0 * h), one_sided))
    return out


def check_against_the_definition(spec, surface, mesh):
    """Vertices on the true surface, normals unit and across both tangents where the field is
    not near a zero, triangles wound like their vertex normals, UVs oriented like the surface."""
    along, around = spec.along, spec.around
    t = np.linspace(0.0, surface.segment_count, along)
    a_local, b_local = _local_ends(surface, t)
    frame = surface.frame
    a, b = frame.to_world(a_local), frame.to_world(b_local)
    s = np.linspace(0.0, 1.0, around)
    positions = mesh.positions.reshape(along, around, 3)
    expected = a[:, None] + s[None, :, None] * (b - a)[:, None]
    size = (np.linalg.norm(a, axis=1) + np.linalg.norm(b - a, axis=1))[:, None]
    assert np.all(np.linalg.norm(positions - expected, axis=-1) <= 1e-12 * size)
    normals = mesh.normals.reshape(along, around, 3)
    assert np.abs(np.linalg.norm(normals, axis=-1) - 1.0).max() <= 1e-12
    # tangents in the working frame (the world's are scale times these)
    d = b_local - a_local
    # a closed surface's last ruling repeats its first, normals included (the curve's tangent
    # may turn at the seam): its tangent is the first one's
    at = np.where(spec.closed & (t >= surface.segment_count), 0.0, t)
    da, db = _tangents_along(surface, at)
    x_t = da[:, None] + s[None, :, None] * (db - da)[:, None]
    half_da, half_db = _tangents_along(surface, at, 0.5e-6)  # their error: about 4/3 of the change
    error = np.linalg.norm(da - half_da, axis=1)[:, None] + np.linalg.norm(db - half_db, axis=1)[:, None]
    raw = np.cross(np.broadcast_to(d[:, None], x_t.shape), x_t)  # (b - a) x dx/dt
    # (differences of the unit-ball working frame round to about 1e-10: slower vertices are not judged)
    speed = np.linalg.norm(x_t, axis=-1).max()
    strong = (np.linalg.norm(raw, axis=-1) > 1e-3 * np.linalg.norm(d, axis=1).max() * speed) & (
        np.linalg.norm(x_t, axis=-1) > 1e-6)
    unit_d = d / np.linalg.norm(d, axis=1, keepdims=True)
    assert np.abs(np.einsum("kmc,kc->km", normals, unit_d)).max() <= 1e-9
    assert np.all((np.abs(np.einsum("kmc,kmc->km", normals, x_t)) <= 1e-6 * speed + 2.0 * error)[strong])
    # winding: a triangle that resolves the surface (its vertex normals within 60 degrees of each
    # other and of its own normal's line, between rulings whose chords move across them the way dx/dt does) is
    # counter-clockwise seen from the side they point to; not judged where the grid does not
    # resolve the surface (the field turning within a triangle next to a pinch point, a chord
    # running against the curve's direction on a loop of three rulings), where the vote of the
    # rulings' signs cannot tell (seen before this mesher too)
    corners = mesh.positions[mesh.faces]
    geometric = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    area = np.linalg.norm(geometric, axis=1)
    longest = np.max(np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=-1), axis=1)
    solid = area > 1e-6 * longest**2
    corner_normals = mesh.normals[mesh.faces][solid]
    agree = np.einsum("fvc,fvc->fv", corner_normals, np.roll(corner_normals, 1, axis=1))
    cosines = np.einsum("fc,fvc->fv", geometric[solid] / area[solid, None], corner_normals)
    chords = np.diff(mesh.positions.reshape(along, around, 3), axis=0)  # world; x_t is local

    def across(vectors, ruling):  # the part of vectors (K', M, 3) across each ruling (K', 3)
        return vectors - np.einsum("kmc,kc->km", vectors, ruling)[..., None] * ruling[:, None]

    forward = np.all((np.einsum("kmc,kmc->km", across(chords, unit_d[:-1]), across(x_t[:-1], unit_d[:-1])) > 0.0)
                     & (np.einsum("kmc,kmc->km", across(chords, unit_d[1:]), across(x_t[1:], unit_d[1:])) > 0.0),
                     axis=1)  # (K - 1,) by quad: the rulings move the way dx/dt does, across themselves
    resolved = (np.all(agree > 0.5, axis=1) & np.all(np.abs(cosines) > 0.5, axis=1)
                & forward[mesh.faces[solid].min(axis=1) // around])
    assert np.all(cosines[resolved] > 0.0)
    # UVs: u the fraction across, v from 0 to 1 never decreasing along, so no face is flipped in
    # UV against the surface's parameters (s, t): a face's UV area has the sign of its (s, t) area
    uvs = mesh.uvs.reshape(along, around, 2)
    assert np.array_equal(uvs[..., 0], np.broadcast_to(s, (along, around)))
    v = uvs[:, 0, 1]
    assert v[0] == 0.0 and v[-1] == 1.0 and np.all(np.diff(v) >= 0.0) and np.all(uvs[..., 1] == v[:, None])
    parameters = np.stack(np.broadcast_arrays(s[None, :], t[:, None]), axis=-1).reshape(-1, 2)

    def signed_areas(points):
        first, second = points[:, 1] - points[:, 0], points[:, 2] - points[:, 0]
        return first[:, 0] * second[:, 1] - first[:, 1] * second[:, 0]

    uv_area, st_area = signed_areas(mesh.uvs[mesh.faces]), signed_areas(parameters[mesh.faces])
    assert np.all(st_area != 0.0)
    moved = uv_area != 0.0  # v stands still between rulings that do not move
    assert np.all(np.sign(uv_area[moved]) == np.sign(st_area[moved]))


@PROPERTY
@given(text=ribbon_batches())
def test_every_ribbon_lies_on_its_definition_with_unit_normals_winding_and_uvs(text):
    for spec, surface in _built(text):
        mesh = _alone(spec, surface)
        if isinstance(mesh, CgameshError):  # refused: the surface's own scan, sample or no area says so
            message = str(mesh)
            assert message.startswith(f"surface '{spec.name}': ") and "\n" not in message
            continue
        assert mesh.double_sided and mesh.faces.dtype == np.int32 and len(mesh.positions) == spec.along * spec.around
        check_against_the_definition(spec, surface, mesh)


@PROPERTY
@given(text=ribbon_batches())
def test_a_batch_gives_each_surface_what_it_gets_alone(text):
    """mesh_ribbons over surfaces of one curve: each mesh is mesh_ribbon_surface's bit for bit,
    and None exactly where that refuses."""
    groups = {}
    for spec, surface in _built(text):
        groups.setdefault(surface.curve, []).append((spec, surface))
    for members in groups.values():
        spec = members[0][0]
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            batch = mesh_ribbons([surface for _, surface in members], spec.around, spec.along, closed=spec.closed)
        for (spec, surface), meshed in zip(members, batch):
            alone = _alone(spec, surface)
            if isinstance(alone, CgameshError):
                assert meshed is None
                continue
            assert meshed.name == alone.name and meshed.double_sided
            for field in ("positions", "normals", "uvs", "faces"):
                x, y = getattr(meshed, field), getattr(alone, field)
                assert x.dtype == y.dtype and np.array_equal(x, y), field


def _linear_ribbon(*pairs, align="true"):
    controls = "".join(f"      - {{a: {list(a)}, b: {list(b)}}}\n" for a, b in pairs)
    text = f"cgamesh: 1\nsurfaces:\n  - name: r\n    type: point_pairs\n    curve: linear\n    align: {align}\n"
    return build_surface(parse_scene(text + "    controls:\n" + controls, "r.yaml").surfaces[0])


def test_a_batch_with_refused_ribbons_meshes_the_others_as_alone():
    """Surfaces of one curve in one call, among them two the mesher refuses: opposite controls
    (no projection between them) and a pair sliding along its own line (no area); they get None,
    alone they raise, and the others get their meshes alone."""
    fine = [_linear_ribbon(((0, 0, 0), (1, 0, 0)), ((0, 1, 0), (1, 1, 0.5 + y)), ((0, 2, 0), (1, 2.5, 1)))
            for y in (0.0, 0.5, 1.0)]
    opposite = _linear_ribbon(((0, 0, 0), (1, 0, 0)), ((1, 1, 0), (0, 1, 0)), ((1, 2, 0), (0, 2, 0)), align="false")
    sliding = _linear_ribbon(((0, 0, 0), (1, 0, 0)), ((0.2, 0, 0), (1.3, 0, 0)), ((0.2, 1, 0), (1.3, 1, 0.5)))
    surfaces = fine[:1] + [opposite] + fine[1:] + [sliding]
    meshes = mesh_ribbons(surfaces, 5, 17)
    assert meshes[1] is None and meshes[-1] is None
    with pytest.raises(DegenerateGeometryError, match="no blade projection at segment 0"):
        mesh_ribbon_surface(opposite, 5, 17)
    with pytest.raises(DegenerateGeometryError, match="no area at segment 0"):
        mesh_ribbon_surface(sliding, 5, 17)
    for surface, mesh in zip(fine, meshes[:1] + meshes[2:-1]):
        alone = mesh_ribbon_surface(surface, 5, 17)
        assert all(np.array_equal(getattr(mesh, f), getattr(alone, f)) for f in ("positions", "normals", "uvs", "faces"))
