"""The speed/accuracy trades cgamesh offers, measured: tessellation, and the tracer's root finders.

    python benchmarks/report_accuracy.py --out docs [--small]

1. For every surface of the examples (circles and point pairs) it meshes uniform grids of
   growing size and tolerance-driven meshes for tolerances from 1e-1 to 1e-4 of the surface's
   size, and measures each mesh's largest deviation from the true surface over triangle
   interiors (cgamesh.meshing.tolerance.deviation), its vertex count and the time it took; and, at 1e-2,
   1e-3 and 1e-4, compares the tolerance mesh with the smallest uniform grid (same vertices
   around, rings evenly in t) reaching the tolerance, found by search over uniform grids:
   vertices and time as ratios to that grid's.
2. On the fig. 17 scene it measures the tracer's sampled root finder against the number N of
   objects per segment (hit-distance and normal errors, time) against the polynomial finder
   (benchmarks/bench_tracer.py's analysis).

It writes docs/accuracy.md (the tables), docs/figures/accuracy_<example>_<surface>.png
(deviation and time against vertex count) and docs/figures/root_finders.png, and prints the
tables. --small measures fewer sizes and one example, for CI; --examples a,b only those;
--compare-only measures only the comparison with the smallest uniform grids and replaces that
table in an existing docs/accuracy.md.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path

# One thread for BLAS: the CPU clock then counts the work, not idle spinning threads.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from cgamesh.meshing.tolerance.deviation import CIRCLES, SEGMENTS, grid_deviation  # noqa: E402
from cgamesh.meshing.circles import mesh_circle_surface  # noqa: E402
from cgamesh.pipelines.scene import Resolution, build_surface, mesh_surface  # noqa: E402
from cgamesh.meshing.ribbons import mesh_ribbon_surface  # noqa: E402
from cgamesh.meshing.tolerance.tolerance_plan import plan_tolerance  # noqa: E402
from cgamesh.inputs.scene import load_scene  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import best_of  # noqa: E402

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


@dataclass(frozen=True)
class Row:
    example: str
    method: str
    setting: str
    vertices: int
    deviation: float  # relative to the surface's size
    milliseconds: float


def timed(work):
    start = time.perf_counter()
    result = work()
    return result, 1e3 * (time.perf_counter() - start)


def measure_surface(name, spec, sizes, tolerances) -> list[Row]:
    surface = build_surface(spec)
    size = surface.frame.scale
    rows = []
    for n in sizes:
        along = n * surface.segment_count + 1
        t = np.linspace(0.0, surface.segment_count, along)
        if spec.type == "point_pairs":
            across = max(2, n // 4)
            mesh, ms = timed(lambda: mesh_ribbon_surface(surface, across, t=t, closed=spec.closed))
            grid, family, setting = mesh.positions.reshape(along, across, 3), SEGMENTS, f"{across} x {along}"
        else:
            mesh, ms = timed(lambda: mesh_circle_surface(surface, n, t=t, closed=spec.closed))
            grid, family, setting = mesh.positions[: along * (n + 1)].reshape(along, n + 1, 3), CIRCLES, f"{n} x {along}"
        deviation = grid_deviation(surface, t, grid, family).max / size
        rows.append(Row(name, "uniform", setting, mesh.vertex_count, deviation, ms))
    for relative in tolerances:
        mesh, ms = timed(lambda: mesh_surface(spec, Resolution(tolerance=relative * size)))
        assert mesh.max_deviation <= relative * size, (name, relative, mesh.max_deviation / size)
        measured = tolerance_mesh_deviation(surface, spec, relative * size, mesh)
        assert measured <= mesh.max_deviation, (name, relative, measured / size, mesh.max_deviation / size)
        rows.append(Row(name, "tolerance", f"{relative:g}", mesh.vertex_count, measured / size, ms))
    return rows


def tolerance_mesh_deviation(surface, spec, tolerance: float, mesh) -> float:
    """cgamesh.meshing.tolerance.deviation's measure of a tolerance mesh (on its plan's rings)."""
    kind = "point_pairs" if spec.type == "point_pairs" else "circles"
    plan = plan_tolerance(surface, tolerance, kind, spec.closed)
    columns = plan.around if kind == "point_pairs" else plan.around + 1
    grid = mesh.positions[: plan.rings * columns].reshape(plan.rings, columns, 3)
    return grid_deviation(surface, plan.t, grid, SEGMENTS if kind == "point_pairs" else CIRCLES).max


@dataclass(frozen=True)
class Comparison:
    example: str
    relative: float
    around: int
    rings: int
    vertices: int
    milliseconds: float
    bound: float  # relative to the surface's size
    measured: float
    uniform_rings: int
    uniform_vertices: int
    uniform_milliseconds: float
    uniform_measured: float


def best_time(work, repeats: int = 3):
    """(result, least milliseconds of ``repeats`` runs) on the process's CPU clock (timing.best_of):
    the comparison's figures are meant to hold on a machine other work shares."""
    seconds, result = best_of(repeats, work, clock=time.process_time)
    return result, 1e3 * seconds


