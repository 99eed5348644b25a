"""Ribbon meshing speed: microseconds per vertex at 1024 x 1024 for a closed KB ribbon.

    python benchmarks/bench_ribbons.py [--size 1024] [--repeat 7]

Prints the mesher's time per vertex and its ratio to a baseline measured in the same run: a
plain numpy ruled strip of the same size (positions, normals, UVs, faces in float32, no
conformal algebra). Target: ratio <= 2. The mesh is checked (vertices on their segments, unit
normals orthogonal to the rulings); the time is only reported, never asserted. Each timed call
allocates its arrays afresh (timing.best_of); the ratio with recycled memory is printed too.

BLAS is pinned to one thread unless OPENBLAS_NUM_THREADS / OMP_NUM_THREADS is set: the
mesher's per-vertex matrix products are tiny GEMMs, and on 2 cores a threaded BLAS competing
with any other load makes them erratic (best-of-7 times from 30 ms to 170 ms in one session).
"""

from __future__ import annotations

import os

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")  # before numpy loads BLAS

import argparse  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from timing import best_of  # noqa: E402 (this script's folder is on sys.path)

from cgamesh.pipelines.scene import build_surface  # noqa: E402
from cgamesh.meshing.ribbons import PairRings, mesh_ribbon_surface  # noqa: E402
from cgamesh.inputs.scene import load_scene  # noqa: E402

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "ribbon_loop.yaml"


def euclidean_strip(around: int, along: int, turns: float = 2.0, length: float = 4.0):
    """(positions, normals, uvs, faces) of a twisted ruled strip x = a + s (b - a), float32.

    a(t) runs along x while the unit ruling d(t) turns about it; the exact normal is
    d x dx/dt, normalised. Written one coordinate at a time (numpy's fast path).
    """
    t = np.linspace(0.0, 1.0, along, dtype=np.float32)
    s = np.linspace(0.0, 1.0, around, dtype=np.float32)
    rate = np.float32(2.0 * np.pi * turns)
    cos, sin = np.cos(rate * t), np.sin(rate * t)
    # x = (length t, (s - 1/2) cos, (s - 1/2) sin), ruling d = (0, cos, sin):
    # N = d x dx/dt = (rate (s - 1/2), length sin, -length cos).
    positions = np.empty((along, around, 3), dtype=np.float32)
    positions[..., 0] = (length * t)[:, None]
    positions[..., 1] = (s[None, :] - 0.5) * cos[:, None]
    positions[..., 2] = (s[None, :] - 0.5) * sin[:, None]
    normals = np.empty_like(positions)
    normals[..., 0] = rate * (s[None, :] - 0.5) * np.ones_like(t)[:, None]
    normals[..., 1] = length * sin[:, None]
    normals[..., 2] = -length * cos[:, None]
    normals /= np.sqrt(np.einsum("kmc,kmc->km", normals, normals))[..., None]
    uvs = np.empty((along, around, 2), dtype=np.float32)
    uvs[..., 0] = s[None, :]
    uvs[..., 1] = t[:, None]
    corner = np.arange(along - 1, dtype=np.int32)[:, None] * around + np.arange(around - 1, dtype=np.int32)
    faces = np.empty((along - 1, around - 1, 2, 3), dtype=np.int32)
    faces[..., 0, 0], faces[..., 0, 1], faces[..., 0, 2] = corner, corner + 1, corner + around
    faces[..., 1, 0], faces[..., 1, 1], faces[..., 1, 2] = corner + 1, corner + around + 1, corner + around
    return positions.reshape(-1, 3), normals.reshape(-1, 3), uvs.reshape(-1, 2), faces.reshape(-1, 3)


def check(mesh, surface, size: int) -> None:
    """Vertices on their rulings' segments at the right fractions; unit normals across no ruling."""
    t = np.linspace(0.0, surface.segment_count, size)
    rows = np.linspace(0, size - 1, 17).astype(int)
    rings = PairRings.from_projection(surface.sample(t[rows]), surface.frame)
    s = np.linspace(0.0, 1.0, size)
    expected = rings.a[:, None, :] + s[None, :, None] * (rings.b - rings.a)[:, None, :]
    got = mesh.positions.reshape(size, size, 3)[rows]
    length = np.linalg.norm(rings.b - rings.a, axis=1)[:, None]
    assert np.all(np.linalg.norm(got - expected, axis=-1) <= 1e-9 * length), "vertex off its segment"
    normals = mesh.normals.reshape(size, size, 3)[rows]
    assert np.allclose(np.linalg.norm(normals, axis=-1), 1.0, atol=1e-12), "normal not unit"
    ruling = (rings.b - rings.a) / length
    assert np.abs(np.einsum("kmc,kc->km", normals, ruling)).max() <= 1e-9, "normal not across the ruling"
    assert mesh.faces.shape == (2 * (size - 1) ** 2, 3) and mesh.double_sided


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=1024, help="vertices across and rulings along")
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()
    size = args.size
    spec = load_scene(EXAMPLE).surfaces[0]
    surface = build_surface(spec)
    mesh_ribbon_surface(surface, 8, 8, closed=spec.closed)  # warm the product-table caches

    base_time, _ = best_of(args.repeat, lambda: euclidean_strip(size, size))
    ribbon_time, mesh = best_of(args.repeat,
                                lambda: mesh_ribbon_surface(surface, size, size, closed=spec.closed))
    recycled_base, _ = best_of(args.repeat, lambda: euclidean_strip(size, size), keep_previous=True)
    recycled_ribbon, _ = best_of(args.repeat, lambda: mesh_ribbon_surface(surface, size, size, closed=spec.closed),
                                 keep_previous=True)
    check(mesh, surface, size)
    vertices = size * size
    print(f"ribbon ({EXAMPLE.name}, {size} x {size}): {ribbon_time / vertices * 1e6:.4f} us/vertex "
          f"({ribbon_time * 1e3:.1f} ms)")
    print(f"euclidean strip baseline:            {base_time / vertices * 1e6:.4f} us/vertex "
          f"({base_time * 1e3:.1f} ms)")
    print(f"ratio: {ribbon_time / base_time:.2f}x (target <= 2x)")
    print(f"with recycled memory (each run's previous result kept alive): {recycled_ribbon * 1e3:.1f} / "
          f"{recycled_base * 1e3:.1f} ms, ratio {recycled_ribbon / recycled_base:.2f}x")


if __name__ == "__main__":
    main()
