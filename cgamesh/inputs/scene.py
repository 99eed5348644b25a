"""Read a YAML scene file (format: shared/spec/scene-format.md) into validated, immutable specs.

Every mistake in a file raises one exception whose ``str()`` is a single line naming the file,
the line of the offending YAML node, its key path, what was expected and what was got::

    spline.yaml:14: surfaces[0].controls[3].radius must be > 0, got 0.0

NaN / infinity raise ``NonFiniteInputError``, geometry without meaning (zero normal, radius <= 0,
coincident or collinear points) ``DegenerateGeometryError``, anything else ``SceneFileError``;
all three are ``InvalidInputError``. Lines come from ``yaml.compose`` node marks, so the file is
walked as a node tree here instead of being loaded into plain dicts first.
"""

from __future__ import annotations

import os
import re
from dataclasses import replace

import yaml

from cgamesh.errors import DegenerateGeometryError, SceneFileError
from cgamesh.inputs.scene_rendering import parse_rendering
from cgamesh.inputs.scene_rules import (CIRCLE_FORMS, CIRCLE_KEYS, CLOSABLE_CURVES, CURVES, DEFAULT_ALONG,
                                        DEFAULT_AROUND, INTERPOLATIONS, MAX_RESOLUTION, MAX_WEIGHT_RATIO,
                                        METERS_PER_UNIT, NAME_PATTERN, POINT_PAIR_KEYS, SUPPORTED_VERSIONS,
                                        SURFACE_KEYS, SURFACE_TYPES, TOP_KEYS, UP_AXES, UV_MODES, coincident,
                                        collinear)
from cgamesh.inputs.scene_specs import CircleControl, Location, PointPairControl, Scene, SurfaceSpec, Vec3
from cgamesh.inputs.scene_yaml import Reader, compose
from cgamesh.material import Material

__all__ = ["CircleControl", "Location", "PointPairControl", "Scene", "SurfaceSpec", "load_scene", "parse_scene"]


def load_scene(path: str | os.PathLike, rendering: bool = True, fast: bool = True) -> Scene:
    """Read and validate the scene file at ``path`` (UTF-8, an optional BOM allowed).

    ``rendering``: also read the rendering keys (camera, lights, objects, ...); meshing leaves
    them unread, so a mistake there stops only the commands that render. ``fast``: try the
    fast path first (see ``parse_scene``).
    """
    file = os.fsdecode(path)
    try:
        with open(file, encoding="utf-8-sig") as stream:
            text = stream.read()
    except OSError as exc:
        raise SceneFileError(f"{file}: cannot read the scene file: {exc.strerror or exc}") from exc
    except UnicodeDecodeError as exc:
        line = exc.object.count(b"\n", 0, exc.start) + 1
        column = exc.start - (exc.object.rfind(b"\n", 0, exc.start) + 1) + 1
        raise SceneFileError(
            f"{file}:{line}: the scene file must be UTF-8 text, got byte 0x{exc.object[exc.start]:02x} "
            f"in column {column}") from exc
    return parse_scene(text, file, rendering, fast)


