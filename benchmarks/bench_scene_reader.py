"""Reading a scene file of thousands of surfaces: the fast path against the careful reader.

    python benchmarks/bench_scene_reader.py [--surfaces 2000] [--controls 4] [--repeats 3]

Writes the same scene of ``surfaces`` tubes of ``controls`` circles each, coordinates at
full float64 precision (what a converter writes), in three layouts: a flow mapping per
control (as the examples are written), PyYAML's ``safe_dump`` block layout (every number on
a line of its own, about five times the lines) and its mixed layout (``default_flow_style=
None``: flow lists under block mappings). Times the whole read, file to validated scene
(``load_scene``, meshing's call: reading, parsing, checking every value and building every
spec), with the fast path and with the careful reader alone (``fast=False``: PyYAML's
pure-Python node tree with every line), and prints MB/s of that whole read, in CPU time of
the reading process and in wall time (the two differ on a machine shared with other work),
with the careful reader's as the baseline of the same run. For reference, libyaml's C loader
(``yaml.load`` with ``CSafeLoader``: plain data only, no lines, no checks, no specs), when
PyYAML has it. The fast path is timed in a fresh process for each layout, as a command reads
its scene (after other readings the heap is larger and the same read slower). Its JSON
reader is orjson's when installed (the ``fastread`` extra), else json's; the first line says
which. Each figure is the shortest of ``repeats`` runs. Checks that both readers
return the same scene; never asserts a time. Target: at least 20 MB/s (CPU) for the whole
read in every layout; a line per layout says whether it is met.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import yaml

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from timing import best_wall_and_cpu as timed  # noqa: E402 (this script's folder is on sys.path)

from cgamesh.inputs.scene import load_scene  # noqa: E402


def scene_document(surfaces: int, controls: int, seed: int = 7) -> dict:
    """Tubes of random circles, every number a float64 at full precision."""
    rng = np.random.default_rng(seed)
    out = []
    for index in range(surfaces):
        centers = np.cumsum(rng.normal(size=(controls, 3)), axis=0).tolist()
        normals = rng.normal(size=(controls, 3)).tolist()
        radii = (0.1 + rng.random(controls)).tolist()
        out.append({"name": f"branch_{index}", "type": "circles", "curve": "catmull_rom",
                    "controls": [{"center": c, "normal": n, "radius": r}
                                 for c, n, r in zip(centers, normals, radii)],
                    "resolution": {"around": 8, "along": 4 * controls}})
    return {"cgamesh": 1, "units": "mm", "up": "z", "surfaces": out}


def flow_style(document: dict) -> str:
    """One control per line, as a flow mapping; the rest in block style."""
    lines = [f"cgamesh: {document['cgamesh']}", f"units: {document['units']}",
             f"up: {document['up']}", "surfaces:"]
    for surface in document["surfaces"]:
        lines += [f"  - name: {surface['name']}", f"    type: {surface['type']}",
                  f"    curve: {surface['curve']}", "    controls:"]
        for control in surface["controls"]:
            center, normal = (", ".join(map(repr, control[k])) for k in ("center", "normal"))
            lines.append(f"      - {{center: [{center}], normal: [{normal}], "
                         f"radius: {control['radius']!r}}}")
        resolution = surface["resolution"]
        lines.append(f"    resolution: {{around: {resolution['around']}, along: {resolution['along']}}}")
    return "\n".join(lines) + "\n"


def rates(megabytes: float, wall: float, cpu: float) -> str:
    return f"{megabytes / wall:6.2f} MB/s wall {megabytes / cpu:6.2f} MB/s CPU"


TARGET_MB_PER_S = 20.0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--surfaces", type=int, default=2000)
    parser.add_argument("--controls", type=int, default=4)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--time-fast-path", metavar="FILE", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.time_fast_path:  # the fast path's timing in a process of its own (see below)
        wall, cpu, _ = timed(args.repeats, lambda: load_scene(args.time_fast_path, rendering=False))
        print(wall, cpu)
        return 0
    document = scene_document(args.surfaces, args.controls)
    from cgamesh.inputs.scene_subset import json_reader

    reader = "orjson" if getattr(json_reader(), "__module__", "") == "orjson" else "json"
    print(f"{args.surfaces} surfaces of {args.controls} controls; PyYAML {yaml.__version__}, "
          f"libyaml C loader {'available' if yaml.__with_libyaml__ else 'NOT available'}; "
          f"JSON reader of the fast path: {reader}; "
          f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print("MB/s of the whole read, file -> validated scene (load_scene), best of runs")
    layouts = (("flow controls", flow_style(document)),
               ("PyYAML safe_dump block", yaml.safe_dump(document, sort_keys=False)),
               ("PyYAML safe_dump mixed",
                yaml.safe_dump(document, sort_keys=False, default_flow_style=None)))
    met = []
    with tempfile.TemporaryDirectory() as folder:
        paths = []
        for index, (style, text) in enumerate(layouts):
            paths.append(Path(folder) / f"scene_{index}.yaml")
            paths[-1].write_text(text)
        for (style, text), path in zip(layouts, paths):
            # The fast path timed in a fresh process, as a command reads its scene: after
            # other readings (the careful reader's node trees most of all) the heap is larger
            # and the same read some 5-10% slower.
            timing = subprocess.run([sys.executable, __file__, "--time-fast-path", str(path),
                                     "--repeats", str(args.repeats)],
                                    capture_output=True, text=True, check=True)
            fast_wall, fast_cpu = map(float, timing.stdout.split())
            fast = load_scene(path, rendering=False)
            megabytes = os.path.getsize(path) / 1e6
            careful_wall, careful_cpu, careful = timed(
                max(1, args.repeats // 2), lambda: load_scene(path, rendering=False, fast=False))
            if fast != careful:
                print(f"{style}: the two readers DIFFER", file=sys.stderr)
                return 1
            rate = megabytes / fast_cpu
            met.append(rate >= TARGET_MB_PER_S)
            print(f"{style} ({megabytes:.2f} MB, {text.count(chr(10))} lines):\n"
                  f"  fast path        {rates(megabytes, fast_wall, fast_cpu)}"
                  f"   ({careful_cpu / fast_cpu:.1f}x the careful reader, CPU)\n"
                  f"  careful reader   {rates(megabytes, careful_wall, careful_cpu)}   (baseline)")
            if yaml.__with_libyaml__:
                wall, cpu, _ = timed(1, lambda: yaml.load(path.read_text(), Loader=yaml.CSafeLoader))
                print(f"  libyaml C loader {rates(megabytes, wall, cpu)}   "
                      "(plain data only, for reference)")
            print(f"  target >= {TARGET_MB_PER_S:.0f} MB/s CPU, whole read: "
                  f"{'met' if met[-1] else 'NOT MET'} ({rate:.1f})")
    print(f"target met in {sum(met)} of {len(met)} layouts")
    return 0


if __name__ == "__main__":
    sys.exit(main())
