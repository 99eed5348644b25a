"""Meshing a scene file of many small tubes: the batched pass against meshing each surface alone.

    python benchmarks/bench_scene_batch.py [--surfaces 2000] [--controls 4] [--repeats 1]
                                           [--interpolation blade|motor]

Writes the scene of ``bench_scene_reader`` (``surfaces`` catmull_rom tubes of ``controls``
random circles, 8 around, 4 rings per control; blade or motor interpolation), reads it once,
then meshes it in process (``mesh_scene``, reading and export excluded) surface by surface
(``batched=False``) and with the batched pass, and prints the CPU time of this process per surface for both and their
ratio (the machine may be shared: CPU time, the best of ``repeats``), with the share of
surfaces the batched pass took. Checks that both give the same meshes, bit for bit; never
asserts a time. BLAS is pinned to one thread unless OPENBLAS_NUM_THREADS / OMP_NUM_THREADS is
set: the meshers' matrix products are small, and a threaded BLAS spinning on a shared 2-core
machine counts as CPU time of this process.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

import numpy as np  # noqa: E402 (after the BLAS thread count)

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_scene_reader import flow_style, scene_document  # noqa: E402

from cgamesh.inputs.scene import load_scene  # noqa: E402
from cgamesh.pipeline import Resolution, _batched_share, mesh_scene  # noqa: E402

FIELDS = ("positions", "normals", "uvs", "faces", "tangents", "uv_lengths", "weld", "colors")


def cpu_best(repeats: int, work):
    best, result = float("inf"), None
    for _ in range(repeats):
        start = time.process_time()
        result = work()
        best = min(best, time.process_time() - start)
    return best, result


def same(first, second) -> bool:
    for (a, _), (b, _) in zip(first, second):
        for name in FIELDS:
            x, y = getattr(a, name), getattr(b, name)
            if (x is None) != (y is None) or (x is not None and not np.array_equal(x, y)):
                return False
    return len(first) == len(second)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--surfaces", type=int, default=2000)
    parser.add_argument("--controls", type=int, default=4)
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--interpolation", choices=("blade", "motor"), default="blade")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "scene.yaml"
        text = flow_style(scene_document(args.surfaces, args.controls))
        path.write_text(text.replace("    type: circles\n",
                                     f"    type: circles\n    interpolation: {args.interpolation}\n"))
        scene = load_scene(path, rendering=False)
    count = len(scene.surfaces)
    share = _batched_share(scene.surfaces, Resolution(), False)
    taken = sum(1 for i in range(count) if share.takes(i) and share.mesh(i) is not None)
    alone, reference = cpu_best(args.repeats, lambda: mesh_scene(scene, batched=False))
    batched, meshes = cpu_best(args.repeats, lambda: mesh_scene(scene, batched=True))
    print(f"{count} tubes of {args.controls} controls, {args.interpolation} interpolation; "
          f"load average {os.getloadavg()[0]:.2f}")
    print(f"  each surface alone   {1e3 * alone / count:8.3f} ms CPU per surface")
    print(f"  batched pass         {1e3 * batched / count:8.3f} ms CPU per surface "
          f"({taken} of {count} surfaces batched, the rest alone)")
    print(f"  ratio                {alone / batched:8.1f}x faster")
    if not same(reference, meshes):
        print("the batched meshes DIFFER from the per-surface ones", file=sys.stderr)
        return 1
    print("  meshes identical (positions, normals, UVs, faces, tangents, lengths, welds; bit for bit)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
