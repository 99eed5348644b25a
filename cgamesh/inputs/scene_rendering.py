"""The rendering part of a scene file: camera, lights, objects, background, max_depth, attenuation.

All optional, and used only by ``cgamesh render`` / ``cgamesh verify --image`` (the mesher
ignores them). Read by ``cgamesh.inputs.scene`` with its node reader, so mistakes are reported the
same way (``scene.yaml:12: camera.position must be a list of 3 numbers, got ...``). Lengths
are in the file's units and axes, like the surfaces.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from cgamesh.errors import DegenerateGeometryError

Vec3 = tuple[float, float, float]

RENDERING_KEYS = ("camera", "lights", "objects", "background", "max_depth", "attenuation")
OBJECT_TYPES = ("sphere", "plane", "disc")
MAX_DEPTH_LIMIT = 16
_CAMERA_KEYS = ("position", "look_at", "up", "focal_length", "image_plane")
_LIGHT_KEYS = ("position", "color", "intensity")
_MATERIAL_KEYS = ("color", "ambient", "diffuse", "specular", "shininess", "reflectivity")
_OBJECT_KEYS = {
    "sphere": ("type", "center", "radius", "material"),
    "plane": ("type", "point", "normal", "material"),
    "disc": ("type", "center", "normal", "radius", "material"),
}


@dataclass(frozen=True)
class PhongMaterial:
    """Blinn-Phong material (paper eqs. 34-36): colour c (each in [0, 1]), ambient k_a, diffuse
    k_d, specular k_s (each >= 0), shininess q (> 0) and reflectivity k_r (in [0, 1])."""

    color: Vec3 = (0.8, 0.8, 0.8)
    ambient: float = 0.1
    diffuse: float = 0.8
    specular: float = 0.5
    shininess: float = 32.0
    reflectivity: float = 0.0


@dataclass(frozen=True)
class CameraSpec:
    """Pinhole camera (paper section 3). ``up`` None: the file's up axis; ``image_plane`` None:
    x_max = 1 and y_max from the image's aspect ratio."""

    position: Vec3
    look_at: Vec3
    up: Vec3 | None = None
    focal_length: float = 1.0
    image_plane: tuple[float, float] | None = None


@dataclass(frozen=True)
class LightSpec:
    """A point light: its colour (each >= 0) times its intensity (>= 0) is I_p of eq. 34."""

    position: Vec3
    color: Vec3 = (1.0, 1.0, 1.0)
    intensity: float = 1.0


@dataclass(frozen=True)
class ObjectSpec:
    """A sphere {center, radius}, plane {point, normal} or disc {center, normal, radius}."""

    type: str
    center: Vec3 | None
    normal: Vec3 | None
    radius: float | None
    point: Vec3 | None
    material: PhongMaterial


@dataclass(frozen=True)
class Attenuation:
    """Depth attenuation f = 1 / (a + b d + c d^2) (paper section 9.2.1; its values by default)."""

    a: float = 0.02
    b: float = 0.0
    c: float = 0.002


@dataclass(frozen=True)
class Rendering:
    """Everything ``parse_rendering`` reads; ``lights`` None means the key was not given."""

    camera: CameraSpec | None = None
    lights: tuple[LightSpec, ...] | None = None
    objects: tuple[ObjectSpec, ...] = ()
    background: Vec3 = (0.0, 0.0, 0.0)
    max_depth: int = 2
    attenuation: Attenuation = Attenuation()


def parse_rendering(r, entries: dict, up: str = "z") -> Rendering:
    """The rendering keys of a scene's top-level mapping ``entries`` (key -> node), read with
    the scene loader's reader ``r``; ``up``: the file's up axis (the camera's default up)."""
    camera = _camera(r, entries["camera"], up) if "camera" in entries else None
    lights = None
    if "lights" in entries:
        items = r.sequence(entries["lights"], "lights", "a list of lights")
        lights = tuple(_light(r, item, f"lights[{i}]") for i, item in enumerate(items))
    objects = ()
    if "objects" in entries:
        items = r.sequence(entries["objects"], "objects", "a list of objects")
        objects = tuple(_object(r, item, f"objects[{i}]") for i, item in enumerate(items))
    background = (0.0, 0.0, 0.0)
    if "background" in entries:
        background = _color(r, entries["background"], "background")
    max_depth = r.optional(entries, "max_depth", "", 2, r.integer, 0, MAX_DEPTH_LIMIT)
    attenuation = Attenuation()
    if "attenuation" in entries:
        attenuation = _attenuation(r, entries["attenuation"])
    return Rendering(camera, lights, objects, background, max_depth, attenuation)


def _optional(r, entries: dict, key: str, path: str, default, read):
    """``read(r, node, key_path)`` of an optional key, else ``default``."""
    return read(r, entries[key], f"{path}.{key}") if key in entries else default


def _nonzero(r, node, path: str) -> Vec3:
    value = r.vector3(node, path)
    if not any(value):
        raise r.error(node, path, f"must be non-zero, got {_fmt(value)}", DegenerateGeometryError)
    # A direction: over its largest component, so a length of 1e-300 or 1e300 cannot underflow
    # or overflow where it is normalised.
    largest = max(abs(c) for c in value)
    return tuple(c / largest for c in value)


def _positive(r, node, path: str) -> float:
    value = r.number(node, path)
    if value <= 0.0:
        raise r.error(node, path, f"must be > 0, got {value!r}")
    return value


def _non_negative(r, node, path: str) -> float:
    value = r.number(node, path)
    if value < 0.0:
        raise r.error(node, path, f"must be >= 0, got {value!r}")
    return value


