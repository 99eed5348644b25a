"""Closed capped cone frusta between consecutive nodes of a polyline: the watertight union's
fallback for a chain whose tube folds over itself (a radius large against its bend).

A frustum is the convex hull of its two end circles, so it is a closed, consistently wound
solid for any radii and any length (no bend inside it can fold it), and a node sphere at every
interior node (``enclosing_sphere_scale``) fills the wedge between two frusta meeting at an
angle. The pieces overlap, so the union of them is one closed surface along the chain.
"""

from __future__ import annotations

import numpy as np

from cgamesh.meshing.junctions import uv_spheres
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.meshing.weld import weld_by_position


def enclosing_sphere_scale(around: int) -> float:
    """The factor by which a UV sphere's radius must grow so that its polygonal mesh strictly
    encloses the true ball of the node's radius.

    A UV sphere's vertices lie on the ball, its flat triangles inside it; the ring a tube
    starts or ends with at that node also has its vertices on the ball, so with the plain
    radius the ring's edges would touch or cross the sphere's facets exactly where several
    tubes share that ring (identical positions the union keeps apart, which a weld then makes
    non-manifold). Scaled by this factor every facet plane is farther from the centre than the
    radius (by a relative 1e-6), so such rings lie strictly inside the sphere and are cut away.
    """
    unit = uv_spheres(np.zeros((1, 3)), np.ones(1), around)
    corners = unit.positions[unit.faces]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    length = np.linalg.norm(normal, axis=1)
    valid = length > 1e-12
    distance = np.abs(np.einsum("ij,ij->i", normal[valid], corners[valid, 0])) / length[valid]
    return float((1.0 + 1e-6) / distance.min())


def frusta(points: np.ndarray, radii: np.ndarray, around: int, name: str) -> list[SurfaceMesh]:
    """One closed capped frustum per consecutive pair of ``points`` (n, 3) with ``radii`` (n,),
    counter-clockwise seen from outside, analytic cone normals and flat cap normals. UVs: u
    around, v 0 at the first end and 1 at the second."""
    pieces = []
    theta = 2.0 * np.pi * np.arange(around + 1) / around
    cos, sin = np.cos(theta), np.sin(theta)
    cos[-1], sin[-1] = cos[0], sin[0]  # the seam repeats column 0 bit for bit
    for k in range(len(points) - 1):
        a, b = points[k], points[k + 1]
        ra, rb = float(radii[k]), float(radii[k + 1])
        axis = b - a
        length = float(np.linalg.norm(axis))
        d = axis / length
        u = np.cross(d, [1.0, 0.0, 0.0] if abs(d[0]) < 0.9 else [0.0, 1.0, 0.0])
        u /= np.linalg.norm(u)
        v = np.cross(d, u)  # u, v, d right-handed: theta turns counter-clockwise about d
        radial = cos[:, None] * u + sin[:, None] * v
        ring_a, ring_b = a + ra * radial, b + rb * radial
        side = radial + d * ((ra - rb) / length)
        side /= np.linalg.norm(side, axis=1, keepdims=True)
        columns = around + 1
        positions = np.concatenate([ring_a, ring_b, [a], ring_a, [b], ring_b])
        normals = np.concatenate([side, side, np.broadcast_to(-d, (columns + 1, 3)),
                                  np.broadcast_to(d, (columns + 1, 3))])
        s = np.arange(columns) / around
        uvs = np.concatenate([np.stack([s, np.zeros(columns)], 1), np.stack([s, np.ones(columns)], 1),
                              [[0.5, 0.0]], np.stack([s, np.zeros(columns)], 1),
                              [[0.5, 1.0]], np.stack([s, np.ones(columns)], 1)])
        i = np.arange(around)
        ia, ib = i, columns + i
        ca, cb = 2 * columns, 3 * columns + 1
        faces = np.concatenate([
            np.stack([ia, ia + 1, ib + 1], 1), np.stack([ia, ib + 1, ib], 1),
            np.stack([np.full(around, ca), ca + 1 + i + 1, ca + 1 + i], 1),
            np.stack([np.full(around, cb), cb + 1 + i, cb + 1 + i + 1], 1)])
        pieces.append(SurfaceMesh(name=f"{name}_{k}", positions=positions, normals=normals.copy(), uvs=uvs,
                                  faces=faces.astype(np.int32), weld=weld_by_position(positions)))
    return pieces


def node_spheres(points: np.ndarray, radii: np.ndarray, around: int, name: str) -> SurfaceMesh:
    """Spheres enclosing the balls at ``points`` (see ``enclosing_sphere_scale``)."""
    return uv_spheres(points, radii * enclosing_sphere_scale(around), around, name=name)


__all__ = ["enclosing_sphere_scale", "frusta", "node_spheres"]
