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

import difflib
import math
import os
import re
from dataclasses import dataclass, replace

import yaml

from cgamesh.errors import (DegenerateGeometryError, InvalidInputError, NonFiniteInputError,
                            SceneFileError)
from cgamesh.material import Material
from cgamesh.inputs.scene_rendering import (RENDERING_KEYS, Attenuation, CameraSpec, LightSpec, ObjectSpec,
                                      parse_rendering)

Vec3 = tuple[float, float, float]

SUPPORTED_VERSIONS = (1,)
METERS_PER_UNIT = {"m": 1.0, "cm": 0.01, "mm": 0.001}
UP_AXES = ("z", "y")
SURFACE_TYPES = ("circles", "point_pairs")
CURVES = ("linear", "bezier", "rational_bezier", "kb", "catmull_rom")
CLOSABLE_CURVES = ("kb", "catmull_rom")
DEFAULT_AROUND = 64
DEFAULT_ALONG = 128
MAX_RESOLUTION = 1_000_000
# Coordinates and radii: float32 (every output file's positions) reaches 3.4e38; the margin
# leaves room for surfaces that bulge past their controls.
MAX_LENGTH = 1e30
MAX_WEIGHT_RATIO = 1e12  # largest / smallest rational Bezier weight of one surface
NAME_PATTERN = "[A-Za-z_][A-Za-z0-9_]*"

_TOP_KEYS = ("cgamesh", "units", "up", "surfaces") + RENDERING_KEYS
_SURFACE_KEYS = ("name", "type", "curve", "tension", "bias", "continuity", "closed", "align",
                 "controls", "resolution", "tolerance", "caps", "material", "uv", "uv_scale",
                 "interpolation")
INTERPOLATIONS = ("blade", "motor")
UV_MODES = ("natural", "xatlas", "none")
_CIRCLE_KEYS = ("center", "normal", "radius", "through", "weight")
_POINT_PAIR_KEYS = ("a", "b", "weight")
_CIRCLE_FORMS = "a circle is {center, normal, radius} or {through: [A, B, D]}"
# Relative tolerance of the degeneracy tests; they are scale-free, so any unit works.
_DEGENERATE_RTOL = 1e-12


# --- public data -------------------------------------------------------------------------------

@dataclass(frozen=True)
class Location:
    """Where a value sits in a scene file: the path as given, 1-based line, key path."""

    file: str
    line: int | None
    key_path: str

    def __str__(self) -> str:
        """``spline.yaml:14: surfaces[0].controls[3].radius`` (parts that are unknown left out)."""
        text = self.file if self.line is None else f"{self.file}:{self.line}"
        return f"{text}: {self.key_path}" if self.key_path else text


@dataclass(frozen=True)
class CircleControl:
    """A circle control, in file units; exactly one form is set.

    Either ``center`` (3,), ``normal`` (3,, non-zero, not normalised) and ``radius`` (> 0), or
    ``through``: three distinct, non-collinear points (3, 3) in the order given.
    ``weight`` > 0 (1.0 unless given; only given with curve rational_bezier).
    """

    center: Vec3 | None
    normal: Vec3 | None
    radius: float | None
    through: tuple[Vec3, Vec3, Vec3] | None
    weight: float
    location: Location


@dataclass(frozen=True)
class PointPairControl:
    """A point pair up(a) ^ up(b): end points (3,) each, in file units, not coincident."""

    a: Vec3
    b: Vec3
    weight: float
    location: Location


