"""The fast path of the scene reader: plain data at C speed, checked over arrays.

The careful reader (``cgamesh.inputs.scene``) walks PyYAML's node tree to name the line of
every mistake; that costs about 10 us per node, so a scene of thousands of surfaces reads at
well under 1 MB/s, with libyaml's C parser too (its nodes and marks are Python objects). Yet
lines are needed only when something is wrong, plus the line of each surface and control
(their ``Location``). So reading is two passes:

1. ``cgamesh.inputs.scene_subset`` accepts a strict subset of YAML, the shape that scene
   files are written in (by hand, by converters, by PyYAML's ``safe_dump`` in its block or
   mixed layout), rewrites it into JSON with the line of every list item's mapping under
   the key "" and lets ``json.loads`` build it; this module then checks every value, key by
   key over all surfaces and over all controls of the file at once (C-level maps, set tests
   and reductions over whole lists, not checks per value).
2. Anything it cannot vouch for returns ``None`` (never an error): text outside the subset
   (quotes, anchors, aliases, tags, block scalars, tabs, multi-line flow, non-ASCII, ...), a
   duplicate key, or any value the careful reader would refuse. ``parse_scene`` then runs
   the careful reader, which gives the located one-line error (or, for valid YAML outside the
   subset, the scene).

So the fast path never decides what an error says: it either returns exactly the ``Scene``
the careful reader returns (the tests compare both on every example and on generated scenes)
or steps aside. Its security follows from the subset: no tag, anchor or alias can be
written in it, so nothing is constructed beyond str, int, float, bool, None, list and dict,
and nothing expands.
"""

from __future__ import annotations

import gc
import math
import re
from collections import deque
from itertools import accumulate, chain, compress, repeat
from operator import itemgetter

import numpy as np

from cgamesh.material import Material
from cgamesh.inputs import scene_rules as rules
from cgamesh.inputs.scene_specs import CircleControl, Location, PointPairControl, Scene, SurfaceSpec
from cgamesh.inputs.scene_rendering import RENDERING_KEYS
from cgamesh.inputs.scene_subset import OutsideSubset as _OutsideSubset
from cgamesh.inputs.scene_subset import plain_document as _plain_document


def read_fast(text: str, path: str, rendering: bool) -> Scene | None:
    """The scene of ``text`` as ``parse_scene`` would return it, or None when this path
    cannot vouch for the text (the careful reader then decides)."""
    # Reading allocates some hundred thousand small lists, dicts and tuples, none in a cycle
    # (reference counting frees them all); the cyclic collector would walk them again and
    # again as they pile up, a quarter of the time. It is paused meanwhile.
    collecting = gc.isenabled()
    gc.disable()
    try:
        plain = _plain_document(text)
        if plain is None:
            return None
        return _scene(*plain, path, rendering)
    except _OutsideSubset:
        return None
    finally:
        if collecting:
            gc.enable()


# --- checks over the plain data ----------------------------------------------------------------

_TOP_KEYS = frozenset(rules.TOP_KEYS)
_SURFACE_KEYS = frozenset(rules.SURFACE_KEYS)
_CIRCLE_KEYS = frozenset(rules.CIRCLE_KEYS)
_POINT_PAIR_KEYS = frozenset(rules.POINT_PAIR_KEYS)
_RESOLUTION_KEYS = frozenset(("around", "along"))
_MATERIAL_KEYS = frozenset(("color", "roughness", "metallic"))
_NAME = re.compile(rules.NAME_PATTERN)
_DEFAULT_MATERIAL = Material()


def _check(condition: bool) -> None:
    if not condition:
        raise _OutsideSubset("a value the careful reader refuses or reads otherwise")


def _number(value: object) -> float:
    """A finite number, as the careful reader's ``number`` reads it."""
    kind = type(value)
    if kind is int:
        try:
            value = float(value)
        except OverflowError:
            raise _OutsideSubset("a huge integer") from None
    else:
        _check(kind is float)
    _check(value - value == 0.0)  # finite
    return value


def _in(value: object, low: float, high: float) -> float:
    value = _number(value)
    _check(low <= value <= high)
    return value


def _choice(entries: dict, key: str, default: str, options: tuple[str, ...]) -> str:
    value = entries.get(key, default)
    _check(type(value) is str and value in options)
    return value


def _flag(entries: dict, key: str, default: bool) -> bool:
    value = entries.get(key, default)
    _check(type(value) is bool)
    return value