def uniform_grid(surface, spec, around: int, rings: int):
    """(mesh, grid, t) of the uniform grid: ``around`` vertices around (across), rings even in t."""
    t = np.linspace(0.0, surface.segment_count, rings)
    if spec.type == "point_pairs":
        mesh = mesh_ribbon_surface(surface, around, t=t, closed=spec.closed)
        return mesh, mesh.positions.reshape(rings, around, 3), t
    mesh = mesh_circle_surface(surface, around, t=t, caps=spec.caps, closed=spec.closed)
    return mesh, mesh.positions[: rings * (around + 1)].reshape(rings, around + 1, 3), t


def smallest_uniform(surface, spec, around: int, tolerance: float, start: int) -> tuple[int, float]:
    """The fewest rings (and the deviation) of a uniform grid with ``around`` that reaches the
    tolerance, by doubling then bisection on its measured deviation (cgamesh.meshing.tolerance.deviation)."""
    family = SEGMENTS if spec.type == "point_pairs" else CIRCLES

    def deviation(rings):
        _, grid, t = uniform_grid(surface, spec, around, rings)
        return grid_deviation(surface, t, grid, family).max

    low, high = 1, max(2, start)
    while (high_deviation := deviation(high)) > tolerance:
        low, high = high, 2 * high
    while high - low > 1:
        middle = (low + high) // 2
        middle_deviation = deviation(middle) if middle >= 2 else float("inf")
        if middle_deviation <= tolerance:
            high, high_deviation = middle, middle_deviation
        else:
            low = middle
    return high, high_deviation