@dataclass(frozen=True)
class SurfaceSpec:
    """One surface of the scene, validated; it becomes one mesh.

    ``around``/``along`` are set (and ``tolerance`` is None) unless the file gives a tolerance
    (file units), in which case both are None. ``tension``/``bias``/``continuity`` are 0.0 for
    every curve but kb. ``uv`` is one of UV_MODES; ``uv_scale`` (file units per texture repeat,
    > 0) is given only with uv natural, None otherwise. ``interpolation`` says how circles are
    interpolated: ``blade`` (the paper's blend of 3-blades, projected) or ``motor`` (each circle
    carried by a similarity motion, docs/interpolation.md).
    """

    name: str
    type: str
    curve: str
    tension: float
    bias: float
    continuity: float
    closed: bool
    align: bool
    controls: tuple[CircleControl | PointPairControl, ...]
    around: int | None
    along: int | None
    tolerance: float | None
    caps: bool
    material: Material
    location: Location
    uv: str = "natural"
    uv_scale: float | None = None
    interpolation: str = "blade"


@dataclass(frozen=True)
class Scene:
    """A whole scene file: format version, units and up axis of the file, its surfaces in order.

    The rendering keys (cgamesh.inputs.scene_rendering) are optional: ``camera`` None and ``lights``
    None when not given (the renderer then frames and lights the scene itself).
    """

    path: str
    version: int
    units: str
    meters_per_unit: float
    up: str
    surfaces: tuple[SurfaceSpec, ...]
    camera: CameraSpec | None = None
    lights: tuple[LightSpec, ...] | None = None
    objects: tuple[ObjectSpec, ...] = ()
    background: tuple[float, float, float] = (0.0, 0.0, 0.0)
    max_depth: int = 2
    attenuation: Attenuation = Attenuation()


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
        from cgamesh.inputs.scene_fast import read_fast  # it imports this module
        scene = read_fast(text, path, rendering)
        if scene is not None:
            return scene
    root = _compose(text, path)
    r = _Reader(path)
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
    r.reject_unknown(root, "", _TOP_KEYS)
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

def _surface(r: _Reader, node: yaml.Node, path: str,
             names_taken: dict[str, Location]) -> SurfaceSpec:
    """One entry of ``surfaces``; ``names_taken`` (name -> where) gains this surface's name."""
    entries = r.mapping(node, path, _SURFACE_KEYS)
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


def _kb_parameter(r: _Reader, entries: dict, key: str, path: str, curve: str) -> float:
    """tension / bias / continuity: in [-1, 1], meaningful (so allowed) only with curve kb."""
    if key not in entries:
        return 0.0
    node, key_path = entries[key], f"{path}.{key}"
    value = r.number_in(node, key_path, -1.0, 1.0)
    if curve != "kb":
        raise r.error(node, key_path, f"must be given only with curve kb, got {value!r} with "
                                      f"curve {curve}")
    return value


