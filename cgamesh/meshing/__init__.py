"""Meshing: surfaces to triangle meshes.

    circles.py       the one circle mesher: rows of rings of any number of surfaces (one surface
                     is a batch of one) to grids of vertices, analytic normals, tangents, UVs,
                     faces, caps; the rare repairs on the rows that need them
    ring_rows.py     its input: rings of many surfaces as rows (circles, Omega, frames, parameters)
    ring_frames.py   ring frames carried by TRS rotations over rows of rings (and closed loops)
    ring_normals.py  the rings' normal field: its continuity across folds and the outward choice
    normals.py       analytic normals as per-ring trigonometric polynomials (paper section 5.2)
    ribbons.py       point-pair ribbons
    uv.py            natural UVs, uv modes, tangents from UVs
    node_normals.py  ring planes at centreline nodes
    junctions.py, frusta.py, watertight.py, float32_grid.py, self_intersections.py
                     branch-point spheres, the watertight union and its repairs
    merge.py, weld.py, colors.py, mesh.py
                     many meshes into one, welding, colour maps, the SurfaceMesh value
    tolerance/       meshing to a tolerance from a priori bounds
    batch_pass/      centreline chains read as rows of rings, chunk by chunk
    scene_batch/     scene surfaces of one shape of work read together
"""
