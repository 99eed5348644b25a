"""The batched pass for scene files: many surfaces of one shape of work meshed as one set of arrays.

The per-surface path (cgamesh.pipeline.mesh_planned: build_surface, then
circles.mesh_circle_surface) pays about 10 ms of Python-level work per surface, whatever its
size. Here a scene's surfaces are grouped by the shape of their work (``scene``), each group's
control blades built for all its surfaces at once (``controls``; the projection scan from their
pairwise products, ``projection_scan``) and its rings meshed as rows of one set of arrays
(``circle_grid``), with the same operations per row as the per-surface
mesher, so every mesh is that mesher's, bit for bit. Point-pair ribbons (``ribbon_group``) have
their projection scan and their rulings' point pairs computed for the whole group, and the
ribbon mesher finishes each surface on its slice.

Covered: ``type: circles`` with ``interpolation: blade`` or ``motor``, every curve kind (linear,
bezier, rational_bezier, kb, catmull_rom; open or closed), a fixed resolution (the file's or
--around/--along) of at most CHUNK_VERTICES vertices a surface, with or without tangents, with
or without caps, every uv mode (applied afterwards, as for any mesh). The circles come from a
sampler (``samplers``: the blade projection, or the splined motion). Also ``type: point_pairs``
(blade interpolation, every curve kind, open or closed) at a fixed resolution. Left to the
per-surface path: tolerance meshing, larger surfaces, and single surfaces needing a rare repair
or refused (see ``circle_grid`` and ``ribbon_group``).
"""

from cgamesh.meshing.scene_batch.scene import BatchedScene

__all__ = ["BatchedScene"]
