"""From validated scene specs to evolved surfaces and their meshes: scene -> objects -> curve -> mesh.

Geometry errors found on the way (a projection that vanishes, a degenerate control) are
re-raised with the surface's place in the scene file in front of them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cgamesh import objects
from cgamesh import uv as uv_map
from cgamesh.curves.bezier import Bezier, RationalBezier
from cgamesh.curves.kochanek_bartels import KochanekBartels
from cgamesh.curves.linear import Linear
from cgamesh.errors import CgameshError, DegenerateGeometryError, InvalidInputError
from cgamesh.frame import LocalFrame
from cgamesh.material import Material
from cgamesh.mesh import SurfaceMesh
from cgamesh.meshing import mesh_circle_surface
from cgamesh.ribbons import mesh_ribbon_surface
from cgamesh.scene import Scene, SurfaceSpec
from cgamesh.surface import EvolvedSurface
from cgamesh.tessellation import mesh_to_tolerance, ribbon_to_tolerance


@dataclass(frozen=True)
class Resolution:
    """Overrides of every surface's resolution or tolerance from the command line (None keeps the file's)."""

    around: int | None = None
    along: int | None = None
    tolerance: float | None = None


def make_curve(spec: SurfaceSpec):
    """The curve of a surface spec, over its controls."""
    n = len(spec.controls)
    if spec.curve == "linear":
        return Linear(n)
    if spec.curve == "bezier":
        return Bezier(n)
    if spec.curve == "rational_bezier":
        return RationalBezier(tuple(c.weight for c in spec.controls))
    if spec.curve == "kb":
        return KochanekBartels(n, spec.tension, spec.bias, spec.continuity, spec.closed)
    if spec.curve == "catmull_rom":
        return KochanekBartels(n, closed=spec.closed)
    raise InvalidInputError(f"{spec.location}.curve: unknown curve kind {spec.curve!r}")


def _circle_points(spec: SurfaceSpec) -> tuple[np.ndarray, np.ndarray]:
    """Points (n, 3) that fix each circle control and how far the circle reaches past them (n,)."""
    points, reach = [], []
    for control in spec.controls:
        if control.through is not None:
            points.extend(control.through)
            reach.extend([0.0, 0.0, 0.0])
        else:
            points.append(control.center)
            reach.append(control.radius)
    return np.array(points, dtype=np.float64), np.array(reach)


def build_surface(spec: SurfaceSpec) -> EvolvedSurface:
    """Normalised (and, with ``align``, aligned) control blades in a local frame, with the curve."""
    try:
        if spec.type == "circles":
            frame = LocalFrame.enclosing(*_circle_points(spec))
            blades = np.stack([_circle_blade(control, frame) for control in spec.controls])
            grade = objects.CIRCLE_GRADE
        else:
            ends = np.array([p for c in spec.controls for p in (c.a, c.b)], dtype=np.float64)
            frame = LocalFrame.enclosing(ends)
            a = frame.to_local(np.array([c.a for c in spec.controls], dtype=np.float64))
            b = frame.to_local(np.array([c.b for c in spec.controls], dtype=np.float64))
            blades = objects.point_pair(a, b)
            grade = objects.POINT_PAIR_GRADE
    except DegenerateGeometryError as error:
        raise DegenerateGeometryError(f"{spec.location}: {error}") from None
    if spec.align:
        blades = objects.align_orientations(blades, grade)
    return EvolvedSurface(spec.name, grade, blades, make_curve(spec), frame)


def _circle_blade(control, frame: LocalFrame) -> np.ndarray:
    if control.through is not None:
        a, b, d = (frame.to_local(np.array(p, dtype=np.float64)) for p in control.through)
        return objects.circle_through(a, b, d)
    return objects.circle_from_center_normal_radius(
        frame.to_local(np.array(control.center, dtype=np.float64)),
        np.array(control.normal, dtype=np.float64),
        control.radius / frame.scale,
    )


def mesh_surface(spec: SurfaceSpec, resolution: Resolution = Resolution()) -> SurfaceMesh:
    """The mesh of one surface, in the scene file's frame and units.

    A tolerance (from the command line, or the file's unless the command line gives a full
    resolution) asks for the fewest vertices within that distance of the true surface; the
    mesh's ``max_deviation`` then holds the measured distance.
    """
    tolerance = _tolerance(spec, resolution)
    if tolerance is None:
        around = resolution.around or spec.around
        along = resolution.along or spec.along
        if spec.type == "circles" and around < 3:
            raise InvalidInputError(f"{spec.location}: a circle needs at least 3 vertices around, got {around}")
    surface = build_surface(spec)
    try:
        if spec.type == "point_pairs":  # caps are circles only (the scene loader refuses them here)
            if tolerance is not None:
                return ribbon_to_tolerance(surface, tolerance, closed=spec.closed)
            return mesh_ribbon_surface(surface, around, along, closed=spec.closed)
        if tolerance is not None:
            return mesh_to_tolerance(surface, tolerance, caps=spec.caps, closed=spec.closed)
        return mesh_circle_surface(surface, around, along, caps=spec.caps, closed=spec.closed)
    except CgameshError as error:
        raise type(error)(f"{spec.location}: {error}") from None


def _tolerance(spec: SurfaceSpec, resolution: Resolution) -> float | None:
    """The tolerance this surface is meshed to, or None for a fixed resolution."""
    if resolution.tolerance is not None:
        return resolution.tolerance
    if spec.tolerance is None:
        return None
    if resolution.around is not None and resolution.along is not None:
        return None
    if resolution.around is not None or resolution.along is not None:
        raise InvalidInputError(
            f"{spec.location}.tolerance: the file asks for a tolerance; give both --around and "
            "--along to override it with a resolution"
        )
    return spec.tolerance


def mesh_scene(scene: Scene, resolution: Resolution = Resolution(),
               progress=lambda label: None) -> list[tuple[SurfaceMesh, Material]]:
    """Every surface's mesh with its material, in file order; ``progress(name)`` after each.

    The UVs are those of each surface's ``uv`` mode (uv.py: natural, none, or one xatlas atlas
    shared by every surface that asks for it).
    """
    meshes = []
    for spec in scene.surfaces:
        meshes.append(mesh_surface(spec, resolution))
        progress(spec.name)
    meshes = uv_map.apply_uv_modes(meshes, [(spec.uv, spec.uv_scale) for spec in scene.surfaces])
    return [(mesh, spec.material) for mesh, spec in zip(meshes, scene.surfaces)]