def compare_with_uniform(name, spec, relatives) -> list[Comparison]:
    """Per tolerance: the tolerance mesh against the smallest uniform grid reaching it."""
    surface = build_surface(spec)
    size = surface.frame.scale
    kind = "point_pairs" if spec.type == "point_pairs" else "circles"
    rows = []
    for relative in relatives:
        tolerance = relative * size
        mesh, ms = best_time(lambda: mesh_surface(spec, Resolution(tolerance=tolerance)))
        plan = plan_tolerance(surface, tolerance, kind, spec.closed)
        measured = tolerance_mesh_deviation(surface, spec, tolerance, mesh)
        rings, uniform_measured = smallest_uniform(surface, spec, plan.around, tolerance, plan.rings // 2)
        # Both timed the way a user gets them: mesh_surface from the spec (building the surface, the
        # pipeline's checks, meshing). Resolution(around, along) is the report's uniform grid exactly.
        uniform_resolution = Resolution(around=plan.around, along=rings)
        uniform, uniform_ms = best_time(lambda: mesh_surface(spec, uniform_resolution))
        reference = uniform_grid(surface, spec, plan.around, rings)[0]
        assert np.array_equal(uniform.positions, reference.positions), (name, relative, "not the report's grid")
        rows.append(Comparison(name, relative, plan.around, plan.rings, mesh.vertex_count, ms, plan.bound / size,
                               measured / size, rings, uniform.vertex_count, uniform_ms, uniform_measured / size))
    return rows


def comparison_table(rows: list[Comparison]) -> str:
    lines = ["| surface | tolerance | around | rings | vertices | bound | measured | uniform rings "
             "| uniform vertices | uniform measured | vertices ratio | time ratio |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r.example} | {r.relative:g} | {r.around} | {r.rings} | {r.vertices} | {r.bound:.2e} "
                     f"| {r.measured:.2e} | {r.uniform_rings} | {r.uniform_vertices} | {r.uniform_measured:.2e} "
                     f"| {r.vertices / r.uniform_vertices:.2f} | {r.milliseconds / r.uniform_milliseconds:.2f} |")
    ratios = np.array([r.vertices / r.uniform_vertices for r in rows])
    times = np.array([r.milliseconds / r.uniform_milliseconds for r in rows])
    lines += ["", f"Vertices ratio: median {np.median(ratios):.2f}, range {ratios.min():.2f}-{ratios.max():.2f}; "
              f"time ratio: median {np.median(times):.2f}, range {times.min():.2f}-{times.max():.2f} "
              f"({len(rows)} cases)."]
    return "\n".join(lines)


COMPARISON_HEADING = "## Tolerance against the smallest uniform grid"


def write_comparison(path: Path, against: str) -> None:
    """Replace the table of the comparison section of an existing report (--compare-only)."""
    text = path.read_text()
    start = text.index(COMPARISON_HEADING)
    table_start = text.index("| surface | tolerance |", start)
    # The table ends with its summary line; the notes after it stay.
    table_end = text.index("\n", text.index("\nVertices ratio:", table_start) + 1)
    note = ("(This table: `python benchmarks/report_accuracy.py --compare-only --out docs`, every example; "
            "the sections below come from the last full run.)\n\n")
    if "--compare-only" in text[start:table_start]:
        note = ""
    path.write_text(text[:table_start] + note + against + text[table_end:])


def root_finders(small: bool) -> tuple[str, dict]:
    """The sampled-versus-polynomial table (markdown) and its figures, on the fig. 17 scene."""
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from bench_tracer import accuracy_table  # noqa: E402

    counts = (8, 32, 128) if small else (8, 16, 32, 64, 128, 256, 512, 1024)
    width, height = (80, 60) if small else (320, 240)
    figures = accuracy_table(load_scene(EXAMPLES / "traced_fig17_scene.yaml"), width, height, counts)
    lines = [f"Camera rays reaching the surface's bounding sphere at {width} x {height}: {figures['rays']:,}; "
             f"the polynomial finder takes {1e3 * figures['polynomial_seconds']:.0f} ms.", "",
             "| N | ms | missed nearest roots | extra roots | distance median | distance p99 | distance max "
             "| normal p99 (deg) |", "|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in figures["rows"]:
        lines.append(f"| {r['N']} | {1e3 * r['seconds']:.0f} | {r['missed']} | {r['extra']} | {r['dist_median']:.1e} "
                     f"| {r['dist_p99']:.1e} | {r['dist_max']:.1e} | {r['normal_p99']:.4f} |")
    return "\n".join(lines), figures


def plot_root_finders(figures: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = figures["rows"]
    n = [r["N"] for r in rows]
    figure, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
    for key, label in (("dist_median", "median"), ("dist_p99", "p99"), ("dist_max", "max")):
        left.loglog(n, [max(r[key], 1e-16) for r in rows], "o-", label=f"hit distance {label}")
    left.set_xlabel("N (objects per segment)")
    left.set_ylabel("error against the polynomial finder / bounding radius")
    right.loglog(n, [1e3 * r["seconds"] for r in rows], "o-", label="sampled")
    right.axhline(1e3 * figures["polynomial_seconds"], color="k", linestyle="--", label="polynomial")
    right.set_xlabel("N (objects per segment)")
    right.set_ylabel("ms for the rays")
    for axes in (left, right):
        axes.grid(True, which="both", alpha=0.3)
        axes.legend()
    figure.suptitle("sampled root finder against the polynomial one (fig. 17 scene)")
    figure.tight_layout()
    figure.savefig(path, dpi=80)
    plt.close(figure)


def plot(rows: list[Row], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
    for method, marker in (("uniform", "o-"), ("tolerance", "s-")):
        chosen = sorted((r for r in rows if r.method == method), key=lambda r: r.vertices)
        vertices = [r.vertices for r in chosen]
        left.loglog(vertices, [r.deviation for r in chosen], marker, label=method)
        right.loglog(vertices, [r.milliseconds for r in chosen], marker, label=method)
    left.set_xlabel("vertices")
    left.set_ylabel("max deviation / surface size")
    right.set_xlabel("vertices")
    right.set_ylabel("meshing time (ms, incl. measuring for tolerance)")
    for axes in (left, right):
        axes.grid(True, which="both", alpha=0.3)
        axes.legend()
    figure.suptitle(rows[0].example)
    figure.tight_layout()
    figure.savefig(path, dpi=80)
    plt.close(figure)


def table(rows: list[Row]) -> str:
    lines = ["| surface | method | resolution or tolerance | vertices | max deviation / size | ms |",
             "|---|---|---|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r.example} | {r.method} | {r.setting} | {r.vertices} | {r.deviation:.2e} | "
                     f"{r.milliseconds:.1f} |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("docs"))
    parser.add_argument("--small", action="store_true", help="fewer sizes (for CI)")
    parser.add_argument("--examples", default="", help="comma-separated example stems (default: all)")
    parser.add_argument("--compare-only", action="store_true",
                        help="only the table against the smallest uniform grids (printed, nothing written)")
    args = parser.parse_args()
    sizes = (8, 16, 32) if args.small else (8, 16, 32, 64, 128, 256)
    tolerances = (1e-1, 1e-2) if args.small else (1e-1, 3e-2, 1e-2, 3e-3, 1e-3, 3e-4, 1e-4)
    compared = (1e-2,) if args.small else (1e-2, 1e-3, 1e-4)
    chosen = set(filter(None, args.examples.split(",")))
    figures = args.out / "figures"
    figures.mkdir(parents=True, exist_ok=True)

    all_rows, comparisons = [], []
    for path in sorted(EXAMPLES.glob("*.yaml")):
        if chosen and path.stem not in chosen:
            continue
        for spec in load_scene(path).surfaces:
            name = f"{path.stem}/{spec.name}"
            if args.compare_only:
                comparisons.extend(compare_with_uniform(name, spec, compared))
                print(comparison_table(comparisons[-len(compared):]), flush=True)
                continue
            rows = measure_surface(name, spec, sizes, tolerances)
            plot(rows, figures / f"accuracy_{path.stem}_{spec.name}.png")
            all_rows.extend(rows)
            comparisons.extend(compare_with_uniform(name, spec, compared))
            print(comparison_table(comparisons[-len(compared):]), flush=True)
            if args.small:
                break
        if args.small and all_rows:
            break
    if args.compare_only:
        against = comparison_table(comparisons)
        print(against)
        write_comparison(args.out / "accuracy.md", against)
        return
    finders, finder_figures = root_finders(args.small)
    plot_root_finders(finder_figures, figures / "root_finders.png")

    text = table(all_rows)
    against = comparison_table(comparisons)
    (args.out / "accuracy.md").write_text(
        "# Speed against accuracy, measured\n\n"
        "Regenerate with `python benchmarks/report_accuracy.py --out docs`.\n\n"
        "## Tolerance against the smallest uniform grid\n\n"
        "For each surface and tolerance (relative to the surface's size: the radius of the ball its\n"
        "controls fill), the tolerance mesh (`--tolerance`: counts and rings from a priori bounds,\n"
        "docs/tolerance.md) against the smallest uniform grid with the same vertices around (across)\n"
        "and rings evenly spaced in the parameter whose deviation reaches the tolerance, found here by\n"
        "doubling and bisection on its ring count. Bound: the tolerance mesh's a priori bound; measured:\n"
        "cgamesh.meshing.tolerance.deviation's figure (relative). Times are the least of 3 runs, on the\n"
        "process's CPU clock with one BLAS thread, of `pipeline.mesh_surface` from the scene's\n"
        "surface spec, as a user gets each mesh: with `Resolution(tolerance=D)` (building the\n"
        "surface, its checks, planning, meshing) and with `Resolution(around=M, along=K)` (building\n"
        "the surface, its checks, meshing; the same grid, bit for bit, as the one measured); ratios\n"
        "are tolerance mesh / uniform grid.\n\n"
        + against + "\n\n## Tessellation\n\n"
        "Deviation is the largest distance of the mesh from the true surface over triangle interiors\n"
        "(cgamesh.meshing.tolerance.deviation), relative to the surface's size. Uniform grids have n vertices\n"
        "around (n / 4 across a ribbon) and n rings per segment; tolerance meshes are cgamesh's\n"
        "tolerance-driven tessellation (their deviation is measured the same way, after the timing).\n"
        "Plots: `figures/accuracy_<example>_<surface>.png`.\n\n"
        + text + "\n\n## The tracer's root finders\n\n"
        "The paper's sampled finder (N objects per segment, sign changes, local quadratic) against\n"
        "the closed-form polynomial finder, on the fig. 17 scene; errors relative to the surface's\n"
        "bounding radius. Plot: `figures/root_finders.png`.\n\n" + finders + "\n" + BLADE_AGAINST_MOTOR
    )
    print(text)
    print(against)
    print(finders)


# The blade / motor comparison: a figure of its own script (benchmarks/figure_blade_motor.py).
BLADE_AGAINST_MOTOR = """
## Blade against motor interpolation

The same streamline of dipy's `cb_2.npz` (18 samples 2–8 mm apart, tube radius 0.25 mm)
meshed with `interpolation: blade` and `interpolation: motor`, and each ring's radius over the
sample radius: blade rings balloon up to 3.95× between samples (most at the open ends) and pinch
below 1 at two of them; motor rings keep the radius. Regenerate with
`python benchmarks/figure_blade_motor.py`; the bulge, neck and fold statistics of both, and of
pyvista's tubes, over whole tractograms and neurons are `python benchmarks/bench_fidelity.py`
(docs/interpolation.md section 11).

![One streamline both ways](figures/blade_vs_motor.png)
"""


if __name__ == "__main__":
    main()
