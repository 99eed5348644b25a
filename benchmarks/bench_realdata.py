"""Real data, file to GLB, cgamesh against pyvista side by side (pyvista: a benchmark-only baseline).

Each case runs as a whole process (read, mesh, write a GLB), cgamesh and pyvista interleaved,
best of a few runs; every child's peak resident memory comes from its own rusage (os.wait4).
Cases: dipy's fornix (tracks300.trk), the same streamlines repeated to a larger count, and
navis' neurons, at 8 vertices around and 3 extra rings between nodes. pyvista's baselines:
``Spline`` (the same rings per node) + ``tube``, and its plain polyline ``tube`` at one ring
per node; both read the same chains (cgamesh's reader) and write a GLB with trimesh. Printed:
time ratios, the per-surface overhead of the batched pass, and peak memory against the bytes
of the mesh arrays written (whole process, and above a bare python + numpy process's peak), beside
the command's own floor: its peak on the smallest input of the same format (a 2-node tree, one
2-point streamline), which no output can go below. Results are checked (vertex counts, finite
arrays); times are printed, never asserted. The big-tube figures: ``python benchmarks/bench_tubes.py``.
``--overhead-only`` runs just the per-surface overhead (in this process: wall and CPU time,
best of ``--repeat``, with the load average), the quick check of the batched pass's fixed and
per-surface costs.

    python benchmarks/bench_realdata.py [--repeat 3] [--copies 10] [--neurons 3] [--blas-threads N] [--tiny] [--overhead-only]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from timing import best_wall_and_cpu  # this script's folder is on sys.path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

AROUND, SUBDIVIDE = 8, 3
BLAS_THREADS = 0  # 0: the environment's setting (--blas-threads)

# Each child prints its own peak resident memory (VmHWM, reset at exec) last: the rusage
# ru_maxrss of a child also counts the parent's pages it was forked from.
PEAK = """
def peak_kb():
    try:
        for line in open('/proc/self/status'):
            if line.startswith('VmHWM:'):
                return int(line.split()[1])
    except OSError:
        pass
    import resource
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
"""

CGAMESH_CHILD = PEAK + """
import sys
from cgamesh_cli.main import main
code = main([sys.argv[1], '-o', sys.argv[2], '--radius', sys.argv[3], '--around', '8', '--subdivide', '3', '-q'])
print('PEAK_KB', peak_kb())
sys.exit(code)
"""

PYVISTA_CHILD = PEAK + """
import sys
import numpy as np
import pyvista as pv
import trimesh
from cgamesh.pipelines.chains import split_chains
from cgamesh.inputs.centerlines import read_centerlines
path, out, radius, mode = sys.argv[1], sys.argv[2], float(sys.argv[3]), sys.argv[4]
lines = read_centerlines(path)
chains, _ = split_chains(lines)
blocks = []
for chain in chains:
    p = lines.points[chain.nodes]
    keep = np.concatenate([[True], np.any(p[1:] != p[:-1], axis=1)])
    p = p[keep]
    if len(p) < 2:
        continue
    line = pv.Spline(p, (len(p) - 1) * 4 + 1) if mode == 'spline' else pv.lines_from_points(p)
    blocks.append(line.tube(radius=radius, n_sides=8, capping=False))
mesh = pv.merge(blocks, merge_points=False).triangulate()  # no search for coincident points
faces = mesh.faces.reshape(-1, 4)[:, 1:]
trimesh.Trimesh(mesh.points, faces, vertex_normals=mesh.point_normals, process=False).export(out)
print('PEAK_KB', peak_kb())
"""


def run_child(code: str, args: list[str]) -> tuple[float, float, float]:
    """(wall seconds, CPU seconds (user + system, from its rusage), peak resident MB (its own
    report)) of one child process: on a machine shared with other work CPU time is the steadier figure."""
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    if BLAS_THREADS:
        env["OPENBLAS_NUM_THREADS"] = env["OMP_NUM_THREADS"] = str(BLAS_THREADS)
    start = time.perf_counter()
    with tempfile.TemporaryFile() as errors:  # a file, not a pipe: nothing to drain while it runs
        child = subprocess.Popen([sys.executable, "-c", code, *args], stdout=subprocess.PIPE,
                                 stderr=errors, env=env)
        output = child.stdout.read().decode()
        child.stdout.close()
        _, status, usage = os.wait4(child.pid, 0)
        seconds = time.perf_counter() - start
        child.returncode = os.waitstatus_to_exitcode(status)
        if child.returncode not in (0, 3):
            errors.seek(0)
            tail = errors.read().decode(errors="replace")[-1500:]
            raise SystemExit(f"child failed with exit status {child.returncode}: {args}\n{tail}")
    peak = [int(line.split()[1]) for line in output.splitlines() if line.startswith("PEAK_KB")]
    return seconds, usage.ru_utime + usage.ru_stime, peak[-1] / 1024.0


BASELINE_CHILD = PEAK + """
import numpy
print('PEAK_KB', peak_kb())
"""


def baseline_memory() -> float:
    """Peak resident MB of a bare python process that imports numpy: the floor under every
    child's peak, whatever it meshes."""
    return run_child(BASELINE_CHILD, [])[2]


