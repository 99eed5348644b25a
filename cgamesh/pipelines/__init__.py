"""The pipelines' parts for centreline inputs: chains -> tube specs -> meshes, with their spheres.

The centreline pipeline (cgamesh.centerline_pipeline) splits an input into chains, makes each
chain's tube a circle surface spec, meshes it through the scene pipeline and closes the branch
nodes and the soma with spheres. Internal: the public face is ``cgamesh.api``.

    tube_options.py   TubeOptions: how centrelines become tubes (the real-data options)
    chains.py         the chains of an input as one flat index array; a chain skipped or taken
    tubes.py          one chain's tube: its circle surface spec, its mesh's attributes and colours
    spheres.py        the junction and soma spheres: which, how large, how many around, their meshes
"""
