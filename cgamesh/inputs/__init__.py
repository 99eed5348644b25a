"""Inputs: what a user hands cgamesh, read and validated at the boundary into values.

Scene files become a ``Scene`` of surface specs; real data (skeletons, tractograms, arrays)
becomes ``Centerlines``. Nothing downstream re-checks them; geometry/ and meshing/ never import
this package.

    formats.py          the table of input formats: suffix or content probe -> reader, kind, default unit; register
    units.py            the length units a reader may name
    scene.py            the careful scene reader: load_scene, parse_scene, located errors
    scene_fast.py       its fast path over plain data (same Scene, or it steps aside)
    scene_subset.py     the YAML subset scene files are written in, read as JSON (the fast path's first pass)
    scene_rules.py      the rules both readers apply: keys, choices, defaults, limits, geometry checks
    scene_specs.py      the values read: Scene, SurfaceSpec, CircleControl, PointPairControl, Location
    scene_yaml.py       the careful reader's YAML: core-schema loading and the node-walking Reader
    scene_rendering.py  the rendering keys: camera, lights, objects, background, depth, attenuation
    centerlines.py      Centerlines: one in-memory type for skeletons, tractograms and arrays
    swc.py              SWC neuron skeletons
    streamlines.py      tractograms (.trk, .tck, .trx)
    arrays.py           plain arrays (.npz, or in memory)
    trees.py            a skeleton split into unbranched chains meeting at junction nodes
"""