def _controls(r: _Reader, node: yaml.Node, path: str, kind: str, curve: str,
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


def _weight(r: _Reader, entries: dict, path: str, curve: str) -> float:
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


def _circle(r: _Reader, node: yaml.Node, path: str, curve: str) -> CircleControl:
    entries = r.mapping(node, path, _CIRCLE_KEYS)
    weight = _weight(r, entries, path, curve)
    if "through" in entries:
        for key in ("center", "normal", "radius"):
            if key in entries:
                raise r.error(entries[key], f"{path}.{key}",
                              f"must not be given together with through ({_CIRCLE_FORMS}), "
                              f"got both")
        through = _through(r, entries["through"], f"{path}.through")
        return CircleControl(None, None, None, through, weight, r.location(node, path))
    center = r.position(r.require(node, entries, "center", path, _CIRCLE_FORMS), f"{path}.center")
    normal_node = r.require(node, entries, "normal", path, _CIRCLE_FORMS)
    normal = r.vector3(normal_node, f"{path}.normal")
    if normal == (0.0, 0.0, 0.0):
        raise r.error(normal_node, f"{path}.normal", f"must be non-zero, got {_fmt(normal)}",
                      DegenerateGeometryError)
    radius_node = r.require(node, entries, "radius", path, _CIRCLE_FORMS)
    radius = r.length(radius_node, f"{path}.radius")
    if radius <= 0.0:
        raise r.error(radius_node, f"{path}.radius", f"must be > 0, got {radius!r}",
                      DegenerateGeometryError)
    return CircleControl(center, normal, radius, None, weight, r.location(node, path))


def _through(r: _Reader, node: yaml.Node, path: str) -> tuple[Vec3, Vec3, Vec3]:
    """Three pairwise distinct, non-collinear points, the circle A ^ B ^ D in that order."""
    items = r.sequence(node, path, "a list of 3 points [A, B, D]")
    if len(items) != 3:
        raise r.wrong(node, path, "a list of 3 points [A, B, D]")
    a, b, d = points = tuple(r.position(item, f"{path}[{i}]") for i, item in enumerate(items))
    for i, j in ((0, 1), (0, 2), (1, 2)):
        if _coincident(points[i], points[j]):
            raise r.error(items[j], f"{path}[{j}]", f"must differ from through[{i}] = "
                          f"{_fmt(points[i])}, got {_fmt(points[j])}", DegenerateGeometryError)
    if _collinear(a, b, d):
        raise r.error(node, path, f"must be 3 points not on one line, got {_fmt(a)}, {_fmt(b)}, "
                                  f"{_fmt(d)}", DegenerateGeometryError)
    return a, b, d


def _point_pair(r: _Reader, node: yaml.Node, path: str, curve: str) -> PointPairControl:
    entries = r.mapping(node, path, _POINT_PAIR_KEYS)
    weight = _weight(r, entries, path, curve)
    a = r.position(r.require(node, entries, "a", path, "a point pair is {a, b}"), f"{path}.a")
    b_node = r.require(node, entries, "b", path, "a point pair is {a, b}")
    b = r.position(b_node, f"{path}.b")
    if _coincident(a, b):
        raise r.error(b_node, f"{path}.b", f"must differ from a = {_fmt(a)}, got {_fmt(b)}",
                      DegenerateGeometryError)
    return PointPairControl(a, b, weight, r.location(node, path))


def _resolution(r: _Reader, entries: dict, path: str,
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


def _material(r: _Reader, entries: dict, path: str) -> Material:
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


# --- geometry checks (scale-free, so they hold in any unit) ------------------------------------

def _scaled(*points: Vec3) -> tuple[Vec3, ...]:
    """The points over their largest |coordinate|: no overflow below, and the tests are relative."""
    scale = max(abs(c) for p in points for c in p)
    if scale == 0.0:
        return points
    return tuple(tuple(c / scale for c in p) for p in points)


def _coincident(p: Vec3, q: Vec3) -> bool:
    """|p - q| <= 1e-12 * max(|p|, |q|, tiny)."""
    p, q = _scaled(p, q)
    gap = math.hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2])
    return gap <= _DEGENERATE_RTOL * max(math.hypot(*p), math.hypot(*q), 1e-300)


def _collinear(a: Vec3, b: Vec3, d: Vec3) -> bool:
    """|(B - A) x (D - A)| <= 1e-12 * |B - A| * |D - A|."""
    a, b, d = _scaled(a, b, d)
    u = (b[0] - a[0], b[1] - a[1], b[2] - a[2])
    v = (d[0] - a[0], d[1] - a[1], d[2] - a[2])
    cross = math.hypot(u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                       u[0] * v[1] - u[1] * v[0])
    return cross <= _DEGENERATE_RTOL * math.hypot(*u) * math.hypot(*v)


def _fmt(v: Vec3) -> str:
    return "[" + ", ".join(repr(c) for c in v) + "]"


# --- YAML: core-schema loading and the node-walking helpers ------------------------------------

_STR, _NULL, _BOOL, _INT, _FLOAT = (f"tag:yaml.org,2002:{t}"
                                    for t in ("str", "null", "bool", "int", "float"))
