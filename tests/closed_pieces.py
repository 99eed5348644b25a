"""Closed pieces with exact normals for the watertight union's tests and benchmark: capped cone
frusta (tubes) and latitude-longitude spheres, as SurfaceMeshes in the meshers' conventions
(repeated seam vertices, counter-clockwise seen from outside), and a random dendritic arbor of
them."""

from __future__ import annotations

import dataclasses

import numpy as np

from cgamesh.meshing.colors import segment_colors
from cgamesh.meshing.mesh import SurfaceMesh


def sphere(name: str, centre, radius: float, rings: int = 12, columns: int = 16) -> SurfaceMesh:
    """A latitude-longitude sphere with exact outward normals, one vertex per pole and the seam
    column repeated (u = 0 and u = 1), wound counter-clockwise seen from outside."""
    centre = np.asarray(centre, dtype=np.float64)
    polar = np.linspace(0.0, np.pi, rings + 1)[1:-1]
    azimuth = np.linspace(0.0, 2.0 * np.pi, columns + 1)
    p, a = np.meshgrid(polar, azimuth, indexing="ij")  # (rings - 1, columns + 1)
    unit = np.stack([np.sin(p) * np.cos(a), np.sin(p) * np.sin(a), np.cos(p)], axis=-1).reshape(-1, 3)
    unit[columns::columns + 1] = unit[0::columns + 1]  # the seam repeats its first column bit for bit
    unit = np.concatenate([[[0.0, 0.0, 1.0]], unit, [[0.0, 0.0, -1.0]]])
    uv = np.stack([a / (2.0 * np.pi), 1.0 - p / np.pi], axis=-1).reshape(-1, 2)
    uv = np.concatenate([[[0.5, 1.0]], uv, [[0.5, 0.0]]])
    width = columns + 1
    grid = 1 + np.arange(rings - 1)[:, None] * width + np.arange(width)[None, :]
    a0, b0 = grid[:-1, :-1].ravel(), grid[1:, :-1].ravel()
    a1, b1 = grid[:-1, 1:].ravel(), grid[1:, 1:].ravel()
    south = len(unit) - 1
    faces = np.concatenate([
        np.stack([np.zeros(columns, np.int64), grid[0, :-1], grid[0, 1:]], 1),  # north cap
        np.stack([a0, b0, b1], 1), np.stack([a0, b1, a1], 1),
        np.stack([np.full(columns, south), grid[-1, 1:], grid[-1, :-1]], 1),  # south cap
    ]).astype(np.int32)
    return SurfaceMesh(name, centre + radius * unit, unit, uv, faces)


def frustum(name: str, start, end, r0: float, r1: float, around: int = 12, along: int = 6) -> SurfaceMesh:
    """A capped cone frustum from ``start`` (radius r0) to ``end`` (r1) with exact normals: the
    side's seam column repeated, each cap a fan around its centre with the rim repeated (its own
    flat normal), wound counter-clockwise seen from outside."""
    start, end = np.asarray(start, float), np.asarray(end, float)
    axis = end - start
    length = np.linalg.norm(axis)
    axis /= length
    e1 = np.cross(axis, [1.0, 0.0, 0.0] if abs(axis[0]) < 0.9 else [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    s = np.linspace(0.0, 1.0, along + 1)
    # each ring turned half a step from the previous (as in most tube meshers): a straight tube's
    # quads would otherwise form flat strips, whose coplanar neighbours MeshLab's
    # self-intersection test misreads as crossing
    theta = np.linspace(0.0, 2.0 * np.pi, around + 1)[None, :] + (np.pi / around) * np.arange(along + 1)[:, None]
    radial = np.cos(theta)[..., None] * e1 + np.sin(theta)[..., None] * e2  # (along + 1, around + 1, 3)
    radial[:, -1] = radial[:, 0]
    radius = r0 + (r1 - r0) * s
    side = start + s[:, None, None] * (end - start) + radius[:, None, None] * radial
    slope = (r1 - r0) / length
    normal = (radial - slope * axis) / np.hypot(1.0, slope)
    positions = [side.reshape(-1, 3)]
    normals = [normal.reshape(-1, 3)]
    u, v = np.meshgrid(np.linspace(0.0, 1.0, around + 1), s)
    uvs = [np.stack([u, v], -1).reshape(-1, 2)]
    w = around + 1
    a = (np.arange(along)[:, None] * w + np.arange(around)).ravel()
    faces = [np.stack([a, a + 1, a + w + 1], 1), np.stack([a, a + w + 1, a + w], 1)]
    count = side.shape[0] * w
    for centre, r, n, ring in ((start, r0, -axis, 0), (end, r1, axis, along)):
        rim = side[ring, :around]
        positions += [centre[None], rim]
        normals += [np.broadcast_to(n, (around + 1, 3))]
        uvs += [np.full((around + 1, 2), 0.5)]
        k = np.arange(around)
        fan = np.stack([np.full(around, count), count + 1 + k, count + 1 + (k + 1) % around], 1)
        faces.append(fan if n @ axis > 0 else fan[:, ::-1])
        count += around + 1
    return SurfaceMesh(name, np.concatenate(positions), np.concatenate(normals), np.concatenate(uvs),
                       np.concatenate(faces).astype(np.int32))


def arbor(segments: int, around: int, rings: int, rng: np.random.Generator):
    """Pieces of a random dendritic tree: tubes with radius and segment attributes and colours,
    junction spheres at branch points, the soma."""
    soma_radius = 6.0
    nodes = [np.zeros(3)]
    headings = [np.zeros(3)]  # the direction of the segment ending at each node
    radii = [1.5]
    children = [0]
    pieces = []
    for k in range(segments):
        parent = 0 if k < 4 else int(rng.integers(1, len(nodes)))
        start = nodes[parent]
        direction = headings[parent] + 0.9 * rng.normal(size=3)  # from the soma: any direction
        direction /= np.linalg.norm(direction)
        r0 = radii[parent] if parent else 1.5
        r1 = max(0.2, r0 * rng.uniform(0.75, 0.95))
        length = rng.uniform(4.0, 20.0) + (soma_radius if parent == 0 else 0.0)
        end = start + length * direction
        pieces.append(frustum(f"tube{k}", start, end, r0, r1, around=around, along=rings))
        nodes.append(end)
        headings.append(direction)
        radii.append(r1)
        children.append(0)
        children[parent] += 1
    for node, (point, radius, count) in enumerate(zip(nodes, radii, children)):
        if node > 0 and count >= 1:
            pieces.append(sphere(f"j{node}", point, radius, rings=max(4, around // 2 + 1), columns=around))
    pieces.append(sphere("soma", np.zeros(3), soma_radius, rings=16, columns=24))
    out = []
    for k, piece in enumerate(pieces):
        ids = np.full(piece.vertex_count, float(k))
        distance = np.linalg.norm(piece.positions, axis=1)
        out.append(dataclasses.replace(piece, colors=segment_colors(ids),
                                       attributes={"segment": ids, "radius": distance}))
    return out
