"""Meshes drawn by the tracer's camera and lighting, for ``cgamesh verify --image``.

Each triangle is projected to the image; for every pixel in its bounding box the pixel's ray
is met with the triangle by the co-circular point pairs of section 7.4 (``Facets``), and the
nearest hit per pixel wins. The hit's normal is the vertex normals interpolated with the
hit's barycentric weights (smooth shading, as a viewer would), turned towards the camera,
and it is shaded with the same Blinn-Phong terms as the traced surface (no shadows, no
reflections, so that the two images differ only by geometry and normals).
"""

from __future__ import annotations

import numpy as np

from cgamesh.tracer import cga
from cgamesh.tracer.primitives import Facets
from cgamesh.tracer.shading import local_colour
from cgamesh.tracer.world import World

# Pixel-triangle pairs met per batch (bounds the memory of the intersection arrays).
PAIRS_PER_BATCH = 200_000


def _pairs(pixels: np.ndarray, depth: np.ndarray, faces: np.ndarray, width: int, height: int):
    """(triangle (P,), pixel index (P,)) for every pixel centre in each triangle's bounding box."""
    corners = pixels[faces]  # (F, 3, 2)
    front = np.all(depth[faces] > 0.0, axis=1) & np.all(np.isfinite(corners), axis=(1, 2))
    lo = np.floor(corners.min(axis=1) - 0.5).astype(np.int64)
    hi = np.ceil(corners.max(axis=1) - 0.5).astype(np.int64)
    lo = np.maximum(lo, 0)
    hi[:, 0] = np.minimum(hi[:, 0], width - 1)
    hi[:, 1] = np.minimum(hi[:, 1], height - 1)
    span = np.where(front[:, None], hi - lo + 1, 0).clip(min=0)
    count = span[:, 0] * span[:, 1]
    triangle = np.repeat(np.arange(len(faces)), count)
    start = np.repeat(np.cumsum(count) - count, count)
    k = np.arange(count.sum()) - start
    columns = lo[triangle, 0] + k % np.maximum(span[triangle, 0], 1)
    rows = lo[triangle, 1] + k // np.maximum(span[triangle, 0], 1)
    return triangle, rows * width + columns


def _nearest_hits(rays, positions, normals, faces, pixels, depth, width, height):
    """Per pixel: distance (inf: none), and the interpolated unit normal (P, 3) of one mesh."""
    triangle, pixel = _pairs(pixels, depth, faces, width, height)
    facets = Facets(positions[faces])
    best_t = np.full(width * height, np.inf)
    best_normal = np.zeros((width * height, 3))
    for start in range(0, len(triangle), PAIRS_PER_BATCH):
        tri, pix = triangle[start:start + PAIRS_PER_BATCH], pixel[start:start + PAIRS_PER_BATCH]
        t, weights = facets.intersect_pairs(rays.take(pix), tri, 0.0)
        hit = np.isfinite(t)
        tri, pix, t, weights = tri[hit], pix[hit], t[hit], weights[hit]
        if t.size == 0:
            continue
        order = np.lexsort((t, pix))
        first = order[np.concatenate([[True], pix[order][1:] != pix[order][:-1]])]
        chosen = first[t[first] < best_t[pix[first]]]
        best_t[pix[chosen]] = t[chosen]
        n = np.einsum("nk,nki->ni", weights[chosen], normals[faces[tri[chosen]]])
        best_normal[pix[chosen]] = n / np.linalg.norm(n, axis=1, keepdims=True)
    return best_t, best_normal


def rasterise(world: World, meshes, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """Colours (height, width, 3) of meshes [(positions, normals, faces, PhongMaterial)] and a
    coverage mask (height, width)."""
    camera = world.camera
    rays = camera.rays(width, height)
    best_t = np.full(width * height, np.inf)
    best_normal = np.zeros((width * height, 3))
    best_mesh = np.full(width * height, -1)
    for k, (positions, normals, faces, _) in enumerate(meshes):
        pixels, depth = camera.project(positions, width, height)
        t, n = _nearest_hits(rays, positions, normals, faces, pixels, depth, width, height)
        closer = t < best_t
        best_t[closer], best_normal[closer], best_mesh[closer] = t[closer], n[closer], k
    image = np.tile(world.background, (width * height, 1))
    for k, (_, _, _, material) in enumerate(meshes):
        covered = np.flatnonzero(best_mesh == k)
        if covered.size == 0:
            continue
        sub = rays.take(covered)
        points = sub.at(best_t[covered])
        toward = np.einsum("ni,ni->n", best_normal[covered], sub.directions) > 0.0
        n = best_normal[covered] * np.where(toward, -1.0, 1.0)[:, None]
        count = covered.size
        image[covered] = local_colour(world, sub, best_t[covered], points, cga.line(points, n),
                                      np.broadcast_to(np.asarray(material.color, dtype=np.float64), (count, 3)),
                                      np.full(count, material.ambient), np.full(count, material.diffuse),
                                      np.full(count, material.specular), np.full(count, material.shininess))
    return np.clip(image, 0.0, 1.0).reshape(height, width, 3), (best_mesh >= 0).reshape(height, width)