# YAML 1.2 core schema. PyYAML resolves by YAML 1.1, where 1e-4 (no dot) is a string and
# yes / on / no are booleans; people writing scene files by hand mean the 1.2 reading.
_CORE_PATTERNS = {
    _NULL: re.compile(r"(?:~|null|Null|NULL|)\Z"),
    _BOOL: re.compile(r"(?:true|True|TRUE|false|False|FALSE)\Z"),
    _INT: re.compile(r"(?:[-+]?[0-9]+|0o[0-7]+|0x[0-9a-fA-F]+)\Z"),
    _FLOAT: re.compile(r"(?:[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?"
                       r"|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))\Z"),
}


class _CoreLoader(yaml.SafeLoader):
    """SafeLoader resolving plain scalars by the YAML 1.2 core schema only."""

    # Key None: tried for every plain scalar. The first match wins, so "1" stays an int.
    yaml_implicit_resolvers = {None: [(tag, _CORE_PATTERNS[tag])
                                      for tag in (_NULL, _BOOL, _INT, _FLOAT)]}

    def scan_to_next_token(self) -> None:
        """PyYAML's, also skipping tabs between tokens of a line (YAML 1.2's s-separate-in-line:
        ``[1,<tab>2]`` is valid). A tab in a block line's indentation is still refused."""
        while True:
            super().scan_to_next_token()
            if self.peek() != "\t" or not self._within_line():
                return
            while self.peek() in " \t":
                self.forward()

    def _within_line(self) -> bool:
        """In a flow collection, or past the indentation of the current line."""
        return self.flow_level > 0 or self.buffer[self.pointer - self.column:self.pointer].strip(" ") != ""


def _compose(text: str, file: str) -> yaml.Node | None:
    """The document's node tree (None if empty); YAML errors become one-line SceneFileErrors."""
    try:
        return yaml.compose(text, Loader=_CoreLoader)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        where = f"{file}:{mark.line + 1}" if mark else file
        problem = exc.problem or exc.context or "syntax error"
        if exc.context and exc.problem and exc.problem.startswith("but "):
            problem = f"{exc.context}, {exc.problem}"  # "expected a single document, but found ..."
        elif exc.context and exc.problem and exc.context_mark:
            problem += f" ({exc.context} on line {exc.context_mark.line + 1})"
        raise SceneFileError(f"{where}: invalid YAML: {' '.join(problem.split())}") from exc
    except yaml.reader.ReaderError as exc:
        line = text.count("\n", 0, exc.position) + 1
        raise SceneFileError(f"{file}:{line}: invalid YAML: character #x{exc.character:04x} is "
                             f"not allowed ({exc.reason})") from exc
    except RecursionError as exc:
        depth, line = _deepest(text)
        raise SceneFileError(f"{file}:{line}: invalid YAML: nested too deeply ({depth} levels of "
                             "lists and mappings)") from exc


def _deepest(text: str) -> tuple[int, int]:
    """(greatest nesting depth, 1-based line where it is first reached) of a YAML text, from its
    parse events: the parser keeps an explicit stack, so this works where composing the node
    tree (recursive) runs out of stack."""
    depth = deepest = 0
    line = 1
    for event in yaml.parse(text, Loader=_CoreLoader):
        if isinstance(event, (yaml.SequenceStartEvent, yaml.MappingStartEvent)):
            depth += 1
            if depth > deepest:
                deepest, line = depth, event.start_mark.line + 1
        elif isinstance(event, (yaml.SequenceEndEvent, yaml.MappingEndEvent)):
            depth -= 1
    return deepest, line


