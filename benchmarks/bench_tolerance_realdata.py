"""Tolerance meshing on real data against the smallest uniform grids, per tube.

    python benchmarks/bench_tolerance_realdata.py [--relative 1e-3] [--chains N | --whole | --files [--sample N]]

For the smallest of navis' example neurons (its own radii) and dipy's fornix (300 streamlines,
radius 0.5 mm), every chain is meshed to a tolerance of ``--relative`` times the median tube
radius, as `cgamesh FILE --tolerance D` meshes it (motor interpolation through the nodes), and
compared with the smallest uniform grid of the same tube with the same vertices around (rings
evenly spaced in the parameter) whose deviation, measured by cgamesh.meshing.tolerance.deviation, reaches
D: found here by doubling and bisection, not by the mesher. Printed per file: the tolerance
meshes' and the uniform grids' vertices and meshing times summed over the chains, their ratios,
the spread of the per-chain vertex ratios, and the largest measured deviation of a tolerance mesh
against D. Times are the least of two runs per chain on the process's CPU clock with one BLAS
thread, both meshes made the way a user gets them: ``pipeline.mesh_surface`` of the chain's
tube, with its tolerance and with ``Resolution(around, along)`` (checked to be the
measured uniform grid bit for bit); so both include building the surface and the pipeline's
checks. By default the first 5 chains of each file (a few minutes); ``--whole`` measures every
chain (hours for the neuron's 1,289 chains on a 2-core machine: the search for each chain's
smallest uniform grid measures every candidate's deviation). ``--files`` compares whole files as
the command meshes them with one uniform resolution for the file (``compare_files``).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from dataclasses import replace
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from report_accuracy import smallest_uniform, tolerance_mesh_deviation, uniform_grid  # noqa: E402
from timing import best_of  # noqa: E402

import cgamesh.pipelines.scene as pipeline  # noqa: E402
from cgamesh.pipelines.centerlines import SOMA, TubeOptions, mesh_centerlines  # noqa: E402
from cgamesh.pipelines.chains import split_chains  # noqa: E402
from cgamesh.errors import CgameshError  # noqa: E402
from cgamesh.inputs.centerlines import read_centerlines  # noqa: E402
from cgamesh.meshing.tolerance.tolerance_plan import plan_tolerance  # noqa: E402
from cgamesh.pipelines.scene import Resolution  # noqa: E402
from cgamesh.pipelines.scene import mesh_surface as real_mesh_surface  # noqa: E402


def least_time(work, repeats: int = 2):
    """(result, least seconds of ``repeats`` runs) on the process's CPU clock (timing.best_of)."""
    seconds, result = best_of(repeats, work, clock=time.process_time)
    return result, seconds


def tube_specs(path: Path, options: TubeOptions) -> list:
    """(request, surface) of every chain, as a tolerance run plans it (caught on its way to the planner)."""
    caught = []
    real = pipeline.plan_surface  # the tolerance run imports it when it plans a chain

    def catching(spec, resolution=Resolution(), *args, surface=None, **kwargs):
        caught.append((spec, surface))  # planned and meshed here coarsely: only the tubes are wanted
        coarse = replace(spec, tolerance=None, around=3, along=2 * (surface.segment_count + 1))
        return real(coarse, resolution, *args, surface=surface, **kwargs)

    pipeline.plan_surface = catching
    try:
        mesh_centerlines(read_centerlines(str(path)), options)
    finally:
        pipeline.plan_surface = real
    return caught