def _frozen(cls: type, fields: dict):
    """``cls(**fields)`` for a frozen dataclass without __post_init__: its generated __init__
    sets each field with object.__setattr__; one assignment of the instance dict does the same
    for all fields at once, at half the cost (which counts over thousands of controls)."""
    instance = _new(cls)
    _set(instance, "__dict__", fields)
    return instance


_new, _set = object.__new__, object.__setattr__
for _cls in (Location, CircleControl, PointPairControl, SurfaceSpec):
    assert not hasattr(_cls, "__post_init__")


def _scene(document: dict, keys: int, path: str, rendering: bool) -> Scene:
    """The Scene of the plain ``document`` that was written with ``keys`` keys."""
    _check(type(document) is dict and _TOP_KEYS.issuperset(document))
    seen = len(document)
    for key in RENDERING_KEYS:
        if key in document:
            # The rendering keys are few and small: the careful reader reads them; meshing
            # leaves them unread, but their keys are counted.
            _check(not rendering)
            seen += _count_keys(document[key])
    version = document.get("cgamesh")
    _check(type(version) is int and version in rules.SUPPORTED_VERSIONS)
    units = _choice(document, "units", "m", tuple(rules.METERS_PER_UNIT))
    up = _choice(document, "up", "z", rules.UP_AXES)
    items = document.get("surfaces")
    _check(type(items) is list and len(items) > 0)
    names: set[str] = set()
    controls = _Controls(path)
    parts = _plain_surfaces(items, controls, path)
    if parts is None:
        parts = [_surface(item, i, names, controls, path) for i, item in enumerate(items)]
    built = tuple(controls.build())
    _check(seen + controls.keys_seen == keys)  # else a key was repeated
    surfaces = []
    for fields, first, last in parts:
        fields["controls"] = built[first:last]
        surfaces.append(_frozen(SurfaceSpec, fields))
    return Scene(path, version, units, rules.METERS_PER_UNIT[units], up, tuple(surfaces))


_MISSING = object()  # a key not written (None is a key written with a null value)
_PLAIN_SURFACE_KEYS = frozenset(("", "name", "type", "curve", "controls", "resolution",
                                 "tolerance", "closed", "caps", "material"))
_SURFACE_TYPES, _CURVES = frozenset(rules.SURFACE_TYPES), frozenset(rules.CURVES)
_CLOSABLE_CURVES = frozenset(rules.CLOSABLE_CURVES)


def _plain_surfaces(items: list, controls: _Controls,
                    path: str) -> list[tuple[dict, int, int]] | None:
    """What ``_surface`` returns for every item, checked key by key over all surfaces at once
    (C-level maps and set tests instead of some twenty checks a surface); None, with nothing
    added to ``controls``, unless every item is a mapping of the keys that converters write
    (``_PLAIN_SURFACE_KEYS``; the others keep their defaults)."""
    if set(map(type, items)) != {dict} or not all(map(_PLAIN_SURFACE_KEYS.issuperset, items)):
        return None
    count = len(items)

    def column(key: str) -> list:
        return list(map(dict.get, items, repeat(key), repeat(_MISSING)))

    lines, names, kinds, curves = column(""), column("name"), column("type"), column("curve")
    _check(_MISSING not in lines)
    _check(set(map(type, names)) == {str} and all(map(_NAME.fullmatch, names))
           and len(set(names)) == count)
    _check(set(map(type, kinds)) == {str} and _SURFACE_TYPES.issuperset(kinds))
    _check(set(map(type, curves)) == {str} and _CURVES.issuperset(curves))
    closed, caps = _flags(column("closed")), _flags(column("caps"))
    _check(_CLOSABLE_CURVES.issuperset(compress(curves, closed)))
    _check({"circles"}.issuperset(compress(kinds, caps)) and not any(compress(closed, caps)))
    controls.keys_seen += sum(map(len, items)) - count  # the line markers are no keys
    key_paths = [f"surfaces[{i}]" for i in range(count)]
    lists = column("controls")
    _check(set(map(type, lists)) == {list}
           and min(map(int.__sub__, map(len, lists), map(int.__add__, repeat(2), closed))) >= 0)
    ranges = None
    if len(set(kinds)) == 1:  # one kind throughout: every control at once, if all are plain
        ranges = controls.add_plain_lists(lists, kinds[0] == "circles", key_paths)
    if ranges is None:
        ranges = []
        for controls_list, kind, curve, closing, key_path in zip(lists, kinds, curves, closed,
                                                                 key_paths):
            first = len(controls.forms)
            controls.add(controls_list, kind, curve, closing, key_path)
            ranges.append((first, len(controls.forms)))
    arounds, alongs, tolerances = _plain_resolutions(column("resolution"), column("tolerance"),
                                                     kinds, controls)
    materials = [_DEFAULT_MATERIAL if entries is _MISSING else _material(entries, controls)
                 for entries in column("material")]
    locations = _with_fields(Location, [{"file": path, "line": line, "key_path": key_path}
                                        for line, key_path in zip(lines, key_paths)])
    return [({"name": name, "type": kind, "curve": curve, "tension": 0.0, "bias": 0.0,
              "continuity": 0.0, "closed": closing, "align": True, "controls": None,
              "around": around, "along": along, "tolerance": tolerance, "caps": capped,
              "material": material, "location": location, "uv": "natural", "uv_scale": None,
              "interpolation": "blade"}, first, last)
            for name, kind, curve, closing, capped, around, along, tolerance, material,
            location, (first, last)
            in zip(names, kinds, curves, closed, caps, arounds, alongs, tolerances, materials,
                   locations, ranges)]