# The smallest input of each format the cases read, and how the memory line names it.
SMALLEST = {".swc": "a 2-node tree", ".trk": "one 2-point streamline", ".npz": "one 2-point streamline"}


def smallest_input(suffix: str, folder: Path, radius: float) -> Path:
    """A file of the format ``suffix`` holding the least the command meshes: two nodes (an SWC
    soma and one child) or one streamline of two points, a few radii apart."""
    points = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 8.0 * radius]])
    path = folder / f"smallest{suffix}"
    if suffix == ".swc":
        path.write_text(f"1 1 0 0 0 {radius} -1\n2 3 0 0 {8.0 * radius} {radius} 1\n")
    elif suffix == ".npz":
        np.savez(path, points=points, offsets=np.array([0, 2]))
    elif suffix == ".trk":
        from nibabel.streamlines import Tractogram, save

        save(Tractogram([points.astype(np.float32)], affine_to_rasmm=np.eye(4)), str(path))
    else:
        raise ValueError(f"no smallest input for {suffix}")
    return path


def command_floor(suffix: str, folder: Path, radius: float) -> float:
    """Peak resident MB of the command (the same child as every case) on the smallest input of
    one format: the interpreter, numpy, the command's own modules and its reader's, resident
    before it reads a node, which every run on that format holds, whatever it writes."""
    path = smallest_input(suffix, folder, radius)
    return run_child(CGAMESH_CHILD, [str(path), str(folder / f"smallest{suffix}.glb"), str(radius)])[2]


def glb_vertices(path: Path) -> int:
    """Vertex count of a GLB from its JSON chunk alone (the parent stays small: a child's
    rusage would otherwise include the pages of the parent it was forked from)."""
    import json
    import struct

    with open(path, "rb") as file:
        file.read(12)
        length, _ = struct.unpack("<II", file.read(8))
        gltf = json.loads(file.read(length))
    return sum(gltf["accessors"][p["attributes"]["POSITION"]]["count"] for m in gltf["meshes"] for p in m["primitives"])


def repeated_tractogram(source: Path, copies: int, folder: Path) -> Path:
    """The streamlines of ``source`` ``copies`` times, as .npz arrays (points, offsets)."""
    from cgamesh.inputs.centerlines import read_centerlines

    lines = read_centerlines(str(source))
    count = len(lines.offsets) - 1
    lengths = np.diff(lines.offsets)
    points = np.concatenate([lines.points] * copies)
    offsets = np.concatenate([[0], np.cumsum(np.tile(lengths, copies))])
    path = folder / f"fornix_x{copies}.npz"
    np.savez(path, points=points, offsets=offsets)
    print(f"repeated tractogram: {count * copies} streamlines, {len(points)} points")
    return path


