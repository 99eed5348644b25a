"""Spheres that close the joints of a tube tree: a branch node's sphere, a neuron's soma.

A chain of tubes starts and ends on circles centred on its end nodes with the nodes' radii;
each such circle lies on the sphere of that radius about the node, so one sphere per branch
node covers every tube end meeting there, with no notch whatever the angles between them.
The spheres are UV spheres with exact normals (the unit radial direction) and u around,
v from pole to pole.

Under a tolerance D each sphere gets the fewest vertices around whose mesh stays within D of
it (``around_within``). Every triangle has its corners on the sphere, so its plane cuts the
sphere in the triangle's circumcircle, of radius rho, at distance sqrt(r^2 - rho^2) from the
centre; every point of the triangle is at least that far from the centre, so within
r - sqrt(r^2 - rho^2) of the sphere. A UV quad is an isosceles trapezoid, which is cyclic: both
its triangles have its circumcircle, one per band of latitude (``deviation_bound``).
"""

from __future__ import annotations

import numpy as np

from cgamesh.meshing.mesh import SurfaceMesh


# The most vertices around a sphere meshed to a tolerance (a sphere of 4,096 around already has
# 8.4 million vertices).
MAX_AROUND = 4096


def sphere_bands(around: int) -> int:
    """Latitude bands of a sphere with ``around`` vertices around: its edges about as long both ways."""
    return max(2, around // 2)


def deviation_bound(around: int) -> float:
    """The largest distance from the unit sphere of any point of its UV mesh with ``around``
    vertices around: max over the bands of 1 - sqrt(1 - rho^2), rho the circumradius of the
    band's first quad (see the module), written rho^2 / (1 + sqrt(1 - rho^2)) to stay exact
    for small rho."""
    bands = sphere_bands(around)
    phi = np.pi * np.arange(bands + 1) / bands
    theta = 2.0 * np.pi / around
    ring = lambda angle: np.stack([np.sin(phi) * np.cos(angle), np.sin(phi) * np.sin(angle),  # noqa: E731
                                   np.cos(phi)], axis=-1)
    first, second = ring(0.0), ring(theta)
    # the triangle (k, 0), (k + 1, 0), (k + 1, 1) of each band: the quad's circumcircle (at a
    # pole, where the quad is that triangle, the triangle's own)
    a, b, c = first[:-1], first[1:], second[1:]
    ab, bc, ca = (np.linalg.norm(x - y, axis=-1) for x, y in ((a, b), (b, c), (c, a)))
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=-1)
    rho_sq = np.minimum((ab * bc * ca / (4.0 * area)) ** 2, 1.0)
    return float(np.max(rho_sq / (1.0 + np.sqrt(1.0 - rho_sq))))


def around_within(radius: float, tolerance: float, limit: int = MAX_AROUND) -> int:
    """The fewest vertices around (at least 4) whose UV sphere of ``radius`` lies within
    ``tolerance`` of the sphere, by ``deviation_bound`` (which falls as ``around`` grows);
    ValueError when more than ``limit`` would be needed."""
    if radius * deviation_bound(4) <= tolerance:
        return 4
    low, high = 4, 8
    while radius * deviation_bound(high) > tolerance:
        if high >= limit:
            raise ValueError(f"a sphere of radius {radius:g} needs more than {limit} vertices around "
                             f"for a tolerance of {tolerance:g}")
        low, high = high, min(2 * high, limit)
    while high - low > 1:  # radius * bound(low) > tolerance >= radius * bound(high)
        middle = (low + high) // 2
        if radius * deviation_bound(middle) <= tolerance:
            high = middle
        else:
            low = middle
    return high


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
