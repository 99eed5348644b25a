"""Ray tracer speed on the paper's fig. 17 scene, and the sampled finder's accuracy against N.

    python benchmarks/bench_tracer.py [--sizes 320x240,640x480] [--samples 8,16,32,64,128,256,512,1024]

Prints two tables:

1. Rendering examples/traced_fig17_scene.yaml (an evolved surface, a sphere, a ground plane;
   shadows, two reflections) with each root finder at each size: seconds, primary rays per
   second and all rays (primary, shadow, reflected) per second. Target: 640 x 480 with the
   polynomial finder in <= 10 s on 2 cores.
2. The sampled finder (the paper's section 5.1.1 algorithm) against the number N of objects
   per segment, on the camera rays that reach the surface's bounding sphere at the largest
   size, measured against the closed-form polynomial finder in the same run: time, hits it
   misses or invents, and the error of its hit distances (relative to the surface's bounding
   radius) and of its normals. This is the speed/accuracy analysis the paper's section 5.1.3
   left undone.

The script checks what it times (the images are finite and in [0, 1]; the polynomial hits are
roots of the true function; the sampled finder converges to them) and never asserts a time.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from cgamesh.inputs.scene import load_scene
from cgamesh.tracer import shading
from cgamesh.tracer.evolved import RootFinder
from cgamesh.tracer.render import render
from cgamesh.tracer.verify import line_angle
from cgamesh.tracer.world import build_world

SCENE = Path(__file__).resolve().parent.parent / "examples" / "traced_fig17_scene.yaml"
# A sampled hit further than this (relative to the bounding radius) from the polynomial one is another root.
WRONG_ROOT = 1e-2


def size(text: str) -> tuple[int, int]:
    width, height = text.lower().split("x")
    return int(width), int(height)


class RayCounter:
    """Counts the rays the shading traces (nearest hits and shadow tests) while installed."""

    def __init__(self):
        self.count = 0
        self._nearest, self._blocked = shading.nearest, shading.blocked

    def __enter__(self):
        def nearest(world, rays, t_min):
            self.count += len(rays)
            return self._nearest(world, rays, t_min)

        def blocked(world, rays, t_min):
            self.count += len(rays)
            return self._blocked(world, rays, t_min)

        shading.nearest, shading.blocked = nearest, blocked
        return self

    def __exit__(self, *exc):
        shading.nearest, shading.blocked = self._nearest, self._blocked


def render_table(scene, sizes, samples: int) -> dict:
    print(f"fig. 17 scene ({SCENE.name}), {os.cpu_count()} cores")
    print(f"{'size':>9} {'finder':>16} {'seconds':>8} {'primary rays/s':>15} {'all rays':>9} {'all rays/s':>11}")
    images = {}
    for width, height in sizes:
        for finder in (RootFinder("polynomial"), RootFinder("sampled", samples)):
            world = build_world(scene, finder)
            with RayCounter() as counter:
                start = time.perf_counter()
                image = render(world, width, height)
                seconds = time.perf_counter() - start
            assert image.shape == (height, width, 3) and np.all(np.isfinite(image))
            assert image.min() >= 0.0 and image.max() <= 1.0 and image.std() > 0.05
            label = finder.kind if finder.kind == "polynomial" else f"sampled N={finder.samples}"
            images[(width, height, finder.kind)] = image
            print(f"{width:>4}x{height:<4} {label:>16} {seconds:>8.2f} {width * height / seconds:>15,.0f} "
                  f"{counter.count:>9,} {counter.count / seconds:>11,.0f}")
    return images


def accuracy_table(scene, width: int, height: int, counts) -> dict:
    """Print the sampled finder's speed and accuracy against N; return the figures.

    Returns {"rays", "polynomial_seconds", "rows": [{"N", "seconds", "missed", "extra",
    "dist_max", "dist_p99", "dist_median", "normal_max", "normal_p99"}, ...]}.
    """
    world = build_world(scene)
    surface = world.surfaces()[0]
    rays = world.camera.rays(width, height)
    near = np.linalg.norm(np.cross(surface.bound_centre - rays.origins, rays.directions), axis=1) <= surface.bound_radius
    rays = rays.take(near)
    radius = surface.bound_radius
    start = time.perf_counter()
    exact = surface.intersect(rays, 0.0)
    exact_seconds = time.perf_counter() - start
    found = np.isfinite(exact.t)
    points = rays.take(found).at(exact.t[found])
    normals = surface.normals(points, exact.param[found])
    # The polynomial hits are roots of the true function: checked against the objects there.
    residual = surface.roots.residual(surface._local(rays.take(found)).rays.lines,
                                      surface.roots.objects(exact.param[found])[0])
    assert residual.max() < 1e-8, residual.max()
    crossing = np.zeros(len(rays), dtype=bool)
    crossing[found] = np.abs(np.einsum("ni,ni->n", normals, rays.directions[found])) > 1e-2
    print(f"\nsampled finder against N: {len(rays):,} camera rays ({width}x{height}) reaching the surface's "
          f"bounding sphere, {found.sum():,} hits; the polynomial finder takes {exact_seconds:.3f} s "
          f"({len(rays) / exact_seconds:,.0f} rays/s)")
    print("missed: the nearest root (away from grazing, |cos| > 0.01 between ray and normal) not found, so a "
          "later one or none is;\nextra: a hit before the nearest root or where there is none; errors relative "
          "to the bounding radius, over the hits both finders agree on")
    print(f"{'N':>6} {'seconds':>8} {'rays/s':>10} {'missed':>7} {'extra':>6} {'dist max':>9} {'dist p99':>9} "
          f"{'dist median':>11} {'normal max':>10} {'normal p99':>10}")
    errors, rows = [], []
    for n in counts:
        sampled = surface.with_finder(RootFinder("sampled", n))
        start = time.perf_counter()
        rough = sampled.intersect(rays, 0.0)
        seconds = time.perf_counter() - start
        with np.errstate(invalid="ignore"):
            gap = (rough.t - exact.t) / radius  # inf - inf is NaN: neither finder hit
        # A nearest root the sampled finder misses shows as a later hit (or none); one it
        # invents, as an earlier hit (or one where there is none).
        missed = np.count_nonzero(crossing & ~(gap <= WRONG_ROOT))
        extra = np.count_nonzero(~found & np.isfinite(rough.t)) + np.count_nonzero(found & (gap < -WRONG_ROOT))
        both = crossing & (np.abs(gap) <= WRONG_ROOT)
        d = np.abs(gap[both])
        rough_normals = surface.normals(rays.take(both).at(rough.t[both]), rough.param[both])
        angle = line_angle(rough_normals, surface.normals(rays.take(both).at(exact.t[both]), exact.param[both]))
        errors.append((np.median(d), np.percentile(d, 99)))
        rows.append({"N": n, "seconds": seconds, "missed": missed, "extra": extra, "dist_max": float(d.max()),
                     "dist_p99": float(np.percentile(d, 99)), "dist_median": float(np.median(d)),
                     "normal_max": float(angle.max()), "normal_p99": float(np.percentile(angle, 99))})
        print(f"{n:>6} {seconds:>8.3f} {len(rays) / seconds:>10,.0f} {missed:>7} {extra:>6} {d.max():>9.2e} "
              f"{np.percentile(d, 99):>9.2e} {np.median(d):>11.2e} {angle.max():>9.4f}° "
              f"{np.percentile(angle, 99):>9.4f}°")
    # The sampled finder converges to the polynomial one.
    medians = [m for m, _ in errors]
    assert all(later < earlier for earlier, later in zip(medians, medians[1:])), medians
    if max(counts) >= 512:
        assert errors[-1][1] < 1e-4, errors[-1]
    return {"rays": len(rays), "polynomial_seconds": exact_seconds, "rows": rows}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="320x240,640x480")
    parser.add_argument("--samples", default="8,16,32,64,128,256,512,1024",
                        help="objects per segment for the accuracy table")
    parser.add_argument("--render-samples", type=int, default=64, help="N of the sampled finder in the render table")
    args = parser.parse_args()
    sizes = [size(s) for s in args.sizes.split(",")]
    scene = load_scene(SCENE)
    render_table(scene, sizes, args.render_samples)
    accuracy_table(scene, *max(sizes), [int(n) for n in args.samples.split(",")])


if __name__ == "__main__":
    main()