def _color(r, node, path: str, high: float = 1.0) -> Vec3:
    color = r.vector3(node, path)
    for i, (item, value) in enumerate(zip(node.value, color)):
        if not 0.0 <= value <= high:
            bound = f"in [0, {high:g}]" if math.isfinite(high) else ">= 0"
            raise r.error(item, f"{path}[{i}]", f"must be {bound}, got {value!r}")
    return color


def _camera(r, node, up_axis: str) -> CameraSpec:
    path = "camera"
    entries = r.mapping(node, path, _CAMERA_KEYS)
    position = r.vector3(r.require(node, entries, "position", path, "a point [x, y, z]"), f"{path}.position")
    look_node = r.require(node, entries, "look_at", path, "a point [x, y, z]")
    look_at = r.vector3(look_node, f"{path}.look_at")
    view = tuple(b - a for a, b in zip(position, look_at))
    view_size = math.hypot(*view)
    if view_size <= 1e-12 * max(math.hypot(*position), math.hypot(*look_at), 1e-300):
        raise r.error(look_node, f"{path}.look_at", f"must differ from camera.position = {_fmt(position)}, "
                      f"got {_fmt(look_at)}", DegenerateGeometryError)
    up = _nonzero(r, entries["up"], f"{path}.up") if "up" in entries else None
    vertical = up if up is not None else ((0.0, 0.0, 1.0) if up_axis == "z" else (0.0, 1.0, 0.0))
    cross = (view[1] * vertical[2] - view[2] * vertical[1], view[2] * vertical[0] - view[0] * vertical[2],
             view[0] * vertical[1] - view[1] * vertical[0])
    if math.hypot(*cross) <= 1e-9 * view_size * math.hypot(*vertical):
        where, what = (entries["up"], f"{path}.up") if up is not None else (look_node, f"{path}.look_at")
        detail = (f"must not be parallel to the view direction look_at - position = {_fmt(view)}, got {_fmt(up)}"
                  if up is not None else f"must not be straight above or below camera.position (the view is "
                  f"then parallel to the file's up axis {up_axis}; give camera.up), got {_fmt(look_at)}")
        raise r.error(where, what, detail, DegenerateGeometryError)
    focal = _optional(r, entries, "focal_length", path, 1.0, _positive)
    plane = None
    if "image_plane" in entries:
        plane_node = entries["image_plane"]
        items = r.sequence(plane_node, f"{path}.image_plane", "a list of 2 numbers [x_max, y_max]")
        if len(items) != 2:
            raise r.wrong(plane_node, f"{path}.image_plane", "a list of 2 numbers [x_max, y_max]")
        plane = tuple(_positive(r, item, f"{path}.image_plane[{i}]") for i, item in enumerate(items))
    return CameraSpec(position, look_at, up, focal, plane)


def _light(r, node, path: str) -> LightSpec:
    entries = r.mapping(node, path, _LIGHT_KEYS)
    position = r.vector3(r.require(node, entries, "position", path, "a point [x, y, z]"), f"{path}.position")
    color = _color(r, entries["color"], f"{path}.color", math.inf) if "color" in entries else (1.0, 1.0, 1.0)
    intensity = _optional(r, entries, "intensity", path, 1.0, _non_negative)
    return LightSpec(position, color, intensity)


def _material(r, entries: dict, path: str) -> PhongMaterial:
    default = PhongMaterial()
    if "material" not in entries:
        return default
    mat_path = f"{path}.material"
    mat = r.mapping(entries["material"], mat_path, _MATERIAL_KEYS)
    color = _color(r, mat["color"], f"{mat_path}.color") if "color" in mat else default.color
    ambient, diffuse, specular = (_optional(r, mat, key, mat_path, getattr(default, key), _non_negative)
                                  for key in ("ambient", "diffuse", "specular"))
    shininess = _optional(r, mat, "shininess", mat_path, default.shininess, _positive)
    reflectivity = r.optional(mat, "reflectivity", mat_path, default.reflectivity, r.number_in, 0.0, 1.0)
    return PhongMaterial(color, ambient, diffuse, specular, shininess, reflectivity)


def _object(r, node, path: str) -> ObjectSpec:
    entries = r.mapping(node, path)
    kind = r.choice(r.require(node, entries, "type", path, f"one of {', '.join(OBJECT_TYPES)}"),
                    f"{path}.type", OBJECT_TYPES)
    r.reject_unknown(node, path, _OBJECT_KEYS[kind])
    forms = {"sphere": "a sphere is {center, radius}", "plane": "a plane is {point, normal}",
             "disc": "a disc is {center, normal, radius}"}[kind]
    center = normal = radius = point = None
    if kind in ("sphere", "disc"):
        center = r.vector3(r.require(node, entries, "center", path, forms), f"{path}.center")
        radius_node = r.require(node, entries, "radius", path, forms)
        radius = r.number(radius_node, f"{path}.radius")
        if radius <= 0.0:
            raise r.error(radius_node, f"{path}.radius", f"must be > 0, got {radius!r}", DegenerateGeometryError)
    if kind in ("plane", "disc"):
        normal = _nonzero(r, r.require(node, entries, "normal", path, forms), f"{path}.normal")
    if kind == "plane":
        point = r.vector3(r.require(node, entries, "point", path, forms), f"{path}.point")
    return ObjectSpec(kind, center, normal, radius, point, _material(r, entries, path))


def _attenuation(r, node) -> Attenuation:
    path = "attenuation"
    entries = r.mapping(node, path, ("a", "b", "c"))
    default = Attenuation()
    a = _optional(r, entries, "a", path, default.a, _positive)
    b = _optional(r, entries, "b", path, default.b, _non_negative)
    c = _optional(r, entries, "c", path, default.c, _non_negative)
    return Attenuation(a, b, c)


def _fmt(v) -> str:
    return "[" + ", ".join(repr(c) for c in v) + "]"
