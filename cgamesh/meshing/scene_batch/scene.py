"""Which surfaces of a scene the batched pass meshes, in which groups, and when.

``BatchedScene.prepare`` sorts a scene's surfaces: those the batched pass covers (see the
package doc) are grouped by the shape of their work (curve kind, control count, curve
parameters, closed, vertices around, rings along; for motor interpolation the motion's kind and
node count) and their controls built (blade) or motions splined (motor, one surface at a time),
in chunks of about CHUNK_RINGS rings; point-pair surfaces are built one by one and grouped by
their built curve, closed, around and along (meshed by ribbons.mesh_ribbons); every other surface, and every
surface whose controls the per-surface builder would refuse or change, is left to the
per-surface path. ``mesh(i)``
gives surface i's mesh, meshing its whole chunk the first time one of its surfaces is
asked for, or None when the chunk's mesher left that surface to the per-surface path.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from cgamesh.errors import CgameshError
from cgamesh.geometry.construction import build_motor_surface, build_surface, make_curve
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.meshing.ribbons import mesh_ribbons
from cgamesh.meshing.scene_batch.circle_grid import mesh_circle_group
from cgamesh.meshing.scene_batch.controls import build_blade_controls
from cgamesh.meshing.scene_batch.samplers import BladeSampler, MotorSampler

# Rings (surfaces times rings along) per chunk: measured fastest from about 800 to 1,600 on
# tubes of 16 rings (a chunk's products stay within a core's cache; the projection scan makes its
# own passes).
CHUNK_RINGS = 1024
# Vertices per chunk, and per batched surface: a larger surface is meshed alone (one surface's
# arrays are then long enough, and the per-surface path keeps its measured speed and price);
# a chunk's temporaries are no larger than those of one such surface meshed alone.
CHUNK_VERTICES = 65536


def group_key(spec, around: int | None, along: int | None, tolerance: float | None):
    """The shape of work of a blade-circle surface (curve, closed, around, along), "motor" for a
    motor-interpolated one (its key follows from its built motion), "ribbon" for a point-pair
    surface (its key follows from its built curve), or None when the batched pass does not
    cover it."""
    if (spec.type == "point_pairs" and tolerance is None and around is not None and along is not None
            and around >= 2 and along >= 2 and around * along <= CHUNK_VERTICES
            and getattr(spec, "interpolation", "blade") == "blade"):
        return "ribbon"
    if (spec.type != "circles" or tolerance is not None or around is None or along is None or around < 3
            or along < 2 or (around + 1) * along > CHUNK_VERTICES):
        return None
    if spec.interpolation == "motor":
        return "motor"
    if spec.interpolation != "blade":
        return None
    try:
        curve = make_curve(spec)
    except CgameshError:
        return None
    return curve, spec.closed, around, along


def _chunk_size(around: int, along: int) -> int:
    """Surfaces per chunk: about CHUNK_RINGS rings, at most CHUNK_VERTICES vertices, at least one."""
    return max(1, min(CHUNK_RINGS // along, CHUNK_VERTICES // ((around + 1) * along)))


class _RibbonChunk:
    """Built point-pair surfaces ``indices`` of one curve, closed, around and along."""

    def __init__(self, indices: list[int], surfaces, closed: bool, around: int, along: int):
        self.indices, self.surfaces = indices, surfaces
        self.closed, self.around, self.along = closed, around, along
        self.meshes: dict[int, SurfaceMesh | None] | None = None

    def mesh_all(self, tangents: bool) -> list[SurfaceMesh | None]:
        meshed = mesh_ribbons(self.surfaces, self.around, self.along, closed=self.closed)
        self.surfaces = None
        return meshed


class _Chunk:
    """Surfaces ``indices`` of one shape of work, their sampler and frames; ``meshes`` once meshed."""

    def __init__(self, indices: list[int], specs, sampler, origin, scale, closed: bool, around: int, along: int):
        self.indices, self.sampler, self.origin, self.scale = indices, sampler, origin, scale
        self.names = [spec.name for spec in specs]
        self.caps = np.array([spec.caps for spec in specs], dtype=bool)
        self.closed, self.around, self.along = closed, around, along
        self.meshes: dict[int, SurfaceMesh | None] | None = None

    def mesh_all(self, tangents: bool) -> list[SurfaceMesh | None]:
        meshed = mesh_circle_group(self.names, self.sampler, self.origin, self.scale, self.closed,
                                   self.around, self.along, tangents, self.caps)
        self.sampler = None  # the controls are no longer needed
        return meshed


class BatchedScene:
    """The batched pass's share of a scene (module doc)."""

    def __init__(self, chunks: list[_Chunk], tangents: bool):
        self._tangents = tangents
        self._chunk_of: dict[int, _Chunk] = {index: chunk for chunk in chunks for index in chunk.indices}

    @classmethod
    def prepare(cls, specs: Sequence, requests: Sequence[tuple[int | None, int | None, float | None]],
                tangents: bool) -> "BatchedScene":
        """specs: the scene's surfaces; requests: each one's (around, along, tolerance) as
        planned (tolerance None for a fixed resolution)."""
        blades: dict[object, list[int]] = {}
        motors: dict[object, list[tuple[int, object]]] = {}
        ribbons: dict[object, list[tuple[int, object]]] = {}
        for index, (spec, request) in enumerate(zip(specs, requests)):
            key = group_key(spec, *request)
            if key == "motor":
                try:
                    surface = build_motor_surface(spec)
                except CgameshError:
                    continue  # the per-surface path names the error
                path = surface.path
                motor_key = (path.kind, len(path.nodes), path.closed, path.weights, spec.closed) + request[:2]
                motors.setdefault(motor_key, []).append((index, surface))
            elif key == "ribbon":
                try:
                    surface = build_surface(spec)
                except CgameshError:
                    continue  # the per-surface path names the error
                ribbons.setdefault((surface.curve, spec.closed) + request[:2], []).append((index, surface))
            elif key is not None:
                blades.setdefault(key, []).append(index)
        chunks = []
        for (curve, closed, around, along), members in blades.items():
            size = _chunk_size(around, along)
            for start in range(0, len(members), size):
                indices = members[start: start + size]
                chosen = [specs[i] for i in indices]
                built = build_blade_controls(chosen, curve.control_count)
                ok = built.ok
                if ok.any():
                    chunks.append(_Chunk([i for i, good in zip(indices, ok) if good],
                                         [spec for spec, good in zip(chosen, ok) if good],
                                         BladeSampler(curve, built.controls[ok]), built.origin[ok], built.scale[ok],
                                         closed, around, along))
        for key, members in motors.items():
            closed, around, along = key[4:]
            size = _chunk_size(around, along)
            for start in range(0, len(members), size):
                part = members[start: start + size]
                surfaces = [surface for _, surface in part]
                chunks.append(_Chunk([i for i, _ in part], [specs[i] for i, _ in part],
                                     MotorSampler([surface.path for surface in surfaces]),
                                     np.array([surface.frame.origin for surface in surfaces]),
                                     np.array([surface.frame.scale for surface in surfaces]), closed, around, along))
        for (_, closed, around, along), members in ribbons.items():
            size = max(1, min(CHUNK_RINGS // along, CHUNK_VERTICES // (around * along)))
            for start in range(0, len(members), size):
                part = members[start: start + size]
                chunks.append(_RibbonChunk([i for i, _ in part], [surface for _, surface in part],
                                           closed, around, along))
        return cls(chunks, tangents)

    def takes(self, index: int) -> bool:
        """Whether surface ``index`` is meshed here (unless its chunk's mesher leaves it: ``mesh``)."""
        return index in self._chunk_of

    def mesh(self, index: int) -> SurfaceMesh | None:
        chunk = self._chunk_of[index]
        if chunk.meshes is None:
            chunk.meshes = dict(zip(chunk.indices, chunk.mesh_all(self._tangents)))
        return chunk.meshes.pop(index)

    @property
    def surface_count(self) -> int:
        return len(self._chunk_of)
