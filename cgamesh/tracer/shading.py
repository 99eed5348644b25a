"""Blinn-Phong shading with shadows and recursive reflections (paper section 9, eqs. 34-36).

For a ray L hitting an object at X, with L' the reflected ray (section 4.2) and all lines
normalised (L^2 = 1), the normal line is N = (L' - L) / |L' - L|, which faces the side the
ray came from. Per light i, L_i = X ^ P_i ^ n_inf (normalised) runs from X to the light and
H = (L_i - L) / |L_i - L| is the half-way line (L points towards X, so -L is the paper's V,
the line to the viewer). Inner products of these lines, all through X, are the cosines of
the angles between them, and for each colour channel

    I = c k_a + k_r I_r + sum_i S_i f I_p,i (c k_d (L_i . N) + k_s (N . H)^q)      (eq. 34)

with the cosines clamped at 0 (a light behind the surface adds nothing), f = 1 / (a + b d +
c d^2) for the distance d from the ray's origin to X (section 9.2.1), and S_i = 0 when the
shadow ray towards light i hits an object before the light (S_i = 1 otherwise; the paper's
shadow attenuation constant is 0 here). I_r is the colour seen along L', traced the same way
up to the scene's ``max_depth`` reflections; a ray that hits nothing sees the background.
The recursion is unrolled: each depth traces all reflected rays of the previous one as one
batch, weighted by the product of the reflectivities on their way.
"""

from __future__ import annotations

import numpy as np

from cgamesh.geometry.algebra.conformal import up
from cgamesh.tracer import cga
from cgamesh.tracer.evolved import TracedSurface
from cgamesh.tracer.primitives import Hit
from cgamesh.tracer.rays import Rays
from cgamesh.tracer.world import World

SHADOW_ATTENUATION = 0.0
# |L' - L| below this (of 2) is a ray grazing its object: the geometric normal is used.
GRAZING = 1e-9


def _cheap_first(objects) -> list[int]:
    """Object indices, primitives before evolved surfaces (whose root finding costs most)."""
    return sorted(range(len(objects)), key=lambda k: isinstance(objects[k], TracedSurface))


def nearest(world: World, rays: Rays, t_min: float) -> tuple[np.ndarray, Hit]:
    """Index (N,) of the object each ray hits first (-1: none) and that hit.

    Cheap objects go first, and each object after them only looks up to the nearest hit so
    far: a ray that meets a plane in front of a surface's bounding sphere skips the surface.
    """
    best = Hit.none(len(rays))
    index = np.full(len(rays), -1)
    for k in _cheap_first(world.objects):
        limited = Rays(rays.lines, rays.origins, rays.directions, np.minimum(rays.t_max, best.t))
        hit = world.objects[k].intersect(limited, t_min)
        closer = hit.t < best.t
        best.t[closer] = hit.t[closer]
        best.param[closer] = hit.param[closer]
        index[closer] = k
    return index, best


def blocked(world: World, rays: Rays, t_min: float) -> np.ndarray:
    """Whether each ray meets any object between t_min and its t_max (N,) bool."""
    out = np.zeros(len(rays), dtype=bool)
    for k in _cheap_first(world.objects):
        open_ = np.flatnonzero(~out)
        if open_.size == 0:
            break
        out[open_] = np.isfinite(world.objects[k].intersect(rays.take(open_), t_min).t)
    return out


def _material_arrays(world: World, index: np.ndarray):
    """Per-hit colour (n, 3) and k_a, k_d, k_s, q, k_r (n,) from the objects' materials."""
    table = [obj.material for obj in world.objects]
    color = np.array([m.color for m in table])[index]
    scalars = np.array([[m.ambient, m.diffuse, m.specular, m.shininess, m.reflectivity] for m in table])[index]
    return color, scalars.T


