"""Meshing a scene file of many small tubes: its surfaces together against each surface alone.

    python benchmarks/bench_scene_batch.py [--surfaces 2000] [--controls 4] [--repeats 1]
                                           [--interpolation blade|motor] [--kind tube|ribbon]

Writes the scene of ``bench_scene_reader`` (``surfaces`` catmull_rom tubes of ``controls``
random circles, 8 around, 4 rings per control; blade or motor interpolation), or with
``--kind ribbon`` one of as many catmull_rom ribbons (``ribbon_document``: ``controls`` random
point pairs, 8 across, 4 rulings per control, blade interpolation), reads it once,
then meshes it in process (``mesh_scene``, reading and export excluded) surface by surface
(each a scene of its own) and as one scene, whose surfaces of one shape of work are meshed
together as rows of the one mesher, and prints the CPU time of this process per surface for both
and their ratio (the machine may be shared: CPU time, the best of ``repeats``), with the share of
surfaces meshed together. Checks that both give the same meshes, bit for bit; never
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
from dataclasses import replace
from pathlib import Path

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

import numpy as np  # noqa: E402 (after the BLAS thread count)

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_scene_reader import flow_style, scene_document  # noqa: E402
from timing import best_of  # noqa: E402 (this script's folder is on sys.path)

from cgamesh.inputs.scene import load_scene  # noqa: E402
from cgamesh.pipelines.scene import Resolution, _batched_share, mesh_scene  # noqa: E402

FIELDS = ("positions", "normals", "uvs", "faces", "tangents", "uv_lengths", "weld", "colors")


def ribbon_document(count: int, controls: int, seed: int = 1) -> str:
    """A scene of ``count`` catmull_rom ribbons, each ``controls`` point pairs along a random walk
    whose segments turn a little from control to control; 8 across, 4 rulings per control."""
    rng = np.random.default_rng(seed)
    lines = ["cgamesh: 1", "surfaces:"]
    for i in range(count):
        centre = rng.uniform(-50.0, 50.0, 3)
        step, across = rng.normal(size=3), rng.normal(size=3)
        lines += [f"  - name: ribbon{i}", "    type: point_pairs", "    curve: catmull_rom",
                  f"    resolution: {{around: 8, along: {4 * controls}}}", "    controls:"]
        previous = None
        for _ in range(controls):
            width = rng.uniform(0.5, 1.0)
            # across the walk, turning by less than a quarter turn from the previous control
            across = across - (across @ step) / (step @ step) * step
            across = across / np.linalg.norm(across)
            if previous is not None and across @ previous < 0.0:
                across = -across
            previous = across
            a, b = centre - width * across, centre + width * across
            lines.append(f"      - {{a: {np.round(a, 6).tolist()}, b: {np.round(b, 6).tolist()}}}")
            step = step / np.linalg.norm(step) + 0.3 * rng.normal(size=3)
            centre = centre + 0.8 * step / np.linalg.norm(step)
            across = across + 0.3 * rng.normal(size=3)
    return "\n".join(lines) + "\n"


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
    parser.add_argument("--kind", choices=("tube", "ribbon"), default="tube")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "scene.yaml"
        if args.kind == "ribbon":
            path.write_text(ribbon_document(args.surfaces, args.controls))
        else:
            text = flow_style(scene_document(args.surfaces, args.controls))
            path.write_text(text.replace("    type: circles\n",
                                         f"    type: circles\n    interpolation: {args.interpolation}\n"))
        scene = load_scene(path, rendering=False)
    count = len(scene.surfaces)
    share = _batched_share(scene.surfaces, Resolution(), False)
    taken = sum(1 for i in range(count) if share.takes(i) and share.mesh(i) is not None)
    one_by_one = [replace(scene, surfaces=(spec,)) for spec in scene.surfaces]
    alone, reference = best_of(args.repeats, lambda: [m for one in one_by_one for m in mesh_scene(one)],
                               clock=time.process_time)
    batched, meshes = best_of(args.repeats, lambda: mesh_scene(scene), clock=time.process_time)
    what = "ribbons" if args.kind == "ribbon" else "tubes"
    interpolation = "blade" if args.kind == "ribbon" else args.interpolation
    print(f"{count} {what} of {args.controls} controls, {interpolation} interpolation; "
          f"load average {os.getloadavg()[0]:.2f}")
    print(f"  each surface alone   {1e3 * alone / count:8.3f} ms CPU per surface")
    print(f"  together             {1e3 * batched / count:8.3f} ms CPU per surface "
          f"({taken} of {count} surfaces batched, the rest alone)")
    print(f"  ratio                {alone / batched:8.1f}x faster")
    if not same(reference, meshes):
        print("the meshes made together DIFFER from those made alone", file=sys.stderr)
        return 1
    print("  meshes identical (positions, normals, UVs, faces, tangents, lengths, welds; bit for bit)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
