"""Whole images: the camera's rays in bands of rows, traced and shaded band by band.

A band holds about BAND_RAYS rays: large enough that the per-object work is vectorised
well, small enough that the intermediate (rays x blades) arrays stay in cache-sized memory
and the progress bar moves. Under a memory budget (cgamesh.budget) a band holds no more rays
than fit it (a surface of a high-order curve needs megabytes per ray), and a row too wide for
it is traced in pieces. ``render_png`` streams the bands into the PNG file, so no image of
the whole size is ever held: any size works within the budget.
"""

from __future__ import annotations

import os

import numpy as np

from cgamesh.budget import Budget
from cgamesh.tracer import shading
from cgamesh.tracer.ray_budget import PIXEL_BYTES, rays_at_once
from cgamesh.tracer.world import World

BAND_RAYS = 8192


def bands(width: int, height: int, rays: int = BAND_RAYS) -> list[slice]:
    rows = max(1, rays // max(width, 1))
    return [slice(start, min(start + rows, height)) for start in range(0, height, rows)]


def plan(world: World, width: int, height: int, max_memory=None) -> tuple[list[slice], int]:
    """(bands of rows, rays traced at once) for this image within the budget."""
    at_once = rays_at_once(world.surfaces(), Budget.of(max_memory), f"render {width}x{height}", BAND_RAYS)
    return bands(width, height, at_once), at_once


def render_bands(world: World, width: int, height: int, progress=lambda label="": None, max_memory=None):
    """Yield (rows slice, colours (rows, width, 3) in [0, 1]) band by band, top first."""
    band_list, at_once = plan(world, width, height, max_memory)
    for band in band_list:
        rays = world.camera.rays(width, height, band)
        if len(rays) <= at_once:
            colours = shading.trace(world, rays)
        else:
            colours = np.concatenate([shading.trace(world, rays.take(np.arange(k, min(k + at_once, len(rays)))))
                                      for k in range(0, len(rays), at_once)])
        yield band, np.clip(colours.reshape(-1, width, 3), 0.0, 1.0)
        progress(f"rows {band.start}-{band.stop - 1}")


def render(world: World, width: int, height: int, progress=lambda label="": None, max_memory=None) -> np.ndarray:
    """The image (height, width, 3) float in [0, 1], top row first; ``progress()`` after each band.

    The whole image is held (float64): ResourceLimitError when it does not fit the budget
    (``render_png`` streams instead)."""
    Budget.of(max_memory).require(width * height * PIXEL_BYTES, f"an image of {width}x{height}", "pixels in memory")
    image = np.zeros((height, width, 3))
    for band, colours in render_bands(world, width, height, progress, max_memory):
        image[band] = colours
    return image


def render_png(world: World, width: int, height: int, path: str | os.PathLike, progress=lambda label="": None,
               max_memory=None) -> int:
    """Render straight into a PNG file at ``path`` (written atomically), band by band; its size."""
    from cgamesh.tracer.png import PngStream

    with PngStream(path, width, height) as png:
        for _, colours in render_bands(world, width, height, progress, max_memory):
            png.add_rows(colours)
    return png.size


def band_count(width: int, height: int, world: World | None = None, max_memory=None) -> int:
    if world is None:
        return len(bands(width, height))
    return len(plan(world, width, height, max_memory)[0])