def _flags(values: list, default: bool = False) -> list[bool]:
    """Booleans of a column, ``default`` where the key was not written."""
    _check({bool, type(_MISSING)}.issuperset(map(type, values)))
    if _MISSING in values:
        return [default if value is _MISSING else value for value in values]
    return values


def _plain_resolutions(resolutions: list, tolerances: list, kinds: list,
                       seen: _Controls) -> tuple[list, list, list]:
    """(around, along, tolerance) columns as ``_resolution`` reads them, surface by surface."""
    given = [entries for entries in resolutions if entries is not _MISSING]
    _check(set(map(type, given)) <= {dict} and all(map(_RESOLUTION_KEYS.issuperset, given)))
    seen.keys_seen += sum(map(len, given))
    arounds = [rules.DEFAULT_AROUND if entries is _MISSING
               else entries.get("around", rules.DEFAULT_AROUND) for entries in resolutions]
    alongs = [rules.DEFAULT_ALONG if entries is _MISSING
              else entries.get("along", rules.DEFAULT_ALONG) for entries in resolutions]
    _check(set(map(type, arounds)) == {int} and set(map(type, alongs)) == {int})
    _check(min(alongs) >= 2 and max(alongs) <= rules.MAX_RESOLUTION
           and min(arounds) >= 2 and max(arounds) <= rules.MAX_RESOLUTION)
    _check(min(compress(arounds, map("circles".__eq__, kinds)), default=3) >= 3)
    if all(value is _MISSING for value in tolerances):
        return arounds, alongs, [None] * len(tolerances)
    values = []
    for i, value in enumerate(tolerances):
        if value is _MISSING:
            values.append(None)
            continue
        _check(resolutions[i] is _MISSING)
        value = _number(value)
        _check(value > 0.0)
        values.append(value)
        arounds[i] = alongs[i] = None
    return arounds, alongs, values


def _surface(entries: object, index: int, names: set[str], controls: _Controls,
             path: str) -> tuple[dict, int, int]:
    """A surface's fields but its controls (added to ``controls``), and the range of its
    controls there."""
    _check(type(entries) is dict)
    line = entries.pop("", None)
    _check(line is not None and _SURFACE_KEYS.issuperset(entries))
    controls.keys_seen += len(entries)
    get = entries.get
    name, kind, curve = get("name"), get("type"), get("curve")
    _check(type(name) is str and _NAME.fullmatch(name) is not None and name not in names
           and kind in rules.SURFACE_TYPES and curve in rules.CURVES
           and type(kind) is str and type(curve) is str)
    names.add(name)
    closed, align, caps = get("closed", False), get("align", True), get("caps", False)
    _check(type(closed) is bool and type(align) is bool and type(caps) is bool)
    _check(not closed or curve in rules.CLOSABLE_CURVES)
    _check(not caps or (kind == "circles" and not closed))
    interpolation = _choice(entries, "interpolation", "blade", rules.INTERPOLATIONS)
    _check(interpolation == "blade" or kind == "circles")
    first = len(controls.forms)
    key_path = f"surfaces[{index}]"
    controls.add(get("controls"), kind, curve, closed, key_path)
    around, along, tolerance = _resolution(entries, kind, controls)
    material = _material(get("material", _DEFAULT_MATERIAL), controls)
    uv = _choice(entries, "uv", "natural", rules.UV_MODES)
    uv_scale = None
    if "uv_scale" in entries:
        uv_scale = _number(entries["uv_scale"])
        _check(uv == "natural" and uv_scale > 0.0)
    tension = bias = continuity = 0.0
    if curve == "kb" or not entries.keys().isdisjoint(_KB_KEYS):
        tension, bias, continuity = (_kb_parameter(entries, key, curve) for key in _KB_KEYS)
    fields = {"name": name, "type": kind, "curve": curve,
              "tension": tension, "bias": bias, "continuity": continuity, "closed": closed,
              "align": align, "controls": None, "around": around, "along": along, "tolerance": tolerance, "caps": caps, "material": material,
              "location": _frozen(Location, {"file": path, "line": line, "key_path": key_path}),
              "uv": uv, "uv_scale": uv_scale, "interpolation": interpolation}
    return fields, first, len(controls.forms)


