"""A scene file's content as immutable values: the surfaces' specs, their controls, where each sits.

What the scene readers (cgamesh.inputs.scene, cgamesh.inputs.scene_fast) return, and what the
centreline pipeline makes for each chain's tube: ``Scene`` holds ``SurfaceSpec``s, whose
controls are ``CircleControl``s or ``PointPairControl``s, each with its ``Location`` in the
file for messages.
"""

from __future__ import annotations

from dataclasses import dataclass

from cgamesh.inputs.scene_rendering import Attenuation, CameraSpec, LightSpec, ObjectSpec
from cgamesh.material import Material

Vec3 = tuple[float, float, float]


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


