"""cgamesh.inputs.scene: valid files become the right dataclasses, every mistake one precise line."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from cgamesh.errors import (DegenerateGeometryError, InvalidInputError, NonFiniteInputError,
                            SceneFileError)
from cgamesh.material import Material
from cgamesh.inputs.scene import (CircleControl, Location, PointPairControl, Scene, SurfaceSpec,
                           load_scene, parse_scene)

FILE = "spline.yaml"

FULL = """\
cgamesh: 1
units: cm
up: y
surfaces:
  - name: tube
    type: circles
    curve: kb
    tension: 0.25
    bias: -1
    continuity: 1e-1
    closed: true
    align: false
    controls:
      - {center: [0, 0, 0], normal: [0, 0, 1], radius: 1.0}
      - {through: [[1, 0, 2], [0, 1, 2], [-1, 0, 2]]}
      - center: [0, 0, 4]
        normal: [0, 1, 1]
        radius: 5e-1
    tolerance: 1.0e-3
    material: {color: [0.8, 0.3, 0.2], roughness: 0.25, metallic: 1}
  - name: ribbon_2
    type: point_pairs
    curve: rational_bezier
    controls:
      - {a: [0, 0, 0], b: [1, 0, 0], weight: 2}
      - {a: [0, 0, 1], b: [1, 0, 1]}
      - {a: [0, 1, 2], b: [1, 1, 2], weight: .5}
    resolution: {around: 2, along: 7}
    caps: false
"""

# A minimal valid scene; the malformed cases below are small edits of it.
BASE = """\
cgamesh: 1
surfaces:
  - name: tube
    type: circles
    curve: linear
    controls:
      - {center: [0, 0, 0], normal: [0, 0, 1], radius: 1.0}
      - {center: [0, 0, 4], normal: [0, 0, 1], radius: 0.5}
"""
C0 = "      - {center: [0, 0, 0], normal: [0, 0, 1], radius: 1.0}"
C1 = "      - {center: [0, 0, 4], normal: [0, 0, 1], radius: 0.5}"
PAIRS = BASE.replace("circles", "point_pairs").replace(C0, "      - {a: [0, 0, 0], b: [1, 0, 0]}") \
    .replace(C1, "      - {a: [0, 0, 1], b: [1, 0, 1]}")


def _edit(text: str, old: str, new: str) -> str:
    assert text.count(old) == 1, old
    return text.replace(old, new)


def test_full_scene_parses_into_the_dataclasses():
    scene = parse_scene(FULL, FILE)
    assert (scene.path, scene.version, scene.units, scene.meters_per_unit, scene.up) == \
        (FILE, 1, "cm", 0.01, "y")
    tube, ribbon = scene.surfaces
    assert tube == SurfaceSpec(
        name="tube", type="circles", curve="kb", tension=0.25, bias=-1.0, continuity=0.1,
        closed=True, align=False,
        controls=(
            CircleControl((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 1.0, None, 1.0,
                          Location(FILE, 14, "surfaces[0].controls[0]")),
            CircleControl(None, None, None, ((1.0, 0.0, 2.0), (0.0, 1.0, 2.0), (-1.0, 0.0, 2.0)),
                          1.0, Location(FILE, 15, "surfaces[0].controls[1]")),
            CircleControl((0.0, 0.0, 4.0), (0.0, 1.0, 1.0), 0.5, None, 1.0,
                          Location(FILE, 16, "surfaces[0].controls[2]")),
        ),
        around=None, along=None, tolerance=1e-3, caps=False,
        material=Material((0.8, 0.3, 0.2), 0.25, 1.0), location=Location(FILE, 5, "surfaces[0]"))
    assert ribbon.controls == (
        PointPairControl((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), 2.0,
                         Location(FILE, 25, "surfaces[1].controls[0]")),
        PointPairControl((0.0, 0.0, 1.0), (1.0, 0.0, 1.0), 1.0,
                         Location(FILE, 26, "surfaces[1].controls[1]")),
        PointPairControl((0.0, 1.0, 2.0), (1.0, 1.0, 2.0), 0.5,
                         Location(FILE, 27, "surfaces[1].controls[2]")),
    )
    assert (ribbon.name, ribbon.type, ribbon.curve, ribbon.around, ribbon.along,
            ribbon.tolerance, ribbon.closed, ribbon.align, ribbon.caps) == \
        ("ribbon_2", "point_pairs", "rational_bezier", 2, 7, None, False, True, False)
    assert ribbon.material == Material((0.8, 0.8, 0.8), 0.5, 0.0)
    assert all(type(c) is float for s in scene.surfaces for c in (s.tension, s.bias, s.continuity))


def test_defaults():
    scene = parse_scene(BASE)
    assert (scene.path, scene.units, scene.meters_per_unit, scene.up) == ("<string>", "m", 1.0, "z")
    (s,) = scene.surfaces
    assert (s.tension, s.bias, s.continuity, s.closed, s.align, s.caps) == \
        (0.0, 0.0, 0.0, False, True, False)
    assert (s.around, s.along, s.tolerance) == (64, 128, None)
    assert s.material == Material((0.8, 0.8, 0.8), 0.5, 0.0)
    assert [c.weight for c in s.controls] == [1.0, 1.0]


@pytest.mark.parametrize("resolution, expected", [
    ("{around: 8}", (8, 128)), ("{along: 3}", (64, 3)), ("{}", (64, 128)),
    ("{around: 1000000, along: 2}", (1_000_000, 2)),
])
def test_partial_resolution_takes_defaults(resolution, expected):
    (s,) = parse_scene(BASE + f"    resolution: {resolution}\n").surfaces
    assert (s.around, s.along, s.tolerance) == (*expected, None)


def test_units_scale():
    assert [parse_scene("units: " + u + "\n" + BASE).meters_per_unit for u in ("m", "cm", "mm")] \
        == [1.0, 0.01, 0.001]


@pytest.mark.parametrize("written, value", [
    ("1e-4", 1e-4), ("1E5", 1e5), ("-2.5e+3", -2500.0), (".5", 0.5), ("-.5", -0.5),
    ("3", 3.0), ("+2.", 2.0), ("0x10", 16.0), ("0o17", 15.0), ("1.5E-300", 1.5e-300),
])
def test_numbers_however_written(written, value):
    (s,) = parse_scene(_edit(BASE, "center: [0, 0, 0]", f"center: [{written}, 0, 0]")).surfaces
    x = s.controls[0].center[0]
    assert type(x) is float and x == value


@given(st.floats(allow_nan=False, allow_infinity=False))
def test_every_finite_float_repr_round_trips(x):
    """Read where any finite number is allowed: a normal's component (its z is 1, so never zero)."""
    (s,) = parse_scene(_edit(BASE, "normal: [0, 0, 1], radius: 1.0", f"normal: [0, {x!r}, 1], radius: 1.0")).surfaces
    assert s.controls[0].normal[1] == x and math.copysign(1, s.controls[0].normal[1]) == \
        math.copysign(1, x)


