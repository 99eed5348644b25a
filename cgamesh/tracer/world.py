"""From a scene file's specs to what the tracer draws: surfaces, objects, lights and a camera.

The evolved surfaces are built here from the specs by the scene format's rules (normalised,
aligned controls in a local frame; the curve of the spec), independently of the mesher's
pipeline. A surface's glTF material (colour, roughness, metallic) becomes a Blinn-Phong one:
k_a = 0.1, k_d = 0.8, k_s = 0.6 (1 - roughness), shininess q = 2 / r^4 - 2 with
r = max(roughness, 0.05) (at least 1), reflectivity k_r = metallic / 2.

A scene without ``camera`` is framed from above and to the side by ``Camera.framing``;
without ``lights`` it gets one white light beside the camera, as bright as the depth
attenuation of the scene's centre (f I = 1 there).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cgamesh.geometry.construction import build_surface
from cgamesh.errors import CgameshError, DegenerateGeometryError
from cgamesh.material import Material
from cgamesh.inputs.scene import Scene, SurfaceSpec
from cgamesh.inputs.scene_rendering import Attenuation, PhongMaterial
from cgamesh.geometry.surface import EvolvedSurface
from cgamesh.tracer import bounds, cga
from cgamesh.tracer.camera import Camera
from cgamesh.tracer.evolved import RootFinder, TracedSurface
from cgamesh.tracer.primitives import Disc, Plane, Sphere

# Rays start this fraction of the scene's size past the point they leave from.
EPSILON_FRACTION = 1e-6


@dataclass(frozen=True)
class Light:
    """A point light: position (3,) and I_p per channel (3,) = colour times intensity."""

    position: np.ndarray
    intensity: np.ndarray


@dataclass(frozen=True)
class World:
    """Everything one render needs. ``epsilon``: the start offset of secondary rays."""

    objects: tuple
    lights: tuple[Light, ...]
    camera: Camera
    background: np.ndarray
    max_depth: int
    attenuation: Attenuation
    epsilon: float
    centre: np.ndarray
    radius: float
    shadows: bool = True

    def surfaces(self) -> list[TracedSurface]:
        return [o for o in self.objects if isinstance(o, TracedSurface)]


def surface_from_spec(spec: SurfaceSpec) -> EvolvedSurface:
    """The evolved surface of a spec, checked to exist all along its curve."""
    surface = build_surface(spec)
    try:
        surface.check_projection_exists()
    except CgameshError as error:
        raise type(error)(f"{spec.location}: {error}") from None
    return surface


def phong_of(material: Material) -> PhongMaterial:
    r = max(material.roughness, 0.05)
    return PhongMaterial(tuple(material.color), 0.1, 0.8, 0.6 * (1.0 - material.roughness),
                         max(2.0 / r**4 - 2.0, 1.0), 0.5 * material.metallic)


def _primitive(spec):
    if spec.type == "sphere":
        return Sphere(spec.center, spec.radius, spec.material)
    if spec.type == "plane":
        return Plane(spec.point, spec.normal, spec.material)
    return Disc(spec.center, spec.normal, spec.radius, spec.material)


def _extent(items) -> tuple[np.ndarray, float]:
    """Centre and radius of a sphere enclosing spheres (centre, radius) (two-sphere algorithm)."""
    if not items:
        return np.zeros(3), 1.0
    sigma = bounds.enclose(np.stack([cga.dual_sphere(np.asarray(c, dtype=np.float64), r) for c, r in items]))
    centre, radius = bounds.dual_centre_radius(sigma)
    return centre, max(float(radius), 1e-9)


def build_world(scene: Scene, finder: RootFinder = RootFinder(), surfaces: bool = True,
                primitives: bool = True, caps: bool = True) -> World:
    """The scene as the tracer sees it (``surfaces`` / ``primitives``: which parts to include)."""
    traced = []
    if surfaces:
        traced = [TracedSurface(surface_from_spec(spec), phong_of(spec.material), caps and spec.caps, finder)
                  for spec in scene.surfaces]
    others = [_primitive(spec) for spec in scene.objects] if primitives else []
    finite = [(s.bound_centre, s.bound_radius) for s in traced]
    finite += [(np.asarray(o.centre), o.radius) for o in others if not isinstance(o, Plane)]
    centre, radius = _extent(finite)
    camera = _camera(scene, centre, radius)
    distance = float(np.linalg.norm(np.asarray(camera.position) - centre))
    attenuation = scene.attenuation
    if scene.lights is None:
        axes = camera.axes
        position = np.asarray(camera.position) + 0.4 * distance * (axes[:, 0] + axes[:, 2])
        level = attenuation.a + attenuation.b * distance + attenuation.c * distance**2
        lights = (Light(position, np.full(3, level)),)
    else:
        lights = tuple(Light(np.asarray(s.position, dtype=np.float64), np.asarray(s.color) * s.intensity)
                       for s in scene.lights)
    return World(tuple(traced) + tuple(others), lights, camera, np.asarray(scene.background, dtype=np.float64),
                 scene.max_depth, attenuation, EPSILON_FRACTION * max(radius, distance), centre, radius)


def _camera(scene: Scene, centre: np.ndarray, radius: float) -> Camera:
    up_axis = (0.0, 0.0, 1.0) if scene.up == "z" else (0.0, 1.0, 0.0)
    spec = scene.camera
    if spec is None:
        return Camera.framing(centre, radius, scene.up)
    up_vector = spec.up if spec.up is not None else up_axis
    view = np.subtract(spec.look_at, spec.position)
    if np.linalg.norm(np.cross(view, up_vector)) <= 1e-9 * np.linalg.norm(view) * np.linalg.norm(up_vector):
        raise DegenerateGeometryError(f"{scene.path}: camera: the view direction {view.tolist()} is parallel "
                                      f"to the up axis {list(up_vector)}; give camera.up")
    x_max, y_max = spec.image_plane if spec.image_plane is not None else (1.0, None)
    return Camera(tuple(spec.position), tuple(spec.look_at), tuple(up_vector), spec.focal_length, x_max, y_max)
