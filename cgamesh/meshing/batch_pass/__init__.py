"""The batched meshing pass: every chain of a centreline input meshed as one set of arrays.

The per-chain path (cgamesh.pipeline.mesh_surface on one motor SurfaceSpec per chain) pays
Python-level work per chain and per control. This pass computes the same surfaces for all
chains at once: the splined similarity motions of every span of every chain as arrays
(``motions``), every ring's circle, frame, normals, UVs and faces (``rings``), and the
centreline bookkeeping around them: node tangents, attributes, colours, junction events,
assembly into the merged or split output (``chains``), chains leaving the soma among them
(with the per-chain path's radii). A chain whose surface needs one of the
per-chain mesher's rare repairs (a stationary ring, a fold of the normal field, a vanishing
normal, an uncertain outward direction, a normal spline not certified away from zero) is
handed to the per-chain path, so the output is that path's in every case.
"""