@pytest.mark.parametrize("value", ["1.0000000000000002e+30", "-1e300", "1.7976931348623157e308"])
def test_coordinates_beyond_float32_outputs_are_refused(value):
    with pytest.raises(SceneFileError, match=r"<string>:7: surfaces\[0\]\.controls\[0\]\.center\[1\] must be "
                                             r"within \+-1e\+30"):
        parse_scene(_edit(BASE, "center: [0, 0, 0]", f"center: [0, {value}, 0]"))


@pytest.mark.parametrize("word", ["yes", "no", "on", "off", "y", "n"])
def test_yaml_1_1_booleans_are_plain_strings(word):
    """The core schema (YAML 1.2) has only true/false; 'no' is a fine surface name."""
    assert parse_scene(_edit(BASE, "name: tube", f"name: {word}")).surfaces[0].name == word


def test_through_keeps_the_given_order_and_tiny_scales_are_fine():
    text = _edit(BASE, C0, "      - {through: [[1e-9, 0, 0], [0, 1e-9, 0], [-1e-9, 0, 0]]}")
    assert parse_scene(text).surfaces[0].controls[0].through == \
        ((1e-9, 0.0, 0.0), (0.0, 1e-9, 0.0), (-1e-9, 0.0, 0.0))


def test_load_scene_reads_a_path(tmp_path: Path):
    path = tmp_path / "s.yaml"
    path.write_text(BASE, encoding="utf-8")
    scene = load_scene(path)
    assert isinstance(scene, Scene) and scene.path == str(path)
    assert scene.surfaces[0].location == Location(str(path), 3, "surfaces[0]")


def test_load_scene_unreadable_file_names_it(tmp_path: Path):
    missing = tmp_path / "nope.yaml"
    with pytest.raises(SceneFileError) as info:
        load_scene(missing)
    assert str(missing) in str(info.value) and "\n" not in str(info.value)


