"""Which surfaces of a scene the batched pass meshes, in which groups, and when.

``BatchedScene.prepare`` sorts a scene's surfaces: those the batched pass covers (see the
package doc) are grouped by the shape of their work (curve kind, control count, curve
parameters, closed, vertices around, rings along) and their controls built, a chunk of about
CHUNK_RINGS rings at a time; every other surface, and every surface whose controls the
per-surface builder would refuse or change, is left to the per-surface path. ``mesh(i)``
gives surface i's mesh, meshing its whole chunk the first time one of its surfaces is
asked for, or None when the chunk's mesher left that surface to the per-surface path.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from cgamesh.errors import CgameshError
from cgamesh.geometry.construction import make_curve
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.meshing.scene_batch.circle_grid import mesh_blade_circles
from cgamesh.meshing.scene_batch.controls import build_blade_controls

# Rings (surfaces times rings along) per chunk: measured fastest from about 800 to 1,600 on
# tubes of 16 rings (a chunk's products stay within a core's cache; the projection scan makes its
# own passes); at least two surfaces a chunk.
CHUNK_RINGS = 1024


def group_key(spec, around: int | None, along: int | None, tolerance: float | None):
    """The shape of work of a surface, or None when the batched pass does not cover it."""
    if (spec.type != "circles" or spec.interpolation != "blade" or tolerance is not None
            or around is None or along is None or around < 3 or along < 2):
        return None
    try:
        curve = make_curve(spec)
    except CgameshError:
        return None
    return curve, spec.closed, around, along


class _Chunk:
    def __init__(self, key, indices: list[int], specs, built):
        self.key, self.indices, self.specs, self.built = key, indices, specs, built
        self.meshes: dict[int, SurfaceMesh | None] | None = None


class BatchedScene:
    """The batched pass's share of a scene (module doc)."""

    def __init__(self, chunks: list[_Chunk], tangents: bool):
        self._tangents = tangents
        self._chunk_of: dict[int, _Chunk] = {}
        for chunk in chunks:
            for index, ok in zip(chunk.indices, chunk.built.ok):
                if ok:
                    self._chunk_of[index] = chunk

    @classmethod
    def prepare(cls, specs: Sequence, requests: Sequence[tuple[int | None, int | None, float | None]],
                tangents: bool) -> "BatchedScene":
        """specs: the scene's surfaces; requests: each one's (around, along, tolerance) as
        planned (tolerance None for a fixed resolution)."""
        groups: dict[object, list[int]] = {}
        for index, (spec, request) in enumerate(zip(specs, requests)):
            key = group_key(spec, *request)
            if key is not None:
                groups.setdefault(key, []).append(index)
        chunks = []
        for key, members in groups.items():
            size = max(2, CHUNK_RINGS // key[3])
            for start in range(0, len(members), size):
                indices = members[start: start + size]
                chosen = [specs[i] for i in indices]
                chunks.append(_Chunk(key, indices, chosen, build_blade_controls(chosen, key[0].control_count)))
        return cls(chunks, tangents)

    def takes(self, index: int) -> bool:
        """Whether surface ``index`` is meshed here (unless its chunk's mesher leaves it: ``mesh``)."""
        return index in self._chunk_of

    def mesh(self, index: int) -> SurfaceMesh | None:
        chunk = self._chunk_of[index]
        if chunk.meshes is None:
            curve, closed, around, along = chunk.key
            ok = chunk.built.ok
            chosen = [i for i, good in zip(chunk.indices, ok) if good]
            names = [spec.name for spec, good in zip(chunk.specs, ok) if good]
            caps = np.array([spec.caps for spec, good in zip(chunk.specs, ok) if good])
            meshed = mesh_blade_circles(names, chunk.built.controls[ok], chunk.built.origin[ok],
                                        chunk.built.scale[ok], curve, closed, around, along, self._tangents, caps)
            chunk.meshes = dict(zip(chosen, meshed))
            chunk.built = None  # the controls are no longer needed
        return chunk.meshes.pop(index)

    @property
    def surface_count(self) -> int:
        return len(self._chunk_of)
