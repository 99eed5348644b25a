"""Centreline chains read as rows of rings of the one circle mesher, chunk by chunk.

The splined similarity motions of every chain (cgamesh.geometry.motors.Motions, open
catmull_rom), their circles read out blade-major (``circle_rows``), every chain's rings as rows of
cgamesh.meshing.circles.mesh_rings (``rings``), and the centreline bookkeeping around them: node
tangents, soma radii, attributes, colours, junction events, assembly into the merged or split
output and the chains that are skipped with their errors (``chains``).
"""
