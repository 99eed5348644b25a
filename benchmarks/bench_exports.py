"""Export speed: microseconds per vertex to write GLB, USDC and USDZ for the KB tube at size x size.

    python benchmarks/bench_exports.py [--size 1024] [--repeats 5]

Prints, for the same mesh, the best of ``repeats`` writes of each format in us/vertex and the
USD formats' ratio to GLB (targets: GLB <= 0.15 us/vertex, USD within 3x of GLB), plus the raw
write + fsync of the GLB's bytes as a floor. It checks what it wrote (the GLB reloads to the same
positions; the USD stages have the mesh's point and triangle counts and pass a reload of a few
corners); it never asserts a time.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from timing import best_of  # noqa: E402 (this script's folder is on sys.path)

from cgamesh.export.gltf import write_glb  # noqa: E402
from cgamesh.export.options import WriteOptions  # noqa: E402
from cgamesh.export.usd import write_usd  # noqa: E402
from cgamesh.material import Material  # noqa: E402
from cgamesh.meshing.circles import mesh_circle_surface  # noqa: E402
from cgamesh.pipelines.scene import build_surface  # noqa: E402
from cgamesh.readers.readback import read_gltf  # noqa: E402
from cgamesh.inputs.scene import load_scene  # noqa: E402

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=1024)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    n = args.size

    surface = build_surface(load_scene(EXAMPLES / "kb_tube.yaml").surfaces[0])
    mesh = mesh_circle_surface(surface, n, n)
    surfaces = [(mesh, Material())]
    vertices = mesh.vertex_count
    common = WriteOptions("z", 1.0, "m")
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        results = {}
        for name, path, write in (("GLB", folder / "t.glb", write_glb), ("USDC", folder / "t.usdc", write_usd),
                                  ("USDZ", folder / "t.usdz", write_usd)):
            write(path, surfaces, common)  # warm: imports, allocations
            results[name] = best_of(args.repeats, lambda: write(path, surfaces, common))[0]
            results[name + " bytes"] = path.stat().st_size
        raw = np.zeros(results["GLB bytes"], np.uint8)

        def raw_write():
            with open(folder / "raw.bin", "wb") as f:
                f.write(memoryview(raw))
                f.flush()
                os.fsync(f.fileno())

        floor = best_of(args.repeats, raw_write)[0]
        _check(folder, mesh)

    glb = results["GLB"] / vertices * 1e6
    print(f"KB tube {n} x {n}: {vertices} vertices, {mesh.triangle_count} triangles")
    print(f"  GLB  {glb:.3f} us/vertex ({results['GLB bytes'] / 2**20:.1f} MiB)   target <= 0.15")
    for name in ("USDC", "USDZ"):
        per = results[name] / vertices * 1e6
        print(f"  {name} {per:.3f} us/vertex ({results[name + ' bytes'] / 2**20:.1f} MiB), "
              f"{per / glb:.2f} x GLB   target <= 3 x GLB")
    print(f"  raw write + fsync of the GLB's bytes: {floor / vertices * 1e6:.3f} us/vertex")


def _check(folder: Path, mesh) -> None:
    """What was timed is right: the GLB reloads to the mesh; the USD files have its counts."""
    loaded = read_gltf(folder / "t.glb", world=True)[0]
    expected = mesh.positions @ np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]]).T
    assert np.abs(loaded.positions - expected).max() <= 1e-6 * np.ptp(expected, axis=0).max()
    assert np.array_equal(loaded.faces, mesh.faces)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from pxr import Usd, UsdGeom

    for name in ("t.usdc", "t.usdz"):
        stage = Usd.Stage.Open(str(folder / name))
        usd_mesh = UsdGeom.Mesh(stage.GetDefaultPrim().GetChild(mesh.name))
        points = np.asarray(usd_mesh.GetPointsAttr().Get())
        indices = np.asarray(usd_mesh.GetFaceVertexIndicesAttr().Get())
        assert len(indices) == 3 * mesh.triangle_count
        assert len(points) == len(np.unique(mesh.weld)), "seams welded"
        corners = mesh.faces[:1000].ravel()
        offset = np.asarray(usd_mesh.GetOrderedXformOps()[0].Get())
        np.testing.assert_allclose(points[indices[:3000]] + offset, mesh.positions[corners],
                                   atol=1e-6 * np.ptp(mesh.positions, axis=0).max())


if __name__ == "__main__":
    main()
