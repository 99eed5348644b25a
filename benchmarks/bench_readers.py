"""Reading a GLB back: cgamesh's checked glTF reader against pygltflib's, on the same file.

    python benchmarks/bench_readers.py [--size 1024] [--repeats 5]

Writes the KB tube at size x size as a GLB, then reads it back, best of ``repeats``, with
``cgamesh.readers.readback.read_gltf`` (every declared number checked, values checked for
finiteness and against min / max, indices against the vertex count) and with the baseline:
pygltflib's load plus numpy views of the same accessors (no checks at all). Prints both in
us/vertex and their ratio; checks that both readers return the mesh that was written; never
asserts a time.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from timing import best_of  # noqa: E402 (this script's folder is on sys.path)

from cgamesh.export.gltf import write_glb  # noqa: E402
from cgamesh.export.options import WriteOptions  # noqa: E402
from cgamesh.inputs.scene import load_scene  # noqa: E402
from cgamesh.material import Material  # noqa: E402
from cgamesh.meshing.circles import mesh_circle_surface  # noqa: E402
from cgamesh.pipelines.scene import build_surface  # noqa: E402
from cgamesh.readers.readback import read_gltf  # noqa: E402

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
DTYPES = {5121: np.uint8, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
WIDTHS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}


def unchecked_read(path: Path):
    """The baseline: pygltflib parses the file; the first primitive's arrays are numpy views."""
    import pygltflib

    gltf = pygltflib.GLTF2().load(str(path))
    blob = gltf.binary_blob()
    primitive = gltf.meshes[0].primitives[0]

    def values(index):
        accessor = gltf.accessors[index]
        view = gltf.bufferViews[accessor.bufferView]
        dtype, width = np.dtype(DTYPES[accessor.componentType]), WIDTHS[accessor.type]
        start = (view.byteOffset or 0) + (accessor.byteOffset or 0)
        return np.frombuffer(blob, dtype, accessor.count * width, start).reshape(-1, width).astype(np.float64)

    return (values(primitive.attributes.POSITION), values(primitive.attributes.NORMAL),
            values(primitive.attributes.TEXCOORD_0), values(primitive.indices).astype(np.int64).reshape(-1, 3))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=1024)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    n = args.size

    surface = build_surface(load_scene(EXAMPLES / "kb_tube.yaml").surfaces[0])
    mesh = mesh_circle_surface(surface, n, n)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "t.glb"
        write_glb(path, [(mesh, Material())], WriteOptions("z", 1.0, "m"))
        checked_time, checked = best_of(args.repeats, lambda: read_gltf(path)[0])
        baseline_time, baseline = best_of(args.repeats, lambda: unchecked_read(path))
    np.testing.assert_array_equal(checked.positions, baseline[0])
    np.testing.assert_array_equal(checked.normals, baseline[1])
    np.testing.assert_array_equal(checked.faces, baseline[3])
    np.testing.assert_array_equal(checked.faces, mesh.faces)
    n_file = np.stack([mesh.normals[:, 0], mesh.normals[:, 2], -mesh.normals[:, 1]], axis=1)  # glTF is +Y up
    assert np.abs(checked.normals - n_file).max() < 1e-6  # float32 of the mesher's normals
    vertices = mesh.vertex_count
    print(f"KB tube {n} x {n}: {vertices} vertices, {mesh.triangle_count} triangles, {path.name}")
    print(f"  checked reader (cgamesh)     {checked_time / vertices * 1e6:.3f} us/vertex")
    print(f"  unchecked (pygltflib views)  {baseline_time / vertices * 1e6:.3f} us/vertex")
    print(f"  ratio                        {checked_time / baseline_time:.2f}")


if __name__ == "__main__":
    main()
