"""The pipelines, side by side: a scene file's surfaces, and centrelines' tubes, from inputs to meshes.

Each takes validated inputs (cgamesh.inputs) through the stages, surfaces (cgamesh.geometry)
then meshes (cgamesh.meshing), and hands the meshes to the writers (cgamesh.export). The
centreline pipeline makes each chain's tube a circle surface spec and meshes it through the
scene pipeline. Internal: the public face is ``cgamesh.api``.

    scene.py                 specs -> surfaces -> meshes: mesh_scene, mesh_surface, plan_surface (Resolution)
    centerlines.py           centrelines -> chains -> tube specs -> tubes and spheres: mesh_centerlines
    centerline_tolerance.py  under a tolerance: every chain planned, the run priced, then meshed
    tube_options.py          TubeOptions: how centrelines become tubes (the real-data options)
    chains.py                the chains of an input as one flat index array; a chain skipped or taken
    tubes.py                 one chain's tube: its circle surface spec, its mesh's attributes and colours
    spheres.py               the junction and soma spheres: which, how large, how many around, their meshes

``cgamesh.pipeline`` and ``cgamesh.centerline_pipeline``, the old names of scene.py and
centerlines.py, are aliases that warn (FutureWarning) for one release.
"""
