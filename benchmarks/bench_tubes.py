"""Tube meshing and export speed, against a plain numpy tube measured in the same run.

    python benchmarks/bench_tubes.py [--size 1024]

Prints microseconds per vertex for: the mesh (vertices, normals, UVs, faces) of the KB tube
example at size x size, the Euclidean baseline tube of the same size, GLB writing, and the
wall time of a cold `cgamesh` run on a 64 x 256 example. It checks that the mesh it timed is
right (vertices on their circles, unit normals); it never asserts a time.

Each timed call allocates its arrays afresh, as a cgamesh run does (timing.best_of); the
ratio is also printed for recycled memory, the cheaper regime of a process that keeps
meshing, where the previous result stays alive and its freed pages are reused.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from euclidean_tube import euclidean_tube  # noqa: E402
from timing import best_of  # noqa: E402

from cgamesh.export.gltf import write_glb  # noqa: E402
from cgamesh.export.options import WriteOptions  # noqa: E402
from cgamesh.material import Material  # noqa: E402
from cgamesh.meshing.circles import mesh_circle_surface  # noqa: E402
from cgamesh.pipelines.scene import build_surface  # noqa: E402
from cgamesh.inputs.scene import load_scene  # noqa: E402
from cgamesh.geometry.surface import CircleRings  # noqa: E402

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def check_on_circles(surface, mesh, around: int, along: int) -> float:
    """Largest distance of a grid vertex from its ring's circle, relative to the surface size."""
    t = np.linspace(0.0, surface.segment_count, along)
    rings = CircleRings.from_projection(surface.sample(t), surface.frame)
    grid = mesh.positions[: along * (around + 1)].reshape(along, around + 1, 3)
    offset = grid - rings.centre[:, None, :]
    height = np.einsum("kmi,ki->km", offset, rings.normal)
    in_plane = np.linalg.norm(offset - height[..., None] * rings.normal[:, None, :], axis=-1)
    error = np.hypot(height, in_plane - rings.radius[:, None])
    return float(error.max() / surface.frame.scale)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=1024)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    n = args.size

    surface = build_surface(load_scene(EXAMPLES / "kb_tube.yaml").surfaces[0])
    mesh_circle_surface(surface, 16, 16)  # warm caches of product term lists
    mesh_seconds, mesh = best_of(args.repeats, lambda: mesh_circle_surface(surface, n, n))
    base_seconds, _ = best_of(args.repeats, lambda: euclidean_tube(n, n))
    recycled_mesh, _ = best_of(args.repeats, lambda: mesh_circle_surface(surface, n, n), keep_previous=True)
    recycled_base, _ = best_of(args.repeats, lambda: euclidean_tube(n, n), keep_previous=True)
    vertices = mesh.vertex_count
    error = check_on_circles(surface, mesh, n, n)
    unit = np.abs(np.linalg.norm(mesh.normals, axis=1) - 1.0).max()
    assert error < 1e-9 and unit < 1e-12, (error, unit)

    with tempfile.TemporaryDirectory() as folder:
        target = Path(folder) / "tube.glb"
        glb_seconds, _ = best_of(args.repeats, lambda: write_glb(
            target, [(mesh, Material())], WriteOptions("z", 1.0, "m")))
        cold_scene = EXAMPLES / "kb_tube.yaml"
        start = time.perf_counter()
        command = Path(sys.executable).with_name("cgamesh")  # the console script beside this Python
        subprocess.run([str(command), str(cold_scene), "-o", str(Path(folder) / "cold.glb"), "-q",
                        "--around", "64", "--along", "256"], check=True)
        cold_seconds = time.perf_counter() - start

    per_vertex = 1e6 / vertices
    print(f"kb tube mesh {n} x {n}: {vertices} vertices, {mesh.triangle_count} triangles")
    print(f"  mesh (V+N+UV+F, float64):  {mesh_seconds * per_vertex:.4f} us/vertex")
    print(f"  euclidean tube (float32):  {base_seconds * per_vertex:.4f} us/vertex")
    print(f"  ratio mesh / euclidean:    {mesh_seconds / base_seconds:.2f} (target <= 2)")
    print(f"  with recycled memory:      {recycled_mesh * per_vertex:.4f} / {recycled_base * per_vertex:.4f} us/vertex, "
          f"ratio {recycled_mesh / recycled_base:.2f} (each run's previous result kept alive)")
    print(f"  GLB write:                 {glb_seconds * per_vertex:.4f} us/vertex (target <= 0.15)")
    print(f"  cold cgamesh run 64 x 256: {cold_seconds:.2f} s wall (target <= 1.0)")
    print(f"  checked: vertices on their circles to {error:.1e} relative, normals unit to {unit:.1e}")


if __name__ == "__main__":
    main()