def _core_value(node: yaml.ScalarNode) -> object:
    """A scalar node's value: str, None, bool, int or float (maybe NaN/inf). ValueError for a
    tag the scene format does not use or a text that does not fit its (explicit) tag."""
    text, tag = node.value, node.tag
    if tag == _STR:
        return text
    if tag not in _CORE_PATTERNS or not _CORE_PATTERNS[tag].match(text):
        raise ValueError(f"{text!r} tagged {tag}")
    if tag == _NULL:
        return None
    if tag == _BOOL:
        return text.lower() == "true"
    if tag == _INT:
        base = {"0o": 8, "0x": 16}.get(text[:2], 10)
        return int(text if base == 10 else text[2:], base)
    lowered = text.lower()
    if lowered.endswith(".inf"):
        return -math.inf if lowered.startswith("-") else math.inf
    return math.nan if lowered == ".nan" else float(text)


def _describe(node: yaml.Node) -> str:
    """What a node holds, for the 'got ...' half of a message."""
    if isinstance(node, yaml.MappingNode):
        return "a mapping"
    if isinstance(node, yaml.SequenceNode):
        n = len(node.value)
        return "an empty list" if n == 0 else f"a list of {n} item{'s' * (n != 1)}"
    try:
        value = _core_value(node)
    except ValueError as exc:
        return str(exc)
    if value is None or type(value) is float:
        return "null" if value is None else repr(value)
    if type(value) is bool:
        return f"{str(value).lower()} (a boolean)"
    return f"{value!r} (a string)" if type(value) is str else f"{value} (an integer)"


_NOT_SCALAR = object()


