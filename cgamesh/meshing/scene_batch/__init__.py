"""Scene surfaces of one shape of work read together, as rows of the one mesher.

A scene's surfaces are grouped by the shape of their work (``scene``), each group's control
blades built for all its surfaces at once (``controls``; the projection scan from their pairwise
products, ``projection_scan``), their circles read at every ring by a sampler (``samplers``) and
meshed as rows of cgamesh.meshing.circles.mesh_rings (``circle_grid``), so a surface gets the
mesh it gets meshed alone. Point-pair ribbons go in chunks to the one ribbon mesher
(cgamesh.meshing.ribbons.mesh_ribbons), which meshes many surfaces as it meshes one.

Covered: ``type: circles`` with ``interpolation: blade`` or ``motor``, every curve kind (linear,
bezier, rational_bezier, kb, catmull_rom; open or closed), a fixed resolution (the file's or
--around/--along) of at most CHUNK_VERTICES vertices a surface, with or without tangents, with
or without caps, every uv mode (applied afterwards, as for any mesh). The circles come from a
sampler (``samplers``: the blade projection, or the splined motion). Also ``type: point_pairs``
(blade interpolation, every curve kind, open or closed) at a fixed resolution. Meshed one by
one instead: tolerance meshing, larger surfaces, and surfaces whose group could not read them
(see ``circle_grid`` and cgamesh.meshing.ribbons): their own readers refine a scan or name the error.
"""

from cgamesh.meshing.scene_batch.scene import BatchedScene

__all__ = ["BatchedScene"]
