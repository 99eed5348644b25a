"""Reading a scene file of thousands of surfaces: the fast path against the careful reader.

    python benchmarks/bench_scene_reader.py [--surfaces 2000] [--controls 4] [--repeats 3]

Writes two scenes of ``surfaces`` tubes of ``controls`` circles each, with coordinates at
full float64 precision (what a converter writes): one with a control per line as a flow
mapping (as the examples are written), one as PyYAML's ``safe_dump`` writes it (every number
on a line of its own). Times the whole read, file to validated specs (``load_scene``, meshing's
call), best of ``repeats``, with the fast path and with the careful reader alone
(``fast=False``: PyYAML's pure-Python node tree with every line), and prints MB/s for both
and their ratio; for reference, also libyaml's C parser building PyYAML's node tree alone
(``yaml.compose`` with ``CSafeLoader``: no checks, no specs), when PyYAML has it. Each
figure is the shortest of ``repeats`` runs, in wall time and in CPU time of this process
(the two differ on a machine shared with other work). Checks that both readers return the
same scene; never asserts a time. The target is at least 20 MB/s on the flow-style scene.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from timing import best_of  # noqa: E402 (this script's folder is on sys.path)

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


def timed(repeats: int, work) -> tuple[float, float, object]:
    """(shortest wall time, shortest CPU time of this process, last result) of ``work()``."""
    cpu = []

    def measured():
        start = time.process_time()
        result = work()
        cpu.append(time.process_time() - start)
        return result

    wall, result = best_of(repeats, measured)
    return wall, min(cpu), result


def rates(megabytes: float, wall: float, cpu: float) -> str:
    return f"{megabytes / wall:6.2f} MB/s wall {megabytes / cpu:6.2f} MB/s CPU"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--surfaces", type=int, default=2000)
    parser.add_argument("--controls", type=int, default=4)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    document = scene_document(args.surfaces, args.controls)
    print(f"{args.surfaces} surfaces of {args.controls} controls; PyYAML {yaml.__version__}, "
          f"libyaml C parser {'available' if yaml.__with_libyaml__ else 'NOT available'}")
    with tempfile.TemporaryDirectory() as folder:
        for style, text in (("flow controls", flow_style(document)),
                            ("PyYAML safe_dump", yaml.safe_dump(document, sort_keys=False))):
            path = Path(folder) / "scene.yaml"
            path.write_text(text)
            megabytes = os.path.getsize(path) / 1e6
            fast_wall, fast_cpu, fast = timed(args.repeats, lambda: load_scene(path, rendering=False))
            careful_wall, careful_cpu, careful = timed(
                max(1, args.repeats // 2), lambda: load_scene(path, rendering=False, fast=False))
            if fast != careful:
                print(f"{style}: the two readers DIFFER", file=sys.stderr)
                return 1
            print(f"{style} ({megabytes:.2f} MB):\n"
                  f"  fast path        {rates(megabytes, fast_wall, fast_cpu)}\n"
                  f"  careful reader   {rates(megabytes, careful_wall, careful_cpu)}"
                  f"   (fast path {careful_wall / fast_wall:.1f}x faster in wall time)")
            if yaml.__with_libyaml__:
                wall, cpu, _ = timed(1, lambda: yaml.compose(path.read_text(), Loader=yaml.CSafeLoader))
                print(f"  libyaml nodes    {rates(megabytes, wall, cpu)}   (parse only, for reference)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
