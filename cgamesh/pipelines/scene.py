"""From validated scene specs to evolved surfaces and their meshes: scene -> objects -> curve -> mesh.

Geometry errors found on the way (a projection that vanishes, a degenerate control) are
re-raised with the surface's place in the scene file in front of them.

Every surface is priced before any is meshed (cgamesh.budget): a fixed resolution by its
vertex count, a tolerance by the a priori estimate of cgamesh.meshing.tolerance.tolerance_budget (after
checking it against its floor), the outputs by their formats; a scene that asks for more than
``max_memory`` is refused in one line naming the surface and the knob.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cgamesh import budget as costs

from cgamesh.meshing import uv as uv_map
from cgamesh.geometry.construction import build_surface, make_curve  # noqa: F401 (part of this module's API)
from cgamesh.errors import CgameshError, InvalidInputError
from cgamesh.material import Material
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.meshing.circles import mesh_circle_surface
from cgamesh.meshing.ribbons import mesh_ribbon_surface
from cgamesh.inputs.scene import Scene, SurfaceSpec
from cgamesh.meshing.tolerance.tessellation import mesh_to_tolerance, ribbon_to_tolerance
from cgamesh.meshing.tolerance.tolerance_budget import estimate as tolerance_estimate
from cgamesh.meshing.tolerance.tolerance_budget import TOLERANCE_FLOOR, tolerance_floor


FLOAT32_MAX = float(np.finfo(np.float32).max)


@dataclass(frozen=True)
class Resolution:
    """Overrides of every surface's resolution or tolerance from the command line (None keeps the
    file's); ``from_options`` builds one from the table of options (cgamesh.options)."""

    around: int | None = None
    along: int | None = None
    tolerance: float | None = None

    @classmethod
    def from_options(cls, values) -> Resolution:
        """The resolution of ``values`` (a mapping by the table's names; None or absent: the file's)."""
        return cls(values.get("around"), values.get("along"), values.get("tolerance"))


def mesh_surface(spec: SurfaceSpec, resolution: Resolution = Resolution(), tangents: bool = False,
                 max_memory=None, surface=None) -> SurfaceMesh:
    """The mesh of one surface, in the scene file's frame and units.

    A tolerance (from the command line, or the file's unless the command line gives a full
    resolution) asks for a mesh within that distance of the true surface, its counts from an
    a priori bound; the mesh's ``max_deviation`` then holds that bound. ``tangents``: the circle
    mesher's analytic tangents are wanted (an output writes TANGENT). ``max_memory``: the budget
    (bytes, a size such as "2G", a cgamesh.budget.Budget, or None for the default); a surface
    that needs more is refused with ResourceLimitError before anything is allocated.
    ``spec``: a scene file's surface, or any request with its fields (a centreline chain's
    tube); ``surface``: its evolved surface already built (else built from the spec).
    """
    plan = plan_surface(spec, resolution, tangents, surface=surface)
    costs.Budget.of(max_memory).require(plan.peak, plan.where, plan.what, _fitting(plan.tolerance, plan.peak))
    return mesh_planned(plan, tangents)


def _fitting(tolerance: float | None, needed: float):
    """A refusal's advice of about the tolerance that would fit; None at a fixed resolution."""
    if tolerance is None:
        return None
    from cgamesh.meshing.tolerance.tolerance_budget import fitting_advice

    return fitting_advice(tolerance, needed)


@dataclass(frozen=True)
class SurfacePlan:
    """A surface about to be meshed and its price: ``held`` bytes its mesh keeps, ``peak`` the
    most meshing it allocates, ``vertices`` (estimated for a tolerance); ``where`` and ``what``
    name it in a refusal."""

    spec: SurfaceSpec
    surface: object
    around: int | None
    along: int | None
    tolerance: float | None
    vertices: int
    held: int
    peak: int
    where: str
    what: str
    prepared: object = None  # a tolerance's PreparedPlan, priced here and placed by mesh_planned


def plan_surface(spec: SurfaceSpec, resolution: Resolution = Resolution(), tangents: bool = False,
                 build: bool = True, surface=None) -> SurfacePlan:
    """Check and price one surface's request (see the module doc); builds its evolved surface
    unless given as ``surface`` (a fixed resolution's only when ``build``: the batched pass
    builds its own)."""
    tolerance = _tolerance(spec, resolution)
    overridden = resolution.around is not None or resolution.along is not None
    if tolerance is None:
        around = resolution.around or spec.around
        along = resolution.along or spec.along
        if spec.type == "circles" and around < 3:
            if resolution.around:  # the file's own resolution is checked on loading
                raise InvalidInputError(f"--around must be at least 3 for the circles of surface {spec.name!r} "
                                        f"({spec.location.file}:{spec.location.line}), got {around}")
            raise InvalidInputError(f"{spec.location}.resolution.around: a circle needs at least 3 vertices "
                                    f"around, got {around}")
        held, peak = costs.surface_bytes(spec.type, around, along, spec.caps, tangents)
        where = (f"{spec.location} with --around {around} --along {along}" if overridden
                 else f"{spec.location}.resolution")
        if surface is None and build:
            surface = build_surface(spec)
        return SurfacePlan(spec, surface, around, along, None,
                           costs.grid_vertices(spec.type, around, along, spec.caps), held, peak,
                           where, f"mesh ({around} x {along})")
    if surface is None:
        surface = build_surface(spec)
    where = (f"{spec.location} with --tolerance {tolerance:g}" if resolution.tolerance is not None
             else f"{spec.location}.tolerance")
    floor = tolerance_floor(surface)
    if not tolerance >= floor:
        raise InvalidInputError(
            f"{where}: a tolerance must be at least {floor:.3g} for this surface ({TOLERANCE_FLOOR:g} of its bounding "
            f"radius {surface.frame.scale:.3g}, and above float64 rounding at its coordinates), got {tolerance:g}")
    try:
        surface.check_projection_exists()  # before sampling it: a vanishing projection is its own error
        cost = tolerance_estimate(surface, tolerance, closed=spec.closed)
    except CgameshError as error:
        raise type(error)(f"{spec.location}: {error}") from None
    held = costs.HELD_PER_VERTEX * cost.vertices
    return SurfacePlan(spec, surface, None, None, tolerance, cost.vertices, held, max(cost.bytes, held), where,
                       f"meshing to tolerance (about {cost.around + 1} x {cost.along} vertices)", cost.plan)