_KB_KEYS = ("tension", "bias", "continuity")


def _kb_parameter(entries: dict, key: str, curve: str) -> float:
    if key not in entries:
        return 0.0
    _check(curve == "kb")
    return _in(entries[key], -1.0, 1.0)


def _resolution(entries: dict, kind: str,
                seen: _Controls) -> tuple[int | None, int | None, float | None]:
    if "tolerance" in entries:
        _check("resolution" not in entries)
        tolerance = _number(entries["tolerance"])
        _check(tolerance > 0.0)
        return None, None, tolerance
    if "resolution" not in entries:
        return rules.DEFAULT_AROUND, rules.DEFAULT_ALONG, None
    resolution = entries["resolution"]
    _check(type(resolution) is dict and _RESOLUTION_KEYS.issuperset(resolution))
    seen.keys_seen += len(resolution)
    around = resolution.get("around", rules.DEFAULT_AROUND)
    along = resolution.get("along", rules.DEFAULT_ALONG)
    least_around = 3 if kind == "circles" else 2
    _check(type(around) is int and least_around <= around <= rules.MAX_RESOLUTION)
    _check(type(along) is int and 2 <= along <= rules.MAX_RESOLUTION)
    return around, along, None


def _material(entries: object, seen: _Controls) -> Material:
    if entries is _DEFAULT_MATERIAL:
        return entries
    _check(type(entries) is dict and _MATERIAL_KEYS.issuperset(entries))
    seen.keys_seen += len(entries)
    color = _DEFAULT_MATERIAL.color
    if "color" in entries:
        values = entries["color"]
        _check(type(values) is list and len(values) == 3)
        color = tuple(_in(value, 0.0, 1.0) for value in values)
    roughness = _in(entries.get("roughness", _DEFAULT_MATERIAL.roughness), 0.0, 1.0)
    metallic = _in(entries.get("metallic", _DEFAULT_MATERIAL.metallic), 0.0, 1.0)
    return Material(color, roughness, metallic)


