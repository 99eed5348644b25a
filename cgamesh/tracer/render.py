"""Whole images: the camera's rays in bands of rows, traced and shaded band by band.

A band holds about BAND_RAYS rays: large enough that the per-object work is vectorised
well, small enough that the intermediate (rays x blades) arrays stay in cache-sized memory
and the progress bar moves.
"""

from __future__ import annotations

import numpy as np

from cgamesh.tracer import shading
from cgamesh.tracer.world import World

BAND_RAYS = 8192


def bands(width: int, height: int) -> list[slice]:
    rows = max(1, BAND_RAYS // max(width, 1))
    return [slice(start, min(start + rows, height)) for start in range(0, height, rows)]


def render(world: World, width: int, height: int, progress=lambda label="": None) -> np.ndarray:
    """The image (height, width, 3) float in [0, 1], top row first; ``progress()`` after each band."""
    image = np.zeros((height, width, 3))
    for band in bands(width, height):
        rays = world.camera.rays(width, height, band)
        image[band] = shading.trace(world, rays).reshape(-1, width, 3)
        progress(f"rows {band.start}-{band.stop - 1}")
    return np.clip(image, 0.0, 1.0)


def band_count(width: int, height: int) -> int:
    return len(bands(width, height))