def test_location_str():
    assert str(Location(FILE, 14, "surfaces[0].controls[3].radius")) == \
        "spline.yaml:14: surfaces[0].controls[3].radius"
    assert str(Location(FILE, None, "surfaces")) == "spline.yaml: surfaces"


def test_exact_message():
    text = _edit(BASE, "radius: 0.5}", "radius: 0.0}")
    with pytest.raises(DegenerateGeometryError) as info:
        parse_scene(text, FILE)
    assert str(info.value) == "spline.yaml:8: surfaces[0].controls[1].radius must be > 0, got 0.0"


# Malformed scenes. The expected line is the one carrying the marker "#!" (so no line number
# is counted by hand); key_path None means a YAML syntax error, which has no key path.
M = "  #!"
S0 = "surfaces[0]"
CTL0 = "surfaces[0].controls[0]"
CASES = [
    # structure: missing, unknown and duplicate keys, wrong version
    ("missing cgamesh", BASE.replace("cgamesh: 1\n", "").replace("surfaces:", "surfaces:" + M),
     SceneFileError, "cgamesh"),
    ("wrong version", BASE.replace("cgamesh: 1", "cgamesh: 2" + M), SceneFileError, "cgamesh"),
    ("version as text", BASE.replace("cgamesh: 1", "cgamesh: '1'" + M), SceneFileError, "cgamesh"),
    ("missing surfaces", "cgamesh: 1" + M + "\nunits: m\n", SceneFileError, "surfaces"),
    ("empty surfaces", "cgamesh: 1\nsurfaces: []" + M + "\n", SceneFileError, "surfaces"),
    ("missing curve", _edit(BASE, "    curve: linear\n", "").replace("tube", "tube" + M),
     SceneFileError, f"{S0}.curve"),
    ("missing controls", BASE.split("    controls:")[0].replace("tube", "tube" + M),
     SceneFileError, f"{S0}.controls"),
    ("unknown top key", _edit(BASE, "cgamesh: 1\n", "cgamesh: 1\ncolour: red" + M + "\n"),
     SceneFileError, "colour"),
    ("unknown surface key", BASE + "    colr: 1" + M + "\n", SceneFileError, f"{S0}.colr"),
    ("unknown control key", _edit(BASE, "radius: 1.0}", "radius: 1.0, radiu: 2}" + M),
     SceneFileError, f"{CTL0}.radiu"),
    ("unknown resolution key", BASE + "    resolution:\n      around: 8\n      alng: 4" + M + "\n",
     SceneFileError, f"{S0}.resolution.alng"),
    ("unknown material key", BASE + "    material: {colour: [1, 0, 0]}" + M + "\n",
     SceneFileError, f"{S0}.material.colour"),
    ("circle key on point pair", _edit(PAIRS, "b: [1, 0, 0]}", "b: [1, 0, 0], radius: 1}" + M),
     SceneFileError, f"{CTL0}.radius"),
    ("duplicate key", BASE + "    curve: bezier" + M + "\n", SceneFileError, f"{S0}.curve"),
    ("duplicate top key", BASE + "cgamesh: 1" + M + "\n", SceneFileError, "cgamesh"),
    ("duplicate control key", _edit(BASE, "radius: 1.0}", "radius: 1.0, radius: 2}" + M),
     SceneFileError, f"{CTL0}.radius"),
    # wrong types
    ("quoted number", _edit(BASE, "radius: 1.0}", "radius: '1.0'}" + M), SceneFileError,
     f"{CTL0}.radius"),
    ("bool as number", _edit(BASE, "radius: 1.0}", "radius: true}" + M), SceneFileError,
     f"{CTL0}.radius"),
    ("null as number", _edit(BASE, "radius: 1.0}", "radius: ~}" + M), SceneFileError,
     f"{CTL0}.radius"),
    ("vector of 2", _edit(BASE, C0, C0.replace("[0, 0, 0]", "[0, 0]") + M), SceneFileError,
     f"{CTL0}.center"),
    ("vector item text", _edit(BASE, C0, C0.replace("[0, 0, 0]", "[0, x, 0]") + M),
     SceneFileError, f"{CTL0}.center[1]"),
    ("controls not a list", BASE.split("    controls:")[0] + "    controls: {a: 1}" + M + "\n",
     SceneFileError, f"{S0}.controls"),
    ("surface not a mapping", "cgamesh: 1\nsurfaces:\n  - tube" + M + "\n", SceneFileError,
     "surfaces[0]"),
    ("yes is not a boolean", BASE + "    align: yes" + M + "\n", SceneFileError, f"{S0}.align"),
    ("unknown units", "units: km" + M + "\n" + BASE, SceneFileError, "units"),
    ("unknown type", _edit(BASE, "circles", "spheres" + M), SceneFileError, f"{S0}.type"),
    ("unknown curve", _edit(BASE, "curve: linear", "curve: bspline" + M), SceneFileError,
     f"{S0}.curve"),
    ("bad name", _edit(BASE, "name: tube", "name: my-tube" + M), SceneFileError, f"{S0}.name"),
    ("name starts with digit", _edit(BASE, "name: tube", "name: 2tube" + M), SceneFileError,
     f"{S0}.name"),
    ("duplicate surface name", BASE + BASE.split("surfaces:\n")[1].replace("tube", "tube" + M),
     SceneFileError, "surfaces[1].name"),
    # NaN and infinity, anywhere
    ("nan radius", _edit(BASE, "radius: 1.0}", "radius: .nan}" + M), NonFiniteInputError,
     f"{CTL0}.radius"),
    ("inf in vector", _edit(BASE, C0, C0.replace("[0, 0, 0]", "[0, .inf, 0]") + M),
     NonFiniteInputError, f"{CTL0}.center[1]"),
    ("-inf tolerance", BASE + "    tolerance: -.Inf" + M + "\n", NonFiniteInputError,
     f"{S0}.tolerance"),
    ("overflowing number", _edit(BASE, "radius: 1.0}", "radius: 1e400}" + M),
     NonFiniteInputError, f"{CTL0}.radius"),
    ("overflowing integer", _edit(BASE, "radius: 1.0}", f"radius: {10 ** 400}}}" + M),
     NonFiniteInputError, f"{CTL0}.radius"),
    ("nan resolution", BASE + "    resolution: {around: .nan}" + M + "\n", NonFiniteInputError,
     f"{S0}.resolution.around"),
    ("nan name", _edit(BASE, "name: tube", "name: .NaN" + M), NonFiniteInputError, f"{S0}.name"),
    # degenerate geometry
    ("zero radius", _edit(BASE, "radius: 1.0}", "radius: 0}" + M), DegenerateGeometryError,
     f"{CTL0}.radius"),
    ("negative radius", _edit(BASE, "radius: 1.0}", "radius: -1e-3}" + M),
     DegenerateGeometryError, f"{CTL0}.radius"),
    ("zero normal", _edit(BASE, "normal: [0, 0, 1], radius: 1.0}",
                          "normal: [0, 0.0, 0], radius: 1.0}" + M), DegenerateGeometryError,
     f"{CTL0}.normal"),
    ("collinear through", _edit(BASE, C0, "      - {through: [[0, 0, 0], [1, 1, 1], "
                                "[3, 3, 3]]}" + M), DegenerateGeometryError, f"{CTL0}.through"),
    ("nearly collinear far away", _edit(BASE, C0, "      - {through: [[1e9, 0, 0], "
                                        "[1000000001, 0, 0], [1000000002, 1e-13, 0]]}" + M),
     DegenerateGeometryError, f"{CTL0}.through"),
    ("coincident through", _edit(BASE, C0, "      - through:\n          - [0, 0, 0]\n"
                                 "          - [0, 1, 0]\n          - [0, 0, 0]" + M),
     DegenerateGeometryError, f"{CTL0}.through[2]"),
    ("coincident a b", _edit(PAIRS, "b: [1, 0, 1]}", "b: [0, 0, 1.0]}" + M),
     DegenerateGeometryError, "surfaces[0].controls[1].b"),
    ("coincident a b at scale", _edit(PAIRS, "{a: [0, 0, 1], b: [1, 0, 1]}",
                                      "{a: [1e20, 0, 1], b: [1e20, 0, 1.5]}" + M),
     DegenerateGeometryError, "surfaces[0].controls[1].b"),
    ("through mixed with center", _edit(BASE, C0, "      - {through: [[1, 0, 0], [0, 1, 0], "
                                        "[-1, 0, 0]], center: [0, 0, 0]}" + M),
     SceneFileError, f"{CTL0}.center"),
    ("circle missing radius", _edit(BASE, ", radius: 1.0}", "}" + M), SceneFileError,
     f"{CTL0}.radius"),
    # (a block list starts at its first item, so that is the line of the list node)
    ("fewer than 2 controls", _edit(BASE, C1 + "\n", "").replace(C0, C0 + M),
     SceneFileError, f"{S0}.controls"),
    ("closed with 2 controls", _edit(BASE, "linear", "kb").replace(C0, C0 + M)
     + "    closed: true\n", SceneFileError, f"{S0}.controls"),
    ("flow list of 1 control", BASE.split("    controls:")[0] + "    controls: [{a: [0, 0, 0], "
     "b: [1, 0, 0]}]" + M + "\n", SceneFileError, f"{S0}.controls"),
    # options that depend on the curve or type
    ("weight zero", _edit(BASE, "linear", "rational_bezier").replace("radius: 1.0}",
                                                                     "radius: 1.0, weight: 0}" + M),
     SceneFileError, f"{CTL0}.weight"),
    ("weight negative", _edit(PAIRS, "linear", "rational_bezier")
     .replace("b: [1, 0, 0]}", "b: [1, 0, 0], weight: -2}" + M), SceneFileError, f"{CTL0}.weight"),
    ("weight without rational", _edit(BASE, "radius: 1.0}", "radius: 1.0, weight: 2}" + M),
     SceneFileError, f"{CTL0}.weight"),
    ("tension with catmull_rom", _edit(BASE, "linear", "catmull_rom") + "    tension: 0.5" + M
     + "\n", SceneFileError, f"{S0}.tension"),
    ("bias with bezier", _edit(BASE, "linear", "bezier") + "    bias: 0" + M + "\n",
     SceneFileError, f"{S0}.bias"),
    ("continuity out of range", _edit(BASE, "linear", "kb") + "    continuity: 1.5" + M + "\n",
     SceneFileError, f"{S0}.continuity"),
    ("closed with bezier", _edit(BASE, "linear", "bezier") + "    closed: true" + M + "\n",
     SceneFileError, f"{S0}.closed"),
    ("caps with closed", _edit(BASE, "linear", "kb").replace(C1, C1 + "\n" + C1)
     + "    closed: true\n    caps: true" + M + "\n", SceneFileError, f"{S0}.caps"),
    ("caps on point_pairs", PAIRS + "    caps: true" + M + "\n", SceneFileError, f"{S0}.caps"),
    # resolution
    ("resolution and tolerance", BASE + "    resolution: {around: 8}\n    tolerance: 0.1" + M
     + "\n", SceneFileError, f"{S0}.tolerance"),
    ("zero tolerance", BASE + "    tolerance: 0" + M + "\n", SceneFileError, f"{S0}.tolerance"),
    ("around 2 on circles", BASE + "    resolution: {around: 2}" + M + "\n", SceneFileError,
     f"{S0}.resolution.around"),
    ("around 1 on point_pairs", PAIRS + "    resolution: {around: 1}" + M + "\n", SceneFileError,
     f"{S0}.resolution.around"),
    ("along 1", BASE + "    resolution:\n      along: 1" + M + "\n", SceneFileError,
     f"{S0}.resolution.along"),
    ("around not integer", BASE + "    resolution: {around: 8.5}" + M + "\n", SceneFileError,
     f"{S0}.resolution.around"),
    ("around too large", BASE + "    resolution: {around: 1000001}" + M + "\n", SceneFileError,
     f"{S0}.resolution.around"),
    ("color out of range", BASE + "    material:\n      color: [0, 1.5, 0]" + M + "\n",
     SceneFileError, f"{S0}.material.color[1]"),
    ("roughness out of range", BASE + "    material: {roughness: -0.1}" + M + "\n",
     SceneFileError, f"{S0}.material.roughness"),
    # YAML syntax
    ("yaml bad mapping", _edit(BASE, "curve: linear", "curve: linear: x" + M), SceneFileError,
     None),
    ("yaml tab", _edit(BASE, "    curve: linear", "\tcurve: linear" + M), SceneFileError, None),
    ("yaml empty document", "# nothing" + M + "\n", SceneFileError, None),
    ("yaml not a mapping", "- 1" + M + "\n", SceneFileError, None),
]


@pytest.mark.parametrize("text, error, key_path",
                         [pytest.param(*case[1:], id=case[0]) for case in CASES])
def test_malformed_scene_is_one_precise_line(text, error, key_path):
    lines = text.splitlines()
    (line,) = [n for n, line in enumerate(lines, 1) if "#!" in line]
    with pytest.raises(InvalidInputError) as info:
        parse_scene(text, FILE)
    message = str(info.value)
    assert type(info.value) is error, message
    assert "\n" not in message
    assert message.startswith(f"{FILE}:{line}: "), message
    if key_path is not None:
        assert message.startswith(f"{FILE}:{line}: {key_path} "), message
        assert " must " in message or " is not a known key" in message, message
