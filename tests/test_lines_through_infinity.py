"""Blade interpolation that turns a circle into a line, or a point pair into a flat point (an end
point at infinity), between two rings of the mesh: refused in one located line naming the
parameter interval and what avoids it, for every curve kind and both object kinds; aligned, the
same controls mesh; a fast but bounded turn of the normal is not refused.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from cgamesh.geometry import flatness
from cgamesh.geometry.construction import build_surface
from cgamesh.geometry.objects import (circle_euclidean, circle_from_center_normal_radius, point_pair,
                                      point_pair_endpoints)
from cgamesh.inputs.scene import parse_scene
from cgamesh.readers.readback import read_gltf

from test_error_messages import assert_finite_unit, refused, run

CURVES = {  # curve kind: extra surface keys, and the key added to the later controls
    "linear": ("", ""),
    "bezier": ("", ""),
    "rational_bezier": ("", ", weight: 2.5"),
    "kb": ("    tension: 0.3\n    bias: -0.2\n    continuity: 0.1\n", ""),
    "catmull_rom": ("", ""),
}
CIRCLES = ["{center: [0, 0, 0], normal: [1, 0, 0], radius: 1.0}",
           "{center: [1.3, 0, 0.7], normal: [-1, 0, 0], radius: 0.5%s}",
           "{center: [2.3, 0, 0.7], normal: [-1, 0, 0], radius: 0.5%s}"]
PAIRS = ["{a: [0, 0, 0], b: [1, 0, 0]}",
         "{a: [1, 1, 0], b: [0.2, 1, 0]%s}",
         "{a: [1, 2, 0], b: [0.2, 2, 0]%s}"]


def scene(kind: str, curve: str, controls, align: str = "false", along: int = 5) -> str:
    extra, later = CURVES[curve]
    body = "".join(f"      - {c % later if '%s' in c else c}\n" for c in controls)
    around = 8 if kind == "circles" else 3
    return (f"cgamesh: 1\nsurfaces:\n  - name: s\n    type: {kind}\n    curve: {curve}\n{extra}"
            f"    align: {align}\n    resolution: {{around: {around}, along: {along}}}\n    controls:\n{body}")


def read_out(surface, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The objects' radius (circles) or length (pairs) in world units, and their normal (circles)
    or direction b - a (pairs), from circle_euclidean and the end points: an independent read-out
    of the flatness measure."""
    blades = surface.sample(t).blades
    with np.errstate(divide="ignore", invalid="ignore"):
        if surface.grade == 3:
            _, normal, radius = circle_euclidean(blades)
            return surface.frame.scale * radius, normal
        a, b = point_pair_endpoints(blades)
        return surface.frame.scale * np.linalg.norm(b - a, axis=-1), b - a


@pytest.mark.parametrize("kind", ["circles", "point_pairs"])
@pytest.mark.parametrize("curve", sorted(CURVES))
def test_a_line_between_rings_is_refused_with_its_interval(tmp_path, kind, curve):
    controls = CIRCLES if kind == "circles" else PAIRS
    path = tmp_path / "cross.yaml"
    text = scene(kind, curve, controls)
    path.write_text(text)
    noun = "circle turns into a line" if kind == "circles" else "point pair has an end point at infinity"
    advice = "set align: true, or interpolation: motor" if kind == "circles" else "set align: true"
    line = refused([path, "-o", tmp_path / "o.glb"],
                   rf"cross\.yaml:3: surfaces\[0\]: surface 's': the interpolated {noun} .*between segment "
                   rf"(\d+), alpha = \S+ and alpha = \S+ \(closest at alpha = \S+, "
                   rf"(radius|length) (unbounded|\S+)\); controls 0 and 1 have opposite orientations "
                   rf"\(align: false\); {advice}$")
    assert not (tmp_path / "o.glb").exists()
    found = re.search(r"between segment (\d+), alpha = (\S+) and alpha = (\S+) \(closest at alpha = ([^,]+),", line)
    segment, lo, hi, closest = int(found[1]), float(found[2]), float(found[3]), float(found[4])
    assert 0.0 <= lo <= closest <= hi <= 1.0 and hi - lo <= 1.0 / 128 + 1e-5
    # Between two rings of the mesh (along 5): no ring lies on it, the mesh would have a huge one.
    surface = build_surface(parse_scene(text, "cross.yaml").surfaces[0])
    rings = np.linspace(0.0, surface.segment_count, 5)
    assert np.min(np.abs(rings - (segment + closest))) > 1e-3
    # Independently: inside the interval the read-out radius / length passes 1e4 bounding radii and
    # the normal (direction) flips.
    reach, direction = read_out(surface, segment + np.linspace(lo, hi, 4001))
    assert not np.all(reach < 1e4 * surface.frame.scale)
    assert np.dot(direction[0], direction[-1]) < -0.99 * np.linalg.norm(direction[0]) * np.linalg.norm(direction[-1])
    assert np.all(np.isfinite(read_out(surface, rings)[0]))  # the rings alone would not show it


