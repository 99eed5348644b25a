"""Spheres that close the joints of a tube tree: a branch node's sphere, a neuron's soma.

A chain of tubes starts and ends on circles centred on its end nodes with the nodes' radii;
each such circle lies on the sphere of that radius about the node, so one sphere per branch
node covers every tube end meeting there, with no notch whatever the angles between them.
The spheres are UV spheres with exact normals (the unit radial direction) and u around,
v from pole to pole.
"""

from __future__ import annotations

import numpy as np

from cgamesh.meshing.mesh import SurfaceMesh


def sphere_bands(around: int) -> int:
    """Latitude bands of a sphere with ``around`` vertices around: its edges about as long both ways."""
    return max(2, around // 2)


def uv_spheres(centres: np.ndarray, radii: np.ndarray, around: int, name: str = "spheres") -> SurfaceMesh:
    """Closed UV spheres (one mesh of S of them: centres (S, 3), radii (S,)), each welded closed.

    Each sphere has (around + 1) * (bands + 1) vertices (seam column and pole rows repeated,
    bit-identical, so ``weld`` closes it) and 2 * around * (bands - 1) triangles, counter-
    clockwise seen from outside.
    """
    centres = np.asarray(centres, dtype=np.float64).reshape(-1, 3)
    radii = np.asarray(radii, dtype=np.float64).reshape(-1)
    bands = sphere_bands(around)
    theta = 2.0 * np.pi * np.arange(around + 1) / around
    phi = np.pi * np.arange(bands + 1) / bands
    unit = np.stack([np.sin(phi)[:, None] * np.cos(theta)[None, :],
                     np.sin(phi)[:, None] * np.sin(theta)[None, :],
                     np.broadcast_to(np.cos(phi)[:, None], (bands + 1, around + 1))], axis=-1)
    unit[:, -1] = unit[:, 0]  # the seam repeats column 0 bit for bit
    unit[0] = (0.0, 0.0, 1.0)  # the poles exactly
    unit[-1] = (0.0, 0.0, -1.0)
    unit = unit.reshape(-1, 3)
    per_sphere = len(unit)
    positions = (centres[:, None, :] + radii[:, None, None] * unit[None]).reshape(-1, 3)
    normals = np.broadcast_to(unit, (len(centres), per_sphere, 3)).reshape(-1, 3).copy()
    u, v = np.meshgrid(np.arange(around + 1) / around, np.arange(bands + 1) / bands)
    uvs = np.tile(np.stack([u.ravel(), v.ravel()], axis=1), (len(centres), 1))
    faces = _sphere_faces(around, bands)
    faces = (faces[None] + (per_sphere * np.arange(len(centres)))[:, None, None]).reshape(-1, 3)
    weld = _sphere_weld(around, bands)
    weld = (weld[None] + (per_sphere * np.arange(len(centres)))[:, None]).reshape(-1)
    index = np.int32 if len(positions) < 2**31 else np.int64
    return SurfaceMesh(name=name, positions=positions, normals=normals, uvs=uvs, faces=faces.astype(index),
                       weld=weld.astype(index))


def _sphere_faces(around: int, bands: int) -> np.ndarray:
    """Triangles of one sphere's grid; at the poles, one triangle per quad (the other has no area)."""
    columns = around + 1
    k, j = np.meshgrid(np.arange(bands), np.arange(around), indexing="ij")
    a = k * columns + j
    b, c, d = a + columns, a + columns + 1, a + 1
    # (a, b, c) runs along phi then theta: d/dphi x d/dtheta points outward.
    lower = np.stack([a, b, c], axis=-1)[:-1 if bands > 1 else None]
    upper = np.stack([a, c, d], axis=-1)[1:]
    if bands == 1:
        return np.zeros((0, 3), dtype=np.int64)
    return np.concatenate([lower.reshape(-1, 3), upper.reshape(-1, 3)])


def _sphere_weld(around: int, bands: int) -> np.ndarray:
    columns = around + 1
    grid = np.arange((bands + 1) * columns).reshape(bands + 1, columns)
    grid[:, -1] = grid[:, 0]
    grid[0] = 0
    grid[-1] = bands * columns
    return grid.ravel()