def mesh_planned(plan: SurfacePlan, tangents: bool) -> SurfaceMesh:
    """Mesh a surface as ``plan_surface`` planned it (the budget already checked)."""
    spec, surface, tolerance, around, along = plan.spec, plan.surface, plan.tolerance, plan.around, plan.along
    try:
        if spec.type == "point_pairs":  # caps are circles only (the scene loader refuses them here)
            if tolerance is not None:
                return ribbon_to_tolerance(surface, tolerance, closed=spec.closed, prepared=plan.prepared)
            return mesh_ribbon_surface(surface, around, along, closed=spec.closed)
        if tolerance is not None:
            return mesh_to_tolerance(surface, tolerance, caps=spec.caps, closed=spec.closed, tangents=tangents,
                                     prepared=plan.prepared)
        return mesh_circle_surface(surface, around, along, caps=spec.caps, closed=spec.closed,
                                   with_tangents=tangents, distinct=True)
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


def _check_uv_scale(mesh: SurfaceMesh, spec: SurfaceSpec) -> None:
    """Refuse a ``uv_scale`` so small that texture coordinates would leave float32's range
    (every output stores them in float32, and they would be written as infinities)."""
    if spec.uv != "natural" or spec.uv_scale is None:
        return
    least = uv_map.natural_extent(mesh) / FLOAT32_MAX
    if spec.uv_scale < least:
        raise InvalidInputError(f"{spec.location}.uv_scale must be at least {least:.3g} for this surface "
                                f"(its texture coordinates would overflow float32), got {spec.uv_scale!r}")


def mesh_scene(scene: Scene, resolution: Resolution = Resolution(), progress=lambda label: None,
               tangents: bool = False, max_memory=None,
               outputs: Sequence[str] = ()) -> list[tuple[SurfaceMesh, Material]]:
    """Every surface's mesh with its material, in file order; ``progress(name)`` after each.

    The UVs are those of each surface's ``uv`` mode (uv.py: natural, none, or one xatlas atlas
    shared by every surface that asks for it). Before any surface is meshed the whole request
    is priced against ``max_memory`` (see ``mesh_surface``): every mesh kept, the largest
    meshing peak, and the largest export of ``outputs`` (their file names or extensions,
    written one after another); ResourceLimitError when it exceeds it.

    Surfaces of one shape of work (cgamesh.meshing.scene_batch) are meshed together, group by
    group, as rows of the one mesher; the rest (a tolerance, a surface larger than a group's
    chunk, one whose group could not read it) one by one.
    """
    budget = costs.Budget.of(max_memory)
    batch = _batched_share(scene.surfaces, resolution, tangents)
    plans = [plan_surface(spec, resolution, tangents, build=not batch.takes(i))
             for i, spec in enumerate(scene.surfaces)]
    for plan in plans:
        budget.require(plan.peak, plan.where, plan.what, _fitting(plan.tolerance, plan.peak))
    held = sum(plan.held for plan in plans)
    vertices = sum(plan.vertices for plan in plans)
    transient = max([plan.peak - plan.held for plan in plans]
                    + [costs.export_bytes(costs.output_suffixes(outputs), vertices, tangents)])
    # one tolerance for every surface (--tolerance): the whole scene scales with it
    shared = resolution.tolerance if all(plan.tolerance is not None for plan in plans) else None
    budget.require(held + transient, f"{scene.path}", f"meshes and exports ({len(plans)} surfaces, "
                   f"about {vertices} vertices)", _fitting(shared, held + transient))
    meshes = []
    for i, plan in enumerate(plans):
        mesh = batch.mesh(i) if batch.takes(i) else None
        if mesh is None:
            if plan.surface is None:  # left by the batched pass: built and meshed alone
                plan = plan_surface(plan.spec, resolution, tangents)
            mesh = mesh_planned(plan, tangents)
        meshes.append(mesh)
        progress(plan.spec.name)
    for mesh, spec in zip(meshes, scene.surfaces):
        _check_uv_scale(mesh, spec)
    meshes = uv_map.apply_uv_modes(meshes, [(spec.uv, spec.uv_scale) for spec in scene.surfaces])
    return [(mesh, spec.material) for mesh, spec in zip(meshes, scene.surfaces)]


def _batched_share(specs: Sequence[SurfaceSpec], resolution: Resolution, tangents: bool):
    """The batched pass's share of a scene (scene_batch.BatchedScene), from each surface's request
    as ``plan_surface`` reads it; a request it would refuse is left to it (and refused there)."""
    from cgamesh.meshing.scene_batch import BatchedScene

    requests = []
    for spec in specs:
        try:
            tolerance = _tolerance(spec, resolution)
        except CgameshError:
            tolerance = float("nan")  # not batched: plan_surface names the error
        if tolerance is None:
            requests.append((resolution.around or spec.around, resolution.along or spec.along, None))
        else:
            requests.append((None, None, tolerance))
    return BatchedScene.prepare(specs, requests, tangents)
