"""--watertight on navis' five hemibrain neurons, every output format read back as stored and
checked: exactly confirmed crossing pairs, zero-area triangles, and MeshLab's (pymeshlab)
boundary / non-manifold edges and vertices and components after merging equal positions.

    python benchmarks/bench_watertight_real.py [--neurons 722817260 ...] [--formats .ply .glb ...]

Prints one line per neuron and format, and the time of the union (meshing, union, float32 grid
repair) beside the time to write the GLB (the baseline measured in the same run). The slow test
tests/test_watertight_real.py asserts the same on the two smallest neurons; this covers all five.
navis is GPL-3 licensed: its files are read where it installed them, never copied.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

from exact_intersections import confirmed_intersections  # noqa: E402 (the tests' folder is on sys.path)
from realdata_files import neurons  # noqa: E402
from test_watertight_real import FORMATS, meshlab_measures, stored_mesh  # noqa: E402

import cgamesh  # noqa: E402
from cgamesh.inputs.swc import read_swc  # noqa: E402
from cgamesh.meshing.self_intersections import degenerate_faces, self_intersections, welded_faces  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--neurons", nargs="*", help="stems of navis' SWC files (default: all five)")
    parser.add_argument("--formats", nargs="*", default=list(FORMATS))
    args = parser.parse_args()
    files = [p for p in neurons() if not args.neurons or p.stem in args.neurons]
    failures = 0
    print("neuron      format  faces    crossing  zero-area  boundary  non-manifold e/v  components (trees)  "
          "MeshLab flags confirmed")
    with tempfile.TemporaryDirectory() as folder:
        for source in files:
            start = time.perf_counter()
            result = cgamesh.load(source, watertight=True, min_radius=0.5)
            union_time = time.perf_counter() - start
            roots = int(np.count_nonzero(read_swc(source).parents < 0))
            for suffix in args.formats:
                path = Path(folder) / f"{source.stem}{suffix}"
                start = time.perf_counter()
                result.export(path)
                write_time = time.perf_counter() - start
                points, faces = stored_mesh(path)
                crossing = len(self_intersections(points, faces))
                zero_area = len(degenerate_faces(*welded_faces(points, faces)))
                topology, mpoints, mfaces, flagged = meshlab_measures(points, faces)
                confirmed = len(confirmed_intersections(mpoints, mfaces, flagged))
                bad = (crossing or zero_area or confirmed or topology["boundary_edges"]
                       or topology["non_two_manifold_edges"] or topology["non_two_manifold_vertices"]
                       or topology["connected_components_number"] != roots)
                failures += bool(bad)
                print(f"{source.stem:<11} {suffix:<7} {len(faces):<8} {crossing:<9} {zero_area:<10} "
                      f"{topology['boundary_edges']:<9} {topology['non_two_manifold_edges']}/"
                      f"{topology['non_two_manifold_vertices']:<15} {topology['connected_components_number']} ({roots})"
                      f"{'':<14} {confirmed}/{len(flagged)}"
                      + (f"   union {union_time:.1f} s = {union_time / write_time:.0f} x GLB write"
                         if suffix == ".glb" else ""), flush=True)
    print("all clean" if not failures else f"{failures} file(s) not clean")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