def compare(name: str, path: Path, radius: float | None, relative: float, chains: int | None) -> None:
    lines = read_centerlines(str(path))
    radii = lines.radii if radius is None else np.full(len(lines.points), radius)
    tolerance = relative * float(np.median(radii[radii > 0]))
    specs = tube_specs(path, TubeOptions(radius=radius, tolerance=tolerance, around=8))[:chains]
    totals = dict(vertices=0, seconds=0.0, uniform_vertices=0, uniform_seconds=0.0)
    ratios, worst, skipped = [], 0.0, 0
    for spec, surface in specs:
        try:
            mesh, seconds = least_time(lambda: real_mesh_surface(spec, Resolution(), surface=surface))
        except CgameshError:
            skipped += 1
            continue
        plan = plan_tolerance(surface, tolerance, "circles", spec.closed)
        worst = max(worst, tolerance_mesh_deviation(surface, spec, tolerance, mesh) / tolerance)
        rings, _ = smallest_uniform(surface, spec, plan.around, tolerance, max(2, plan.rings // 2))
        resolution = Resolution(around=plan.around, along=rings)
        uniform, uniform_seconds = least_time(lambda: real_mesh_surface(spec, resolution, surface=surface))
        reference = uniform_grid(surface, spec, plan.around, rings)[0]
        assert np.array_equal(uniform.positions, reference.positions), (name, "not the measured grid")
        totals["vertices"] += mesh.vertex_count
        totals["seconds"] += seconds
        totals["uniform_vertices"] += uniform.vertex_count
        totals["uniform_seconds"] += uniform_seconds
        ratios.append(mesh.vertex_count / uniform.vertex_count)
        if len(ratios) % 50 == 0:
            print(f"  ... {len(ratios)} of {len(specs)} chains: vertices ratio "
                  f"{totals['vertices'] / totals['uniform_vertices']:.2f}, time ratio "
                  f"{totals['seconds'] / totals['uniform_seconds']:.2f}", flush=True)
    ratios = np.array(ratios)
    print(f"{name}: {len(ratios)} tubes (skipped {skipped}), tolerance {tolerance:.3g} ({relative:g} of the median radius)")
    print(f"  tolerance meshes: {totals['vertices']:,} vertices, {1e3 * totals['seconds']:.0f} ms; smallest uniform "
          f"grids: {totals['uniform_vertices']:,} vertices, {1e3 * totals['uniform_seconds']:.0f} ms")
    print(f"  vertices ratio {totals['vertices'] / totals['uniform_vertices']:.2f} (per tube: median "
          f"{np.median(ratios):.2f}, range {ratios.min():.2f}-{ratios.max():.2f}); time ratio "
          f"{totals['seconds'] / totals['uniform_seconds']:.2f}; largest measured deviation {worst:.2f} of the tolerance",
          flush=True)


def compare_files(name: str, path: Path, radius: float | None, relative: float, sample: int | None = None,
                  one_around: bool = False) -> None:
    """The whole file as a user meshes it: ``cgamesh FILE --tolerance D`` against the smallest
    ``--around M --subdivide K`` whose every tube and sphere is within D (one resolution for the
    whole file, as the command takes it). Spheres: a UV sphere of M around is within D of its
    sphere when r deviation_bound(M) <= D (cgamesh.meshing.junctions), so M is at least what the
    largest sphere needs; tubes: each tube's uniform grid measured (cgamesh.meshing.tolerance.deviation),
    K the fewest reaching D on every tube, by doubling and bisection, for each M among the
    sag's count around (1.25, 1.5 and 2 times it, at least the spheres' floor); the fewest
    vertices win. Times: CPU, one run each of mesh_centerlines (no file written), with one BLAS thread. ``sample``:
    K searched on the N tubes whose grids stray most at --subdivide 0 only (every tube costs
    minutes at the resolutions involved): a lower bound of K, so the ratios printed are upper
    bounds of the true ones. ``one_around``: only the first M (the smallest of them)."""
    from cgamesh.pipelines.spheres import spheres_around
    from cgamesh.meshing.tolerance.deviation import CIRCLES, grid_deviation

    lines = read_centerlines(str(path))
    radii = lines.radii if radius is None else np.full(len(lines.points), radius)
    tolerance = relative * float(np.median(radii[radii > 0]))
    tolerance_options = TubeOptions(radius=radius, tolerance=tolerance)
    start = time.process_time()
    built = mesh_centerlines(lines, tolerance_options)
    seconds = time.process_time() - start
    vertices = sum(mesh.vertex_count for mesh in built.meshes)
    del built
    print(f"{name}: whole file, tolerance {tolerance:.3g} ({relative:g} of the median radius): "
          f"{vertices:,} vertices in {seconds:.1f} s CPU", flush=True)

    specs, surfaces = zip(*tube_specs(path, tolerance_options))
    chains, junctions = split_chains(lines)
    soma = lines.kinds == SOMA if lines.kinds is not None else np.zeros(len(lines.points), dtype=bool)
    sphere_radii = np.concatenate([radii[junctions[~soma[junctions]]], radii[soma]])
    floor = int(spheres_around(sphere_radii, tolerance).max()) if len(sphere_radii) else 3
    widest = max(float(surface.circles(np.arange(surface.segment_count + 1.0)).radius.max()) for surface in surfaces)
    sag = int(np.ceil(np.pi / (2.0 * np.arcsin(np.sqrt(0.5 * tolerance / widest)))))  # r (1 - cos(pi / M)) <= D
    candidates = sorted({max(floor, int(np.ceil(f * sag))) for f in (1.25, 1.5, 2.0)})[:1 if one_around else None]

    def deviation(k: int, around: int, subdivide: int) -> float:
        rings = surfaces[k].segment_count * (subdivide + 1) + 1
        _, grid, t = uniform_grid(surfaces[k], specs[k], around, rings)
        return grid_deviation(surfaces[k], t, grid, CIRCLES).max

    best = None
    for around in candidates:
        # the tubes measured: all, or the ``sample`` that stray most at --subdivide 0 (then K is a
        # lower bound of the smallest uniform resolution, and the ratios printed upper bounds)
        order = list(range(len(specs)))
        if sample is not None and sample < len(specs):
            order = list(np.argsort([-deviation(k, around, 0) for k in order])[:sample])

        def reaches(around: int, subdivide: int) -> bool:
            for position, k in enumerate(order):
                if deviation(k, around, subdivide) > tolerance:
                    order.insert(0, order.pop(position))  # the tube that failed last is measured first
                    return False
            return True

        low, high = -1, 1  # reaches(around, low) is False (or low = -1), reaches(around, high) is True
        while not reaches(around, high):
            low, high = high, 2 * high + 1
        while high - low > 1:
            middle = (low + high) // 2
            low, high = (low, middle) if middle >= 0 and reaches(around, middle) else (middle, high)
        options = TubeOptions(radius=radius, around=around, subdivide=high)
        start = time.process_time()
        uniform = mesh_centerlines(lines, options)
        uniform_seconds = time.process_time() - start
        uniform_vertices = sum(mesh.vertex_count for mesh in uniform.meshes)
        del uniform
        print(f"  --around {around} --subdivide {high}: {uniform_vertices:,} vertices in {uniform_seconds:.1f} s CPU",
              flush=True)
        if best is None or uniform_vertices < best[2]:
            best = (around, high, uniform_vertices, uniform_seconds)
    around, subdivide, uniform_vertices, uniform_seconds = best
    bound = "" if sample is None or sample >= len(specs) else (
        f" (K measured on the {sample} of {len(specs)} tubes that stray most at --subdivide 0: at most the "
        "smallest uniform resolution, so these ratios are upper bounds)")
    print(f"  smallest uniform: --around {around} --subdivide {subdivide}; vertices ratio "
          f"{vertices / uniform_vertices:.2f}, time ratio {seconds / uniform_seconds:.2f}{bound}", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--relative", type=float, default=1e-3, help="tolerance / median radius")
    parser.add_argument("--chains", type=int, default=5, help="the first N chains of each file (default 5)")
    parser.add_argument("--whole", action="store_true", help="every chain of each file")
    parser.add_argument("--files", action="store_true",
                        help="whole files as the command meshes them, against one uniform resolution (compare_files)")
    parser.add_argument("--one-around", action="store_true", help="with --files: only the smallest M tried")
    parser.add_argument("--sample", type=int, default=None,
                        help="with --files: search the resolution on the N tubes that stray most (a bound, faster)")
    args = parser.parse_args()
    chains = None if args.whole else args.chains
    from realdata_files import fornix, smallest_neuron

    neuron = smallest_neuron()
    if args.files:
        compare_files(f"navis neuron {neuron.stem}", neuron, None, args.relative, args.sample, args.one_around)
        compare_files("dipy fornix", fornix(), 0.5, args.relative, args.sample, args.one_around)
        return
    compare(f"navis neuron {neuron.stem}", neuron, None, args.relative, chains)
    compare("dipy fornix", fornix(), 0.5, args.relative, chains)


if __name__ == "__main__":
    main()