def case(name: str, path: Path, radius: float, repeat: int, folder: Path, baseline: float, floors: dict) -> dict:
    """Interleaved runs of cgamesh, pyvista Spline+tube and pyvista tube; best wall and CPU times.
    ``floors``: the command's floor by file suffix, measured on first use."""
    if path.suffix not in floors:
        floors[path.suffix] = command_floor(path.suffix, folder, radius)
    floor = floors[path.suffix]
    wall = {"cgamesh": np.inf, "spline": np.inf, "tube": np.inf}
    cpu = dict(wall)
    memory = {key: 0.0 for key in wall}
    outputs = {key: folder / f"{name}_{key}.glb" for key in wall}
    for _ in range(repeat):
        for key in wall:
            code, extra = (CGAMESH_CHILD, []) if key == "cgamesh" else (PYVISTA_CHILD, [key])
            seconds, processor, peak = run_child(code, [str(path), str(outputs[key]), str(radius), *extra])
            wall[key], cpu[key] = min(wall[key], seconds), min(cpu[key], processor)
            memory[key] = max(memory[key], peak)
    ours, theirs = glb_vertices(outputs["cgamesh"]), glb_vertices(outputs["spline"])
    assert ours > 0 and theirs > 0, (ours, theirs)
    # cgamesh repeats the seam column ((around + 1) / around of pyvista's vertices on the same
    # rings) and adds junction and soma spheres to neurons
    assert ours / (AROUND + 1) >= 0.98 * theirs / AROUND, (name, ours, theirs)
    if path.suffix != ".swc":
        assert abs(ours / (AROUND + 1) - theirs / AROUND) <= 0.02 * theirs / AROUND + 2, (name, ours, theirs)
    written = outputs["cgamesh"].stat().st_size / 2**20
    print(f"{name:>14}: {ours} vertices; wall cgamesh {wall['cgamesh']:.2f} s, pyvista Spline+tube "
          f"{wall['spline']:.2f} s ({wall['cgamesh'] / wall['spline']:.2f}x, target <= 1.0x), plain tube "
          f"{wall['tube']:.2f} s ({wall['cgamesh'] / wall['tube']:.2f}x, target <= 3x)")
    print(f"{'':>14}  CPU  cgamesh {cpu['cgamesh']:.2f} s, pyvista Spline+tube {cpu['spline']:.2f} s "
          f"({cpu['cgamesh'] / cpu['spline']:.2f}x), plain tube {cpu['tube']:.2f} s "
          f"({cpu['cgamesh'] / cpu['tube']:.2f}x)")
    print(f"{'':>14}  peak memory cgamesh {memory['cgamesh']:.0f} MB for {written:.1f} MB written "
          f"({memory['cgamesh'] / written:.1f}x, target <= 3x; {(memory['cgamesh'] - baseline) / written:.1f}x "
          f"above the {baseline:.0f} MB of a bare python + numpy, which is {baseline / memory['cgamesh']:.0%} of "
          f"the peak; the command on {SMALLEST[path.suffix]} peaks at {floor:.1f} MB, which is "
          f"{floor / written:.1f}x of this output); pyvista Spline+tube {memory['spline']:.0f} MB")
    return wall


def per_surface_overhead(counts: list[int], repeat: int = 1) -> None:
    """Time of N tiny tubes (2 nodes each) through the batched pass, over N, in this process
    after one warm-up call (the one-off imports and cached product tables are not per surface);
    wall and CPU time (CPU: the steadier figure on a shared machine), each the best of
    ``repeat`` calls."""
    from cgamesh.api import tubes

    rng = np.random.default_rng(1)
    tubes([rng.normal(size=(2, 3))], radii=0.5, units="mm")
    print(f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    for n in counts:
        polylines = [rng.normal(size=(2, 3)) * 10.0 for _ in range(n)]
        wall, cpu, built = best_wall_and_cpu(max(repeat, 1), lambda: tubes(polylines, radii=0.5, units="mm"))
        assert sum(m.vertex_count for m, _ in built.surfaces) == n * 5 * (AROUND + 1), "vertex count"
        print(f"per-surface overhead, N = {n:>6}: {1e6 * wall / n:.1f} us per surface wall, "
              f"{1e6 * cpu / n:.1f} us CPU (target < 50 us)")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--copies", type=int, default=10, help="fornix copies (10 = 3,000 streamlines)")
    parser.add_argument("--neurons", type=int, default=3)
    parser.add_argument("--tiny", action="store_true", help="one run, small sizes (the CI test)")
    parser.add_argument("--overhead-only", action="store_true",
                        help="only the per-surface overhead, in this process (best of --repeat)")
    parser.add_argument("--blas-threads", type=int, default=0,
                        help="OPENBLAS_NUM_THREADS for every child (0: as the environment says); on a busy "
                             "machine BLAS threads spin on cgamesh's many small matrix products")
    args = parser.parse_args(argv)
    global BLAS_THREADS
    BLAS_THREADS = args.blas_threads
    if args.overhead_only:
        if BLAS_THREADS:
            print("--blas-threads applies to child processes; set OPENBLAS_NUM_THREADS for --overhead-only")
        per_surface_overhead([10, 100] if args.tiny else [100, 1000, 10000], 1 if args.tiny else args.repeat)
        return
    from realdata_files import fornix, neurons

    repeat = 1 if args.tiny else args.repeat
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        baseline, floors = baseline_memory(), {}
        case("fornix", fornix(), 0.5, repeat, folder, baseline, floors)
        if args.copies > 1:
            case(f"fornix x{args.copies}", repeated_tractogram(fornix(), args.copies, folder), 0.5, repeat, folder,
                 baseline, floors)
        for path in sorted(neurons(), key=lambda p: p.stat().st_size)[: args.neurons]:
            case(path.stem, path, 40.0, repeat, folder, baseline, floors)
    per_surface_overhead([10, 100] if args.tiny else [100, 1000, 10000], repeat)
    print("big-tube figures: python benchmarks/bench_tubes.py")


if __name__ == "__main__":
    main()
