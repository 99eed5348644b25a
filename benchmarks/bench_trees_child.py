"""One timed run of ``bench_trees.py``, in a fresh process running one tree's code.

    python bench_trees_child.py TREE_ROOT kb-tube SCENE SIZE OUT.glb
    python bench_trees_child.py TREE_ROOT scene SCENE WARMUP_SCENE
    python bench_trees_child.py TREE_ROOT command ARG...

- ``kb-tube`` (bench_tubes.py): after a warm-up mesh at 256 x 256 (caches of product term lists;
  f8376ab meshes a surface that large alone, as it meshes 1024 x 1024, not in its batched pass)
  and one at SIZE x SIZE, dropped, ``mesh_scene`` of the scene at SIZE x SIZE, then writing it as
  a GLB (``export.registry.write``), each the median of INNER calls. The timed mesh still touches fresh pages, as a cgamesh run
  does; the dropped one is there because the kernel's cost of handing out 350 MB (system time)
  depends on what ran just before: a child right after another one of that size got them for a
  fifth of the CPU time of a child after a small one, so whichever tree ran first looked 5 times
  slower (0.47 against 0.09 s, the same code; user time 0.04 against 0.05 s).
- ``scene`` (bench_scene_batch.py): after meshing WARMUP_SCENE (a few surfaces of the same
  kind), ``mesh_scene`` of SCENE, read beforehand (reading is not timed).
- ``command`` (bench_realdata.py): ``cgamesh_cli.main.main(ARG...)``; the parent times the
  whole process.

Answers (trees.answer) the user, system and wall seconds of each timed part, the vertex count and its
own peak resident memory. Uses only ``cgamesh.inputs.scene.load_scene``,
``cgamesh.pipeline.Resolution`` / ``mesh_scene`` (without ``batched=``, which goes away),
``cgamesh.export.registry.write`` and ``cgamesh_cli.main.main``, all in f8376ab and after it.
"""

from __future__ import annotations

import gc
import resource
import statistics
import sys
import time

from trees import answer, check_imports, peak_kb


INNER = 5  # the KB tube's mesh and write are 0.05 to 0.1 s: the median of this many calls a child


def timed(work) -> tuple[dict, object]:
    """({"user": s, "system": s, "cpu": s, "wall": s}, result) of one call of ``work``, nothing of
    earlier work in the way. System time is mostly the kernel handing out fresh pages, which a
    machine other work shares makes the noisy part: hence both, apart."""
    gc.collect()
    before, wall = resource.getrusage(resource.RUSAGE_SELF), time.perf_counter()
    result = work()
    after, wall = resource.getrusage(resource.RUSAGE_SELF), time.perf_counter() - wall
    user, system = after.ru_utime - before.ru_utime, after.ru_stime - before.ru_stime
    return {"user": user, "system": system, "cpu": user + system, "wall": wall}, result


def timed_median(work, count: int) -> tuple[dict, object]:
    """``timed`` ``count`` times, each call's result dropped before the next (timing.best_of's
    rule): the median of each figure, and the last result."""
    figures, result = [], None
    for _ in range(count):
        result = None
        figure, result = timed(work)
        figures.append(figure)
    return {key: statistics.median(f[key] for f in figures) for key in figures[0]}, result


def vertices(meshes) -> int:
    return sum(mesh.vertex_count for mesh, _ in meshes)


def scene_pipeline():
    """The scene pipeline's module, under its name in this tree (it moved from cgamesh.pipeline)."""
    try:
        from cgamesh.pipelines import scene
    except ImportError:  # the tree before the move
        from cgamesh import pipeline as scene
    return scene


def writer(scene):
    """``write(path, meshes)`` with the scene's up axis and units, as this tree's writers take them
    (one WriteOptions value, or the keywords before it)."""
    from cgamesh.export.registry import write

    try:
        from cgamesh.export.options import WriteOptions
    except ImportError:  # the tree before WriteOptions
        return lambda path, meshes: write(path, meshes, up=scene.up, meters_per_unit=scene.meters_per_unit,
                                          source_units=scene.units)
    options = WriteOptions(up=scene.up, meters_per_unit=scene.meters_per_unit, source_units=scene.units)
    return lambda path, meshes: write(path, meshes, options)


def kb_tube(path: str, size: str, out: str) -> dict:
    from cgamesh.inputs.scene import load_scene

    Resolution, mesh_scene = scene_pipeline().Resolution, scene_pipeline().mesh_scene

    n = int(size)
    scene = load_scene(path, rendering=False)
    mesh_scene(scene, Resolution(256, 256))
    mesh_scene(scene, Resolution(n, n))  # dropped: see the docstring (the kernel's pages, not the code)
    mesh_time, meshes = timed_median(lambda: mesh_scene(scene, Resolution(n, n)), INNER)
    write = writer(scene)
    write_time, _ = timed_median(lambda: write(out, meshes), INNER)
    return {"mesh": mesh_time, "GLB write": write_time, "vertices": vertices(meshes)}


def scene_batch(path: str, warmup: str) -> dict:
    from cgamesh.inputs.scene import load_scene

    mesh_scene = scene_pipeline().mesh_scene

    mesh_scene(load_scene(warmup, rendering=False))
    scene = load_scene(path, rendering=False)
    mesh_time, meshes = timed(lambda: mesh_scene(scene))
    return {"mesh": mesh_time, "vertices": vertices(meshes)}


def command(argv: list[str]) -> dict:
    from cgamesh_cli.main import main

    status = main(argv)
    if status not in (0, 3):  # 3: segments skipped, as bench_realdata.py allows
        raise SystemExit(f"cgamesh {' '.join(argv)} exited with status {status}")
    return {}


def main() -> None:
    root, case, args = sys.argv[1], sys.argv[2], sys.argv[3:]
    check_imports(root)
    result = {"kb-tube": lambda: kb_tube(*args), "scene": lambda: scene_batch(*args), "command": lambda: command(args)}[case]()
    answer({**result, "peak_kb": peak_kb()})


if __name__ == "__main__":
    main()
