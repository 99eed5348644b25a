"""Natural texture coordinates in the (alpha, n) parameter plane.

u runs around each circle (or across a ribbon) in [0, 1]; v runs along the surface in
[0, 1] in proportion to arc length, measured between consecutive rings, so a checker
texture keeps square cells along a tube whose rings are unevenly spaced in alpha.
"""

from __future__ import annotations

import numpy as np


def along_coordinates(ring_samples: np.ndarray) -> np.ndarray:
    """v (K,) from points (K, S, 3) sampled at the same S places on each ring.

    The step between rings is the mean distance the S samples travel; v is the
    running sum of steps, normalised to end at 1.
    """
    steps = np.linalg.norm(np.diff(ring_samples, axis=0), axis=-1).mean(axis=-1)
    travelled = np.concatenate([[0.0], np.cumsum(steps)])
    if travelled[-1] > 0.0:
        return travelled / travelled[-1]
    return np.linspace(0.0, 1.0, len(travelled))


def grid_uvs(v: np.ndarray, columns: int) -> np.ndarray:
    """UVs (K * columns, 2) of a (K, columns) grid: u = j / (columns - 1), v per ring."""
    u = np.linspace(0.0, 1.0, columns)
    return np.stack(np.broadcast_arrays(u[None, :], v[:, None]), axis=-1).reshape(-1, 2)


def disc_uvs(theta: np.ndarray) -> np.ndarray:
    """UVs (M + 1, 2) of a disc: its rim at angles theta (M,), then its centre."""
    rim = np.stack([0.5 + 0.5 * np.cos(theta), 0.5 + 0.5 * np.sin(theta)], axis=1)
    return np.vstack([rim, [[0.5, 0.5]]])
