"""The speed/accuracy trades cgamesh offers, measured: tessellation, and the tracer's root finders.

    python benchmarks/report_accuracy.py --out docs [--small]

1. For every surface of the examples (circles and point pairs) it meshes uniform grids of
   growing size and tolerance-driven meshes for tolerances from 1e-1 to 1e-4 of the surface's
   size, and measures each mesh's largest deviation from the true surface over triangle
   interiors (cgamesh.meshing.deviation), its vertex count and the time it took.
2. On the fig. 17 scene it measures the tracer's sampled root finder against the number N of
   objects per segment (hit-distance and normal errors, time) against the polynomial finder
   (benchmarks/bench_tracer.py's analysis).

It writes docs/accuracy.md (the tables), docs/figures/accuracy_<example>_<surface>.png
(deviation and time against vertex count) and docs/figures/root_finders.png, and prints the
tables. --small measures fewer sizes and one example, for CI.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cgamesh.meshing.deviation import CIRCLES, SEGMENTS, grid_deviation
from cgamesh.meshing.circles import mesh_circle_surface
from cgamesh.pipeline import Resolution, build_surface, mesh_surface
from cgamesh.meshing.ribbons import mesh_ribbon_surface
from cgamesh.inputs.scene import load_scene

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
        rows.append(Row(name, "tolerance", f"{relative:g}", mesh.vertex_count, mesh.max_deviation / size, ms))
    return rows


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
    args = parser.parse_args()
    sizes = (8, 16, 32) if args.small else (8, 16, 32, 64, 128, 256)
    tolerances = (1e-1, 1e-2) if args.small else (1e-1, 3e-2, 1e-2, 3e-3, 1e-3, 3e-4, 1e-4)
    figures = args.out / "figures"
    figures.mkdir(parents=True, exist_ok=True)

    all_rows = []
    for path in sorted(EXAMPLES.glob("*.yaml")):
        for spec in load_scene(path).surfaces:
            name = f"{path.stem}/{spec.name}"
            rows = measure_surface(name, spec, sizes, tolerances)
            plot(rows, figures / f"accuracy_{path.stem}_{spec.name}.png")
            all_rows.extend(rows)
            if args.small:
                break
        if args.small and all_rows:
            break
    finders, finder_figures = root_finders(args.small)
    plot_root_finders(finder_figures, figures / "root_finders.png")

    text = table(all_rows)
    (args.out / "accuracy.md").write_text(
        "# Speed against accuracy, measured\n\n"
        "Regenerate with `python benchmarks/report_accuracy.py --out docs`.\n\n"
        "## Tessellation\n\n"
        "Deviation is the largest distance of the mesh from the true surface over triangle interiors\n"
        "(cgamesh.meshing.deviation), relative to the surface's size (the radius of the ball its controls\n"
        "fill). Uniform grids have n vertices around (n / 4 across a ribbon) and n rings per segment;\n"
        "tolerance meshes are cgamesh's tolerance-driven tessellation, whose time includes measuring\n"
        "the result. Plots: `figures/accuracy_<example>_<surface>.png`.\n\n"
        + text + "\n\n## The tracer's root finders\n\n"
        "The paper's sampled finder (N objects per segment, sign changes, local quadratic) against\n"
        "the closed-form polynomial finder, on the fig. 17 scene; errors relative to the surface's\n"
        "bounding radius. Plot: `figures/root_finders.png`.\n\n" + finders + "\n"
    )
    print(text)
    print(finders)

if __name__ == "__main__":
    main()