class _Reader:
    """Checked values out of one file's nodes: methods take ``(node, key_path, ...)`` and return
    plain Python values; ``error`` / ``wrong`` build the one-line exception for callers to raise."""

    def __init__(self, file: str) -> None:
        self.file = file

    def location(self, node: yaml.Node, path: str) -> Location:
        return Location(self.file, node.start_mark.line + 1, path)

    def error(self, node: yaml.Node, path: str, detail: str,
              kind: type[InvalidInputError] = SceneFileError) -> InvalidInputError:
        """``file:line: key.path <detail>``, e.g. detail = "must be > 0, got 0.0"."""
        where = self.location(node, path)
        return kind(f"{where} {detail}" if path else f"{where}: the scene {detail}")

    def wrong(self, node: yaml.Node, path: str, expected: str) -> InvalidInputError:
        """``... must be <expected>, got <what the node holds>``; NaN / inf anywhere counts as
        a non-finite input rather than a format mistake."""
        got = _describe(node)  # which shows a float as its repr
        kind = NonFiniteInputError if got in ("nan", "inf", "-inf") else SceneFileError
        return self.error(node, path, f"must be {expected}, got {got}", kind)

    def scalar(self, node: yaml.Node, path: str) -> object:
        """The value of a scalar node, ``_NOT_SCALAR`` for a list or mapping."""
        if not isinstance(node, yaml.ScalarNode):
            return _NOT_SCALAR
        try:
            return _core_value(node)
        except ValueError as exc:
            raise self.error(node, path, f"must be a plain value, got {exc}") from None

    def mapping(self, node: yaml.Node, path: str,
                allowed: tuple[str, ...] | None = None) -> dict[str, yaml.Node]:
        """key -> value node of a mapping with string keys, each once and (if given) allowed."""
        if not isinstance(node, yaml.MappingNode):
            raise self.wrong(node, path, "a mapping")
        entries: dict[str, yaml.Node] = {}
        first_line: dict[str, int] = {}
        for key_node, value_node in node.value:
            key = self.scalar(key_node, path)
            if type(key) is not str:
                raise self.error(key_node, path, f"must have names as keys, got the key "
                                                 f"{_describe(key_node)}")
            key_path = _join(path, key)
            if key in entries:
                raise self.error(key_node, key_path, f"must appear only once, got it again "
                                                     f"(first on line {first_line[key]})")
            entries[key], first_line[key] = value_node, key_node.start_mark.line + 1
        if allowed is not None:
            self.reject_unknown(node, path, allowed)
        return entries

    def reject_unknown(self, node: yaml.MappingNode, path: str, allowed: tuple[str, ...]) -> None:
        for key_node, _ in node.value:
            if key_node.value not in allowed:
                close = difflib.get_close_matches(key_node.value, allowed, n=1)
                hint = f"; did you mean {close[0]!r}?" if close else ""
                raise self.error(key_node, _join(path, key_node.value),
                                 f"is not a known key; expected one of {', '.join(allowed)}{hint}")

    def require(self, node: yaml.Node, entries: dict, key: str, path: str,
                expected: str) -> yaml.Node:
        """The value node of a required key; missing -> error at the mapping's own line."""
        if key not in entries:
            raise self.error(node, _join(path, key), f"must be given ({expected}), got no such key")
        return entries[key]

    def optional(self, entries: dict, key: str, path: str, default, read, *args):
        """``read(value_node, key_path, *args)`` if the key is there, else ``default``."""
        return read(entries[key], _join(path, key), *args) if key in entries else default

    def sequence(self, node: yaml.Node, path: str, expected: str) -> list[yaml.Node]:
        """The item nodes of a list; ``expected`` describes the list wanted, for the message."""
        if not isinstance(node, yaml.SequenceNode):
            raise self.wrong(node, path, expected)
        return node.value

    def boolean(self, node: yaml.Node, path: str) -> bool:
        value = self.scalar(node, path)
        if type(value) is not bool:
            raise self.wrong(node, path, "true or false")
        return value

    def choice(self, node: yaml.Node, path: str, options: tuple[str, ...]) -> str:
        value = self.scalar(node, path)
        if type(value) is not str or value not in options:
            raise self.wrong(node, path, f"one of {', '.join(options)}")
        return value

    def number(self, node: yaml.Node, path: str) -> float:
        """A finite float; integers are accepted, booleans and quoted text are not."""
        value = self.scalar(node, path)
        if type(value) is int:
            try:
                value = float(value)
            except OverflowError:
                raise self.error(node, path, f"must be a finite number, got an integer of "
                                 f"{len(str(abs(value)))} digits", NonFiniteInputError) from None
        if type(value) is not float:
            raise self.wrong(node, path, "a number")
        if not math.isfinite(value):
            raise self.error(node, path, f"must be a finite number, got {value!r}",
                             NonFiniteInputError)
        return value

    def number_in(self, node: yaml.Node, path: str, low: float, high: float) -> float:
        value = self.number(node, path)
        if not low <= value <= high:
            raise self.error(node, path, f"must be in [{low:g}, {high:g}], got {value!r}")
        return value

    def integer(self, node: yaml.Node, path: str, low: int, high: int) -> int:
        value = self.scalar(node, path)
        if type(value) is not int or not low <= value <= high:
            raise self.wrong(node, path, f"an integer from {low} to {high}")
        return value

    def length(self, node: yaml.Node, path: str) -> float:
        """A finite number of magnitude at most MAX_LENGTH (lengths and coordinates)."""
        value = self.number(node, path)
        if abs(value) > MAX_LENGTH:
            raise self.error(node, path, f"must be within +-{MAX_LENGTH:g} (output files store float32), "
                                         f"got {value!r}")
        return value

    def position(self, node: yaml.Node, path: str) -> Vec3:
        """A point: 3 finite coordinates, each of magnitude at most MAX_LENGTH."""
        items = self.sequence(node, path, "a list of 3 numbers")
        if len(items) != 3:
            raise self.wrong(node, path, "a list of 3 numbers")
        x, y, z = (self.length(item, f"{path}[{i}]") for i, item in enumerate(items))
        return x, y, z

    def vector3(self, node: yaml.Node, path: str) -> Vec3:
        """A list of exactly 3 finite numbers, as a tuple of floats."""
        items = self.sequence(node, path, "a list of 3 numbers")
        if len(items) != 3:
            raise self.wrong(node, path, "a list of 3 numbers")
        x, y, z = (self.number(item, f"{path}[{i}]") for i, item in enumerate(items))
        return x, y, z


def _join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key
