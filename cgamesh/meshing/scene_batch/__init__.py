"""The batched pass for scene files: many surfaces of one shape of work meshed as one set of arrays.

The per-surface path (cgamesh.pipeline.mesh_planned: build_surface, then
circles.mesh_circle_surface) pays about 10 ms of Python-level work per surface, whatever its
size. Here a scene's surfaces are grouped by the shape of their work (``scene``), each group's
control blades built for all its surfaces at once (``controls``) and its rings meshed as rows
of one set of arrays (``circle_grid``), with the same operations per row as the per-surface
mesher, so every mesh is that mesher's, bit for bit.

Covered: ``type: circles`` with ``interpolation: blade``, every curve kind (linear, bezier,
rational_bezier, kb, catmull_rom; open or closed), a fixed resolution (the file's or
--around/--along), with or without tangents, with or without caps, every uv mode (applied
afterwards, as for any mesh). Left to the per-surface path: point-pair ribbons, motor
interpolation, tolerance meshing, and single surfaces needing a rare repair (see
``circle_grid``).
"""

from cgamesh.meshing.scene_batch.scene import BatchedScene

__all__ = ["BatchedScene"]
