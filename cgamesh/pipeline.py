"""From validated scene specs to evolved surfaces and their meshes: scene -> objects -> curve -> mesh.

Geometry errors found on the way (a projection that vanishes, a degenerate control) are
re-raised with the surface's place in the scene file in front of them.
"""

from __future__ import annotations

from dataclasses import dataclass


from cgamesh.meshing import uv as uv_map
from cgamesh.geometry.construction import build_surface, make_curve  # noqa: F401 (part of this module's API)
from cgamesh.errors import CgameshError, InvalidInputError
from cgamesh.material import Material
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.meshing.circles import mesh_circle_surface
from cgamesh.meshing.ribbons import mesh_ribbon_surface
from cgamesh.inputs.scene import Scene, SurfaceSpec
from cgamesh.meshing.tessellation import mesh_to_tolerance, ribbon_to_tolerance


@dataclass(frozen=True)
class Resolution:
    """Overrides of every surface's resolution or tolerance from the command line (None keeps the file's)."""

    around: int | None = None
    along: int | None = None
    tolerance: float | None = None


def mesh_surface(spec: SurfaceSpec, resolution: Resolution = Resolution(), tangents: bool = False) -> SurfaceMesh:
    """The mesh of one surface, in the scene file's frame and units.

    A tolerance (from the command line, or the file's unless the command line gives a full
    resolution) asks for a mesh within that distance of the true surface, its counts from an
    a priori bound; the mesh's ``max_deviation`` then holds that bound. ``tangents``: the circle mesher's
    analytic tangents are wanted (an output writes TANGENT).
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
            return mesh_to_tolerance(surface, tolerance, caps=spec.caps, closed=spec.closed, tangents=tangents)
        return mesh_circle_surface(surface, around, along, caps=spec.caps, closed=spec.closed,
                                   with_tangents=tangents)
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


def mesh_scene(scene: Scene, resolution: Resolution = Resolution(), progress=lambda label: None,
               tangents: bool = False) -> list[tuple[SurfaceMesh, Material]]:
    """Every surface's mesh with its material, in file order; ``progress(name)`` after each.

    The UVs are those of each surface's ``uv`` mode (uv.py: natural, none, or one xatlas atlas
    shared by every surface that asks for it).
    """
    meshes = []
    for spec in scene.surfaces:
        meshes.append(mesh_surface(spec, resolution, tangents))
        progress(spec.name)
    meshes = uv_map.apply_uv_modes(meshes, [(spec.uv, spec.uv_scale) for spec in scene.surfaces])
    return [(mesh, spec.material) for mesh, spec in zip(meshes, scene.surfaces)]