def parse_scene(text: str, path: str = "<string>", rendering: bool = True,
                fast: bool = True) -> Scene:
    """Validate scene-file ``text``; ``path`` only names the file in error messages;
    ``rendering`` as for ``load_scene``.

    ``fast``: first try the fast path (cgamesh.inputs.scene_fast), which returns the same
    Scene for the common shape of scene files or steps aside; this careful reader, which keeps
    every node's line, then decides and names the line of any mistake. False: the careful
    reader alone (the reference the fast path is tested against)."""
    if fast:
        from cgamesh.inputs.scene_fast import read_fast
        scene = read_fast(text, path, rendering)
        if scene is not None:
            return scene
    root = compose(text, path)
    r = Reader(path)
    if root is None:
        raise SceneFileError(f"{path}:1: the scene must be a mapping starting with 'cgamesh: 1', "
                             "got an empty document")
    entries = r.mapping(root, "")
    # The version comes first: a newer file's unknown keys are explained by its version.
    version_node = r.require(root, entries, "cgamesh", "", "the format version, 1")
    version = r.scalar(version_node, "cgamesh")
    if type(version) is not int or version not in SUPPORTED_VERSIONS:
        supported = ", ".join(map(str, SUPPORTED_VERSIONS))
        raise r.wrong(version_node, "cgamesh", f"a supported format version ({supported})")
    r.reject_unknown(root, "", TOP_KEYS)
    units = r.optional(entries, "units", "", "m", r.choice, tuple(METERS_PER_UNIT))
    up = r.optional(entries, "up", "", "z", r.choice, UP_AXES)

    surfaces_node = r.require(root, entries, "surfaces", "", "a list of surfaces")
    items = r.sequence(surfaces_node, "surfaces", "a non-empty list of surfaces")
    if not items:
        raise r.wrong(surfaces_node, "surfaces", "a non-empty list of surfaces")
    names_taken: dict[str, Location] = {}
    surfaces = tuple(_surface(r, item, f"surfaces[{i}]", names_taken)
                     for i, item in enumerate(items))
    scene = Scene(path, version, units, METERS_PER_UNIT[units], up, surfaces)
    if not rendering:
        return scene
    keys = parse_rendering(r, entries, up)
    return replace(scene, camera=keys.camera, lights=keys.lights, objects=keys.objects,
                   background=keys.background, max_depth=keys.max_depth, attenuation=keys.attenuation)




# --- sections ----------------------------------------------------------------------------------

def _surface(r: Reader, node: yaml.Node, path: str,
             names_taken: dict[str, Location]) -> SurfaceSpec:
    """One entry of ``surfaces``; ``names_taken`` (name -> where) gains this surface's name."""
    entries = r.mapping(node, path, SURFACE_KEYS)
    name_node = r.require(node, entries, "name", path, f"a name matching {NAME_PATTERN}")
    name = r.scalar(name_node, f"{path}.name")
    if type(name) is not str or not re.fullmatch(NAME_PATTERN, name):
        raise r.wrong(name_node, f"{path}.name", f"a name matching {NAME_PATTERN}")
    if name in names_taken:
        first = names_taken[name]
        raise r.error(name_node, f"{path}.name", f"must be unique, got {name!r} again (first used "
                                                 f"by {first.key_path} on line {first.line})")
    names_taken[name] = r.location(node, path)
    kind = r.choice(r.require(node, entries, "type", path, f"one of {', '.join(SURFACE_TYPES)}"),
                    f"{path}.type", SURFACE_TYPES)
    curve = r.choice(r.require(node, entries, "curve", path, f"one of {', '.join(CURVES)}"),
                     f"{path}.curve", CURVES)

    tension, bias, continuity = (_kb_parameter(r, entries, key, path, curve)
                                 for key in ("tension", "bias", "continuity"))
    closed = r.optional(entries, "closed", path, False, r.boolean)
    if closed and curve not in CLOSABLE_CURVES:
        raise r.error(entries["closed"], f"{path}.closed",
                      f"must be false unless curve is kb or catmull_rom, got true with "
                      f"curve {curve}")
    align = r.optional(entries, "align", path, True, r.boolean)
    caps = r.optional(entries, "caps", path, False, r.boolean)
    if caps and kind != "circles":
        raise r.error(entries["caps"], f"{path}.caps",
                      f"must be false for type {kind} (caps close a tube's ends), got true")
    if caps and closed:
        raise r.error(entries["caps"], f"{path}.caps",
                      "must be false when closed is true (a closed tube has no ends), got true")

    interpolation = r.optional(entries, "interpolation", path, "blade", r.choice, INTERPOLATIONS)
    if interpolation == "motor" and kind != "circles":
        raise r.error(entries["interpolation"], f"{path}.interpolation",
                      f"must be blade for type {kind} (motor carries circles by similarity motions; "
                      "a point pair has no motor interpolation), got motor")

    controls_node = r.require(node, entries, "controls", path, "a list of controls")
    controls = _controls(r, controls_node, f"{path}.controls", kind, curve, closed)
    around, along, tolerance = _resolution(r, entries, path, kind)
    material = _material(r, entries, path)
    uv = r.optional(entries, "uv", path, "natural", r.choice, UV_MODES)
    uv_scale = None
    if "uv_scale" in entries:
        scale_node = entries["uv_scale"]
        uv_scale = r.number(scale_node, f"{path}.uv_scale")
        if uv != "natural":
            raise r.error(scale_node, f"{path}.uv_scale",
                          f"must be given only with uv natural, got {uv_scale!r} with uv {uv}")
        if uv_scale <= 0.0:
            raise r.error(scale_node, f"{path}.uv_scale", f"must be > 0, got {uv_scale!r}")
    return SurfaceSpec(name, kind, curve, tension, bias, continuity, closed, align, controls,
                       around, along, tolerance, caps, material, r.location(node, path), uv, uv_scale,
                       interpolation)