class _Controls:
    """Every control of the file, gathered so that their numbers are checked as arrays and
    their specs built by C-level maps."""

    def __init__(self, path: str) -> None:
        self.path = path
        self.keys_seen = 0  # keys of every mapping checked, surfaces' and their parts' too
        self.lines: list[int] = []
        self.key_paths: list[str] = []
        self.weights: list[float] = []
        self.forms: list[int] = []  # _CIRCLE, _PAIR or _THROUGH, in file order
        self.centers: list = []
        self.normals: list = []
        self.radii: list = []
        self.ends_a: list = []
        self.ends_b: list = []
        self.throughs: list = []

    def add(self, items: object, kind: str, curve: str, closed: bool, key_path: str) -> None:
        _check(type(items) is list and len(items) >= (3 if closed else 2))
        circles = kind == "circles"
        if self._add_plain(items, circles, key_path):
            return
        allowed = _CIRCLE_KEYS_LINE if circles else _POINT_PAIR_KEYS_LINE
        rational = curve == "rational_bezier"
        weights = []
        for i, entries in enumerate(items):
            _check(type(entries) is dict and allowed.issuperset(entries))
            line = entries.get("")
            _check(line is not None)
            self.keys_seen += len(entries) - 1
            self.lines.append(line)
            self.key_paths.append(f"{key_path}.controls[{i}]")
            weight = 1.0
            if "weight" in entries:
                _check(rational)
                weight = _number(entries["weight"])
                _check(weight > 0.0)
                weights.append(weight)
            self.weights.append(weight)
            if not circles:
                self.forms.append(_PAIR)
                self.ends_a.append(entries.get("a"))
                self.ends_b.append(entries.get("b"))
            elif "through" in entries:
                _check(entries.keys().isdisjoint(("center", "normal", "radius")))
                self.forms.append(_THROUGH)
                self.throughs.append(_through(entries["through"]))
            else:
                self.forms.append(_CIRCLE)
                self.centers.append(entries.get("center"))
                self.normals.append(entries.get("normal"))
                self.radii.append(entries.get("radius"))
        if weights:
            if len(weights) < len(items):
                weights.append(1.0)  # the controls given no weight
            largest = max(weights)
            _check(all(weight * rules.MAX_WEIGHT_RATIO >= largest for weight in weights))

    def add_plain_lists(self, lists: list[list], circles: bool,
                        key_paths: list[str]) -> list[tuple[int, int]] | None:
        """Add the controls of every list (of surfaces ``key_paths``, all of one kind) if
        every one is of the plain shape (see ``_add_plain``), by maps over all of them at
        once; the range of each list's controls, or None with nothing added."""
        counts = list(map(len, lists))
        paths = map(str.__add__, chain.from_iterable(map(repeat, key_paths, counts)),
                    chain.from_iterable(map(_control_suffixes, counts)))
        first = len(self.forms)
        if not self._add_plain(list(chain.from_iterable(lists)), circles, paths):
            return None
        ends = list(accumulate(counts, initial=first))
        return list(zip(ends, ends[1:]))

    def _add_plain(self, items: list, circles: bool, key_path) -> bool:
        """Add ``items`` if every one is a mapping of exactly the plain keys (center, normal
        and radius; a and b), by C-level maps over the list; False (nothing added) if not.
        ``key_path``: the list's (str), or an iterable of each item's."""
        row, width = (_CIRCLE_ROW, 4) if circles else (_PAIR_ROW, 3)
        try:
            rows = list(map(row, items))
        except (KeyError, TypeError):  # a key missing, or an item that is not a mapping
            return False
        count = len(rows)
        if sum(map(len, items)) != width * count:  # a key more than the plain ones
            return False
        columns = tuple(zip(*rows))
        self.lines += columns[0]
        if circles:
            self.centers += columns[1]
            self.normals += columns[2]
            self.radii += columns[3]
        else:
            self.ends_a += columns[1]
            self.ends_b += columns[2]
        self.keys_seen += (width - 1) * count
        if type(key_path) is str:
            self.key_paths += map(key_path.__add__, _control_suffixes(count))
        else:
            self.key_paths += key_path  # one for each item, made by the caller
        self.weights += repeat(1.0, count)
        self.forms += repeat(_CIRCLE if circles else _PAIR, count)
        return True

    def build(self) -> list[CircleControl | PointPairControl]:
        """The specs, in file order, once every number has passed."""
        limit = rules.MAX_LENGTH
        centers, normals = _vectors(self.centers, limit), _vectors(self.normals)
        radii = _floats(self.radii, limit)
        ends_a, ends_b = _vectors(self.ends_a, limit), _vectors(self.ends_b, limit)
        _check((0.0, 0.0, 0.0) not in normals and (not radii or min(radii) > 0.0))
        if ends_a:
            for i in np.flatnonzero(_maybe_coincident(np.array(ends_a), np.array(ends_b))).tolist():
                _check(not rules.coincident(ends_a[i], ends_b[i]))
        path = self.path
        locations = _with_fields(Location, [{"file": path, "line": line, "key_path": key_path}
                                            for line, key_path in zip(self.lines, self.key_paths)])
        forms = self.forms
        count = len(forms)
        circles = forms.count(_CIRCLE)
        if circles == count:  # the common case: every control a circle given by its center
            return _with_fields(CircleControl, [
                {"center": center, "normal": normal, "radius": radius, "through": None,
                 "weight": weight, "location": location}
                for center, normal, radius, weight, location
                in zip(centers, normals, radii, self.weights, locations)])
        if forms.count(_PAIR) == count:
            return _with_fields(PointPairControl, [
                {"a": a, "b": b, "weight": weight, "location": location}
                for a, b, weight, location in zip(ends_a, ends_b, self.weights, locations)])
        built = []
        circle, pair = iter(zip(centers, normals, radii)), iter(zip(ends_a, ends_b))
        through = iter(self.throughs)
        for form, weight, location in zip(forms, self.weights, locations):
            if form == _PAIR:
                a, b = next(pair)
                fields = {"a": a, "b": b, "weight": weight, "location": location}
            else:
                center, normal, radius = next(circle) if form == _CIRCLE else (None, None, None)
                fields = {"center": center, "normal": normal, "radius": radius,
                          "through": next(through) if form == _THROUGH else None,
                          "weight": weight, "location": location}
            built.append(_frozen(PointPairControl if form == _PAIR else CircleControl, fields))
        return built


