"""The baseline every mesher benchmark is measured against: a plain numpy tube.

A circle of fixed radius swept along a straight line, with exact normals, UVs and grid
triangles, in float32 — what any tube tool does at the very least, with no conformal algebra.
"""

from __future__ import annotations

import numpy as np


def euclidean_tube(around: int, along: int, radius: float = 1.0, length: float = 4.0):
    """(positions, normals, uvs, faces) of a straight tube: along x (around + 1) vertices."""
    theta = np.linspace(0.0, 2.0 * np.pi, around + 1, dtype=np.float32)
    cos, sin = np.cos(theta), np.sin(theta)
    z = np.linspace(0.0, length, along, dtype=np.float32)
    positions = np.empty((along, around + 1, 3), dtype=np.float32)
    positions[..., 0] = radius * cos
    positions[..., 1] = radius * sin
    positions[..., 2] = z[:, None]
    normals = np.empty_like(positions)
    normals[..., 0] = cos
    normals[..., 1] = sin
    normals[..., 2] = 0.0
    uvs = np.empty((along, around + 1, 2), dtype=np.float32)
    uvs[..., 0] = np.linspace(0.0, 1.0, around + 1, dtype=np.float32)
    uvs[..., 1] = np.linspace(0.0, 1.0, along, dtype=np.float32)[:, None]
    columns = around + 1
    corner = np.arange(along - 1, dtype=np.int32)[:, None] * columns + np.arange(around, dtype=np.int32)
    faces = np.empty((along - 1, around, 2, 3), dtype=np.int32)
    faces[..., 0, 0] = corner
    faces[..., 0, 1] = corner + 1
    faces[..., 0, 2] = corner + columns
    faces[..., 1, 0] = corner + 1
    faces[..., 1, 1] = corner + columns + 1
    faces[..., 1, 2] = corner + columns
    return positions.reshape(-1, 3), normals.reshape(-1, 3), uvs.reshape(-1, 2), faces.reshape(-1, 3)