def _kb_parameter(r: Reader, entries: dict, key: str, path: str, curve: str) -> float:
    """tension / bias / continuity: in [-1, 1], meaningful (so allowed) only with curve kb."""
    if key not in entries:
        return 0.0
    node, key_path = entries[key], f"{path}.{key}"
    value = r.number_in(node, key_path, -1.0, 1.0)
    if curve != "kb":
        raise r.error(node, key_path, f"must be given only with curve kb, got {value!r} with "
                                      f"curve {curve}")
    return value


def _controls(r: Reader, node: yaml.Node, path: str, kind: str, curve: str,
              closed: bool) -> tuple[CircleControl | PointPairControl, ...]:
    minimum = 3 if closed else 2
    expected = f"a list of at least {minimum} controls" + (" (closed is true)" if closed else "")
    items = r.sequence(node, path, expected)
    if len(items) < minimum:
        raise r.wrong(node, path, expected)
    read = _circle if kind == "circles" else _point_pair
    controls = tuple(read(r, item, f"{path}[{i}]", curve) for i, item in enumerate(items))
    largest = max(control.weight for control in controls)
    for control in controls:
        # Only the ratios of weights matter; a control weighing 1e-12 of another is absent
        # except at its own end, where the curve would jump.
        if control.weight * MAX_WEIGHT_RATIO < largest:
            raise SceneFileError(f"{control.location}.weight must be at least {1.0 / MAX_WEIGHT_RATIO:g} "
                                 f"times the largest weight ({largest!r}), got {control.weight!r}")
    return controls


def _weight(r: Reader, entries: dict, path: str, curve: str) -> float:
    """A control's weight: > 0, meaningful (so allowed) only with curve rational_bezier."""
    if "weight" not in entries:
        return 1.0
    node, key_path = entries["weight"], f"{path}.weight"
    value = r.number(node, key_path)
    if curve != "rational_bezier":
        raise r.error(node, key_path, f"must be given only with curve rational_bezier, "
                                      f"got {value!r} with curve {curve}")
    if value <= 0.0:
        raise r.error(node, key_path, f"must be > 0, got {value!r}")
    return value


def _circle(r: Reader, node: yaml.Node, path: str, curve: str) -> CircleControl:
    entries = r.mapping(node, path, CIRCLE_KEYS)
    weight = _weight(r, entries, path, curve)
    if "through" in entries:
        for key in ("center", "normal", "radius"):
            if key in entries:
                raise r.error(entries[key], f"{path}.{key}",
                              f"must not be given together with through ({CIRCLE_FORMS}), "
                              f"got both")
        through = _through(r, entries["through"], f"{path}.through")
        return CircleControl(None, None, None, through, weight, r.location(node, path))
    center = r.position(r.require(node, entries, "center", path, CIRCLE_FORMS), f"{path}.center")
    normal_node = r.require(node, entries, "normal", path, CIRCLE_FORMS)
    normal = r.vector3(normal_node, f"{path}.normal")
    if normal == (0.0, 0.0, 0.0):
        raise r.error(normal_node, f"{path}.normal", f"must be non-zero, got {_fmt(normal)}",
                      DegenerateGeometryError)
    radius_node = r.require(node, entries, "radius", path, CIRCLE_FORMS)
    radius = r.length(radius_node, f"{path}.radius")
    if radius <= 0.0:
        raise r.error(radius_node, f"{path}.radius", f"must be > 0, got {radius!r}",
                      DegenerateGeometryError)
    return CircleControl(center, normal, radius, None, weight, r.location(node, path))