_CIRCLE, _PAIR, _THROUGH = 0, 1, 2
_CIRCLE_ROW = itemgetter("", "center", "normal", "radius")
_PAIR_ROW = itemgetter("", "a", "b")
_SUFFIXES: list[str] = []


def _control_suffixes(count: int) -> list[str]:
    """'.controls[0]' ... '.controls[count - 1]' (made once, shared by every surface)."""
    if len(_SUFFIXES) < count:
        _SUFFIXES.extend(f".controls[{i}]" for i in range(len(_SUFFIXES), count))
    return _SUFFIXES[:count]


_CIRCLE_KEYS_LINE = _CIRCLE_KEYS | {""}
_POINT_PAIR_KEYS_LINE = _POINT_PAIR_KEYS | {""}


def _with_fields(cls: type, fields: list[dict]) -> list:
    """Frozen dataclass instances of ``cls``, one per dict of field values, as ``_frozen``
    builds them, by maps over builtins (no Python-level loop)."""
    instances = list(map(_new, repeat(cls, len(fields))))
    deque(map(_set, instances, repeat("__dict__"), fields), maxlen=0)
    return instances


def _count_keys(value: object) -> int:
    """Keys of every mapping in ``value`` (list items' line markers left out)."""
    if type(value) is dict:
        return sum(_count_keys(v) for v in value.values()) + len(value) - ("" in value)
    if type(value) is list:
        return sum(_count_keys(v) for v in value)
    return 0


def _floats(values: list, limit: float = math.inf) -> list[float]:
    """``values`` as the careful reader's ``number`` reads them (an int as float(int)), all
    finite and at most ``limit`` in size; anything else (bool, text, None, a list, a huge
    int) refused. By C-level maps and reductions over the whole list."""
    kinds = set(map(type, values))
    if not kinds <= {float}:
        _check(kinds <= {float, int})
        try:
            values = list(map(float, values))
        except OverflowError:
            raise _OutsideSubset("a huge integer") from None
    # A NaN or an infinity makes the sum so; a sum that overflows only sends the file to
    # the careful reader.
    _check(not values or (math.isfinite(sum(values))
                          and -limit <= min(values) and max(values) <= limit))
    return values


def _vectors(values: list, limit: float = math.inf) -> list[tuple[float, float, float]]:
    """``values``, lists of three numbers each (as ``_floats``), as tuples."""
    if not values:
        return []
    _check(set(map(type, values)) == {list} and set(map(len, values)) == {3})
    triples = iter(_floats(list(chain.from_iterable(values)), limit))
    return list(zip(triples, triples, triples))


def _maybe_coincident(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rows where a and b may be coincident by the careful reader's test (a tenfold margin over
    its 1e-12 for rounding); only those go through the exact, scalar test."""
    scale = np.maximum(np.abs(a).max(axis=1, initial=0.0), np.abs(b).max(axis=1, initial=0.0))
    safe = np.where(scale > 0.0, scale, 1.0)[:, None]
    a, b = a / safe, b / safe
    gap = np.linalg.norm(a - b, axis=1)
    size = np.maximum(np.maximum(np.linalg.norm(a, axis=1), np.linalg.norm(b, axis=1)), 1e-300)
    return gap <= 10.0 * rules.DEGENERATE_RTOL * size


def _through(value: object) -> tuple:
    """The careful reader's checks of ``through``, the same scalar functions (few in a file)."""
    _check(type(value) is list and len(value) == 3)
    points = tuple(tuple(_length(c) for c in _triple(point)) for point in value)
    for i, j in ((0, 1), (0, 2), (1, 2)):
        _check(not rules.coincident(points[i], points[j]))
    _check(not rules.collinear(*points))
    return points


def _triple(value: object) -> list:
    _check(type(value) is list and len(value) == 3)
    return value


def _length(value: object) -> float:
    value = _number(value)
    _check(abs(value) <= rules.MAX_LENGTH)
    return value