def surface_lines(world: World, rays: Rays, index: np.ndarray, hit: Hit) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Hit points (n, 3), reflected lines L' (n, 32) and normal lines N (n, 32) for rays that hit."""
    points = rays.at(hit.t)
    reflected = np.zeros_like(rays.lines)
    geometric = np.zeros_like(points)
    for k, obj in enumerate(world.objects):
        mine = np.flatnonzero(index == k)
        if mine.size:
            sub = rays.take(mine)
            reflected[mine] = obj.reflect(sub, points[mine], hit.param[mine])
            geometric[mine] = obj.normals(points[mine], hit.param[mine])
    reflected = cga.normalise_line(reflected)
    difference = reflected - rays.lines
    size = np.sqrt(np.maximum(cga.square(difference, 3), 0.0))
    normal_lines = difference / np.where(size > 0.0, size, 1.0)[:, None]
    grazing = ~(size > GRAZING)
    if np.any(grazing):
        toward = np.einsum("ni,ni->n", geometric[grazing], rays.directions[grazing]) > 0.0
        facing = geometric[grazing] * np.where(toward, -1.0, 1.0)[:, None]
        normal_lines[grazing] = cga.line(points[grazing], facing)
    return points, reflected, normal_lines


def local_colour(world: World, rays: Rays, t: np.ndarray, points: np.ndarray, normal_lines: np.ndarray,
                 color: np.ndarray, ambient, diffuse, specular, shininess) -> np.ndarray:
    """The ambient, diffuse and specular terms of eq. 34 (n, 3), with depth attenuation and shadows."""
    total = color * ambient[:, None]
    a, b, c = world.attenuation.a, world.attenuation.b, world.attenuation.c
    attenuation = 1.0 / (a + b * t + c * t * t)
    x = up(points)
    for light in world.lights:
        to_light = cga.normalise_line(cga.line_through(x, up(light.position)))
        cos_light = np.maximum(cga.scalar_product(normal_lines, to_light, 3), 0.0)
        lit = np.flatnonzero(cos_light > 0.0)
        if lit.size == 0:
            continue
        shade = 1.0
        if world.shadows:
            distance = np.linalg.norm(light.position - points[lit], axis=1)
            shadow_rays = Rays.from_lines(to_light[lit], points[lit], distance)
            shade = np.where(blocked(world, shadow_rays, world.epsilon), SHADOW_ATTENUATION, 1.0)
        half = cga.normalise_line(to_light[lit] - rays.lines[lit])
        cos_half = np.maximum(cga.scalar_product(normal_lines[lit], half, 3), 0.0)
        terms = (color[lit] * (diffuse[lit] * cos_light[lit])[:, None]
                 + (specular[lit] * cos_half ** shininess[lit])[:, None])
        total[lit] += (shade * attenuation[lit])[:, None] * light.intensity[None, :] * terms
    return total


def trace(world: World, rays: Rays) -> np.ndarray:
    """Colours (N, 3) (not clipped) seen along the rays."""
    colours = np.zeros((len(rays), 3))
    owner = np.arange(len(rays))
    weight = np.ones(len(rays))
    t_min = 0.0
    for depth in range(world.max_depth + 1):
        index, hit = nearest(world, rays, t_min)
        missed = index < 0
        colours[owner[missed]] += weight[missed, None] * world.background[None, :]
        struck = np.flatnonzero(~missed)
        if struck.size == 0:
            break
        rays, index, owner, weight = rays.take(struck), index[struck], owner[struck], weight[struck]
        hit = Hit(hit.t[struck], hit.param[struck])
        points, reflected, normal_lines = surface_lines(world, rays, index, hit)
        color, (k_a, k_d, k_s, q, k_r) = _material_arrays(world, index)
        local = local_colour(world, rays, hit.t, points, normal_lines, color, k_a, k_d, k_s, q)
        colours[owner] += weight[:, None] * local
        mirror = np.flatnonzero(k_r > 0.0)
        if depth == world.max_depth or mirror.size == 0:
            break
        rays = Rays.from_lines(reflected[mirror], points[mirror])
        owner, weight = owner[mirror], weight[mirror] * k_r[mirror]
        t_min = world.epsilon
    return colours