def _through(r: Reader, node: yaml.Node, path: str) -> tuple[Vec3, Vec3, Vec3]:
    """Three pairwise distinct, non-collinear points, the circle A ^ B ^ D in that order."""
    items = r.sequence(node, path, "a list of 3 points [A, B, D]")
    if len(items) != 3:
        raise r.wrong(node, path, "a list of 3 points [A, B, D]")
    a, b, d = points = tuple(r.position(item, f"{path}[{i}]") for i, item in enumerate(items))
    for i, j in ((0, 1), (0, 2), (1, 2)):
        if coincident(points[i], points[j]):
            raise r.error(items[j], f"{path}[{j}]", f"must differ from through[{i}] = "
                          f"{_fmt(points[i])}, got {_fmt(points[j])}", DegenerateGeometryError)
    if collinear(a, b, d):
        raise r.error(node, path, f"must be 3 points not on one line, got {_fmt(a)}, {_fmt(b)}, "
                                  f"{_fmt(d)}", DegenerateGeometryError)
    return a, b, d


def _point_pair(r: Reader, node: yaml.Node, path: str, curve: str) -> PointPairControl:
    entries = r.mapping(node, path, POINT_PAIR_KEYS)
    weight = _weight(r, entries, path, curve)
    a = r.position(r.require(node, entries, "a", path, "a point pair is {a, b}"), f"{path}.a")
    b_node = r.require(node, entries, "b", path, "a point pair is {a, b}")
    b = r.position(b_node, f"{path}.b")
    if coincident(a, b):
        raise r.error(b_node, f"{path}.b", f"must differ from a = {_fmt(a)}, got {_fmt(b)}",
                      DegenerateGeometryError)
    return PointPairControl(a, b, weight, r.location(node, path))


def _resolution(r: Reader, entries: dict, path: str,
                kind: str) -> tuple[int | None, int | None, float | None]:
    """(around, along, tolerance): either both counts or the tolerance is set."""
    if "tolerance" in entries:
        node = entries["tolerance"]
        if "resolution" in entries:
            raise r.error(node, f"{path}.tolerance", "must not be given together with resolution "
                          f"(line {entries['resolution'].start_mark.line + 1}), got both")
        tolerance = r.number(node, f"{path}.tolerance")
        if tolerance <= 0.0:
            raise r.error(node, f"{path}.tolerance", f"must be > 0, got {tolerance!r}")
        return None, None, tolerance
    if "resolution" not in entries:
        return DEFAULT_AROUND, DEFAULT_ALONG, None
    res_path = f"{path}.resolution"
    res = r.mapping(entries["resolution"], res_path, ("around", "along"))
    # Across a ribbon two vertices (its two edges) suffice; around a circle three at least.
    least_around = 3 if kind == "circles" else 2
    around = r.optional(res, "around", res_path, DEFAULT_AROUND,
                        r.integer, least_around, MAX_RESOLUTION)
    along = r.optional(res, "along", res_path, DEFAULT_ALONG, r.integer, 2, MAX_RESOLUTION)
    return around, along, None


def _material(r: Reader, entries: dict, path: str) -> Material:
    default = Material()
    if "material" not in entries:
        return default
    mat_path = f"{path}.material"
    mat = r.mapping(entries["material"], mat_path, ("color", "roughness", "metallic"))
    color = default.color
    if "color" in mat:
        color = r.vector3(mat["color"], f"{mat_path}.color")
        for i, (item, value) in enumerate(zip(mat["color"].value, color)):
            if not 0.0 <= value <= 1.0:
                raise r.error(item, f"{mat_path}.color[{i}]", f"must be in [0, 1], got {value!r}")
    roughness = r.optional(mat, "roughness", mat_path, default.roughness, r.number_in, 0.0, 1.0)
    metallic = r.optional(mat, "metallic", mat_path, default.metallic, r.number_in, 0.0, 1.0)
    return Material(color, roughness, metallic)




def _fmt(v: Vec3) -> str:
    return "[" + ", ".join(repr(c) for c in v) + "]"