@pytest.mark.parametrize("kind", ["circles", "point_pairs"])
@pytest.mark.parametrize("curve", sorted(CURVES))
def test_aligned_the_same_controls_mesh(tmp_path, kind, curve):
    path = tmp_path / "aligned.yaml"
    path.write_text(scene(kind, curve, CIRCLES if kind == "circles" else PAIRS, align="true", along=33))
    status, _, err = run([path, "-o", tmp_path / "o.glb"])
    assert status == 0, err
    meshes = read_gltf(tmp_path / "o.glb", world=True)
    assert_finite_unit(meshes)
    assert np.abs(meshes[0].positions).max() < 10.0


def test_the_tolerance_path_and_the_motor_interpolation(tmp_path):
    """The tolerance planner scans too; a motor interpolation of the same controls has no line."""
    path = tmp_path / "cross.yaml"
    path.write_text(scene("circles", "linear", CIRCLES))
    refused([path, "-o", tmp_path / "o.glb", "--tolerance", "1e-2"], r"cross\.yaml:3: .*turns into a line")
    path.write_text(scene("circles", "linear", CIRCLES).replace("    align: false\n",
                                                                "    align: false\n    interpolation: motor\n"))
    status, _, err = run([path, "-o", tmp_path / "o.glb"])
    assert status == 0, err


def test_a_fast_but_bounded_turn_is_not_refused(tmp_path):
    """Normals 160 degrees apart, unaligned: the interpolated circle grows (to a few radii) and turns
    fast, but stays a circle; the flip is refined and let through."""
    tilted = "{center: [1.3, 0, 0.7], normal: [-0.9396926207859083, 0.3420201433256687, 0], radius: 0.5}"
    path = tmp_path / "turn.yaml"
    text = scene("circles", "linear", [CIRCLES[0], tilted], along=200)
    path.write_text(text)
    surface = build_surface(parse_scene(text, "turn.yaml").surfaces[0])
    reach = read_out(surface, np.linspace(0.0, 1.0, 2001))[0]
    assert 2.0 < reach.max() < 50.0  # large, bounded
    status, _, err = run([path, "-o", tmp_path / "o.glb"])
    assert status == 0, err
    assert_finite_unit(read_gltf(tmp_path / "o.glb", world=True))


def test_carrier_part_is_normal_over_radius_and_direction_over_half_length():
    rng = np.random.default_rng(7)
    centre, normal = rng.normal(size=(5, 3)), rng.normal(size=(5, 3))
    radius = rng.uniform(0.1, 2.0, 5)
    m = flatness.carrier_part(circle_from_center_normal_radius(centre, normal, radius), 3)
    unit = normal / np.linalg.norm(normal, axis=1, keepdims=True)
    assert np.allclose(m, unit / radius[:, None], rtol=1e-12, atol=1e-12)
    a, b = rng.normal(size=(5, 3)), rng.normal(size=(5, 3))
    d = flatness.carrier_part(point_pair(a, b), 2)
    length_sq = np.einsum("ij,ij->i", b - a, b - a)
    # P = up(a) ^ up(b) / (|b - a|^2 / 2) normalised up to sign; P . n_inf = up(b) - up(a) over that.
    assert np.allclose(np.abs(np.einsum("ij,ij->i", d, (b - a))), 2.0, rtol=1e-10)
    assert np.allclose(np.linalg.norm(d, axis=1), 2.0 / np.sqrt(length_sq), rtol=1e-10)
    assert np.allclose(flatness.reach(d, 2), np.sqrt(length_sq), rtol=1e-10)


@pytest.mark.parametrize("align", ["true", "false"])
@pytest.mark.parametrize("second", ["[1, 0, 0]", "[-1, 0, 0]"])
def test_disjoint_circles_in_one_plane_have_no_blade_interpolation(tmp_path, align, second):
    """Two disjoint circles in one plane: their pencil holds a line between them, so one orientation
    interpolates through it and the other through circles of no real projection; either way one
    located line. The motor interpolation meshes them."""
    controls = ["{center: [0, 0, 2], normal: [1, 0, 0], radius: 0.5}",
                f"{{center: [0, 0.5, 3], normal: {second}, radius: 0.5}}"]
    path = tmp_path / "plane.yaml"
    text = scene("circles", "linear", controls, align=align, along=12)
    path.write_text(text)
    refused([path, "-o", tmp_path / "o.glb"], r"plane\.yaml:3: surfaces\[0\]: surface 's': the interpolated "
                                              r"(circle turns into a line .*alpha = 0\.5, radius unbounded|"
                                              r"object has no blade projection at segment 0, alpha = 0\.5 )")
    path.write_text(text.replace("    controls:", "    interpolation: motor\n    controls:"))
    status, _, err = run([path, "-o", tmp_path / "o.glb"])
    assert status == 0, err
    assert_finite_unit(read_gltf(tmp_path / "o.glb", world=True))


def test_a_ribbon_on_one_line_has_no_area(tmp_path):
    path = tmp_path / "line.yaml"
    path.write_text(scene("point_pairs", "linear", ["{a: [0, 0, 0], b: [1, 0, 0]}", "{a: [3, 0, 0], b: [2, 0, 0]}"]))
    refused([path, "-o", tmp_path / "o.glb"],
            r"line\.yaml:\d+: surfaces\[0\]\.controls: every point pair lies on one line, so the ribbon has no area$")
