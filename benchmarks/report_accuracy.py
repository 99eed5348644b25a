"""The speed/accuracy trade of tessellation, measured on the example surfaces.

    python benchmarks/report_accuracy.py --out docs [--small]

For every circle surface of the examples it meshes uniform grids of growing size and
tolerance-driven meshes for tolerances from 1e-1 to 1e-4 of the surface's size, and measures
each mesh's largest deviation from the true surface over triangle interiors
(cgamesh.deviation), its vertex count and the time it took. It writes docs/accuracy.md (a
table) and docs/figures/accuracy_<example>.png (deviation and time against vertex count),
and prints the table. --small measures fewer sizes, for CI.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cgamesh.deviation import circle_grid_deviation
from cgamesh.meshing import mesh_circle_surface
from cgamesh.pipeline import build_surface
from cgamesh.scene import load_scene
from cgamesh.tessellation import mesh_to_tolerance

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
        mesh, ms = timed(lambda: mesh_circle_surface(surface, n, t=t, closed=spec.closed))
        grid = mesh.positions.reshape(along, n + 1, 3)
        deviation = circle_grid_deviation(surface, t, grid).max / size
        rows.append(Row(name, "uniform", f"{n} x {along}", mesh.vertex_count, deviation, ms))
    for relative in tolerances:
        mesh, ms = timed(lambda: mesh_to_tolerance(surface, relative * size, closed=spec.closed))
        assert mesh.max_deviation <= relative * size, (name, relative, mesh.max_deviation / size)
        rows.append(Row(name, "tolerance", f"{relative:g}", mesh.vertex_count, mesh.max_deviation / size, ms))
    return rows


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
            if spec.type != "circles":
                continue
            name = f"{path.stem}/{spec.name}"
            rows = measure_surface(name, spec, sizes, tolerances)
            plot(rows, figures / f"accuracy_{path.stem}_{spec.name}.png")
            all_rows.extend(rows)
            if args.small:
                break
        if args.small and all_rows:
            break

    text = table(all_rows)
    (args.out / "accuracy.md").write_text(
        "# Tessellation: accuracy against vertices and time\n\n"
        "Regenerate with `python benchmarks/report_accuracy.py --out docs`. Deviation is the largest\n"
        "distance of the mesh from the true surface over triangle interiors (cgamesh.deviation),\n"
        "relative to the surface's size (the radius of the ball its controls fill). Uniform grids\n"
        "have n vertices around and n rings per segment; tolerance meshes are cgamesh's\n"
        "tolerance-driven tessellation, whose time includes measuring the result.\n\n"
        + text + "\n\nFigures: `figures/accuracy_<example>_<surface>.png`.\n"
    )
    print(text)


if __name__ == "__main__":
    main()
