"""Cost of the watertight union on a neuron-sized input: a random tree of capped tubes, a junction
sphere at every branch point, and a soma.

    python benchmarks/bench_watertight.py [--segments 400] [--around 8] [--rings 4] [--repeats 3]

The tree grows from a soma (radius 6) by adding segments of length 4-20 at the end of a random
earlier segment (a branch point gets a junction sphere of the node's radius), radii tapering from
1.5 to 0.2, as in a dendritic arbor in micrometres. Prints the pieces, the union's vertices and
triangles, and the best of ``repeats`` times for: the union (cgamesh.meshing.watertight.union),
manifold3d's boolean alone (the same pieces, positions only), and writing the union as GLB (the
baseline measured in the same run). It checks the result (every welded edge has exactly two
triangles; the volume is positive and below the pieces' sum); it never asserts a time.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

from closed_pieces import arbor  # noqa: E402 (the tests' folder is on sys.path)
from timing import best_of  # noqa: E402 (this script's folder is on sys.path)

from cgamesh.export.gltf import write_glb  # noqa: E402
from cgamesh.export.options import WriteOptions  # noqa: E402
from cgamesh.material import Material  # noqa: E402
from cgamesh.meshing.watertight import union  # noqa: E402


def boolean_alone(pieces):
    import manifold3d

    solids = []
    for piece in pieces:
        mesh = manifold3d.Mesh64(vert_properties=np.ascontiguousarray(piece.positions),
                                 tri_verts=np.ascontiguousarray(piece.faces, dtype=np.uint64))
        mesh.merge()  # the seams' repeated positions
        solids.append(manifold3d.Manifold(mesh))
    return manifold3d.Manifold.batch_boolean(solids, manifold3d.OpType.Add).to_mesh64()


def check(result, pieces) -> None:
    faces = np.asarray(result.weld)[result.faces]
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    assert (counts == 2).all(), f"{(counts != 2).sum()} welded edges without exactly two triangles"

    def volume(mesh):
        a, b, c = (mesh.positions[mesh.faces[:, k]] for k in range(3))
        return np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0

    assert 0.0 < volume(result) < sum(volume(p) for p in pieces)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--segments", type=int, default=400)
    parser.add_argument("--around", type=int, default=8)
    parser.add_argument("--rings", type=int, default=4, help="rings along each tube, beyond its first")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    pieces = arbor(args.segments, args.around, args.rings, np.random.default_rng(7))
    tubes = sum(p.name.startswith("tube") for p in pieces)
    spheres = len(pieces) - tubes
    vertices = sum(p.vertex_count for p in pieces)
    print(f"pieces: {tubes} tubes, {spheres} spheres (incl. soma); {vertices:,} vertices, "
          f"{sum(p.triangle_count for p in pieces):,} triangles")
    union_time, result = best_of(args.repeats, lambda: union(pieces, "arbor"))
    check(result, pieces)
    alone_time, _ = best_of(args.repeats, lambda: boolean_alone(pieces))
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "arbor.glb")
        glb_time, size = best_of(args.repeats, lambda: write_glb(path, [(result, Material())],
                                                                 WriteOptions("z", 1e-6, "um")))
    print(f"union: {result.vertex_count:,} vertices, {result.triangle_count:,} triangles (closed, 2-manifold)")
    print(f"union             {union_time * 1e3:8.1f} ms  ({union_time / len(pieces) * 1e3:.2f} ms/piece, "
          f"{union_time / glb_time:.1f} x the GLB write)")
    print(f"boolean alone     {alone_time * 1e3:8.1f} ms  (positions only: the channels and bookkeeping cost "
          f"{union_time / alone_time:.2f} x)")
    print(f"GLB write         {glb_time * 1e3:8.1f} ms  ({size:,} bytes; baseline)")


if __name__ == "__main__":
    main()
