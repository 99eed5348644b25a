"""Spheres, planes, discs and triangular facets: ray hits by meets, reflections (section 4, 7.4).

Every traceable object answers three questions for a batch of rays:

- ``intersect(rays, t_min) -> Hit``: the nearest hit with t in [t_min, t_max], t = inf where
  there is none (``param`` carries an object-specific parameter, here NaN);
- ``reflect(rays, points, param)``: the reflected rays L' as lines through the hit points,
  correctly oriented (section 4.2); the shading takes the normal line from L' - L;
- ``normals(points, param)``: unit geometric normals (either side), for degenerate reflections.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from cgamesh.geometry.algebra.conformal import N_INF, up
from cgamesh.geometry.objects import circle_from_center_normal_radius, point_pair
from cgamesh.inputs.scene_rendering import PhongMaterial
from cgamesh.tracer import cga
from cgamesh.tracer.rays import Rays

# A ray lies in a disc's plane when |L v C| is below this fraction of |L| |C| (coefficient norms).
IN_PLANE_RTOL = 1e-10
# A disc's edge counts as hit while Y^2 <= EDGE_RTOL |Y|^2 (Y = L v C), i.e. up to rounding.
EDGE_RTOL = 1e-9


@dataclass(frozen=True)
class Hit:
    """t (N,): distance along each ray (inf: no hit); param (N,): object-specific (NaN if unused)."""

    t: np.ndarray
    param: np.ndarray

    @classmethod
    def none(cls, n: int) -> "Hit":
        return cls(np.full(n, np.inf), np.full(n, np.nan))


class Traceable(Protocol):
    material: PhongMaterial

    def intersect(self, rays: Rays, t_min: float) -> Hit: ...

    def reflect(self, rays: Rays, points: np.ndarray, param: np.ndarray) -> np.ndarray: ...

    def normals(self, points: np.ndarray, param: np.ndarray) -> np.ndarray: ...


def nearest_in_range(t: np.ndarray, rays: Rays, t_min: float) -> np.ndarray:
    """Row-wise smallest of candidate distances t (N, K) within [t_min, t_max]; inf if none."""
    valid = (t >= t_min) & (t <= rays.t_max[:, None])
    return np.where(valid, t, np.inf).min(axis=1)


@dataclass(frozen=True)
class Sphere:
    centre: tuple[float, float, float]
    radius: float
    material: PhongMaterial = PhongMaterial()
    blade: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "blade", cga.sphere(np.asarray(self.centre, dtype=np.float64), self.radius))

    def intersect(self, rays: Rays, t_min: float) -> Hit:
        """F = L v S (eq. 3), F^2 >= 0: the points of eq. 5; the nearer one in range."""
        a, b, _ = cga.split_point_pair(cga.meet(rays.lines, self.blade, 3, 4))
        t = np.stack([rays.parameter_of(a), rays.parameter_of(b)], axis=1)
        return Hit(nearest_in_range(t, rays, t_min), np.full(len(rays), np.nan))

    def reflect(self, rays: Rays, points: np.ndarray, param: np.ndarray) -> np.ndarray:
        """L' = Phi_X L Phi_X with the tangent plane Phi_X = (X . S) ^ n_inf (eq. 8)."""
        tangent = cga.outer(cga.inner(up(points), self.blade, (1,), (4,)), N_INF, (3,), (1,))
        return cga.reflect_in_plane(rays.lines, cga.normalise_plane(tangent))

    def normals(self, points: np.ndarray, param: np.ndarray) -> np.ndarray:
        return (points - np.asarray(self.centre)) / self.radius


@dataclass(frozen=True)
class Plane:
    point: tuple[float, float, float]
    normal: tuple[float, float, float]
    material: PhongMaterial = PhongMaterial()
    blade: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "blade", cga.plane(np.asarray(self.point, dtype=np.float64),
                                                    np.asarray(self.normal, dtype=np.float64)))

    def intersect(self, rays: Rays, t_min: float) -> Hit:
        """L v Phi = lambda X ^ n_inf (eq. 4); lambda = 0: parallel, or in the plane (no hit)."""
        meet = cga.meet(rays.lines, self.blade, 3, 4)
        x, lam = cga.plane_point(meet)
        crossing = np.abs(lam) > 1e-12 * np.linalg.norm(meet, axis=-1)
        t = np.where(crossing, rays.parameter_of(np.where(crossing[:, None], x, 0.0)), np.inf)
        return Hit(nearest_in_range(t[:, None], rays, t_min), np.full(len(rays), np.nan))

    def reflect(self, rays: Rays, points: np.ndarray, param: np.ndarray) -> np.ndarray:
        """L' = Phi L Phi (section 4.2)."""
        return cga.reflect_in_plane(rays.lines, self.blade)

    def normals(self, points: np.ndarray, param: np.ndarray) -> np.ndarray:
        n = np.asarray(self.normal, dtype=np.float64)
        return np.broadcast_to(n / np.linalg.norm(n), points.shape)


@dataclass(frozen=True)
class Disc:
    centre: tuple[float, float, float]
    normal: tuple[float, float, float]
    radius: float
    material: PhongMaterial = PhongMaterial()
    blade: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        circle = circle_from_center_normal_radius(np.asarray(self.centre, dtype=np.float64),
                                                  np.asarray(self.normal, dtype=np.float64), self.radius)
        object.__setattr__(self, "blade", circle)

    @property
    def carrier(self) -> np.ndarray:
        """The plane C ^ n_inf of the disc, normalised to Phi^2 = -1."""
        return cga.normalise_plane(cga.outer(self.blade, N_INF, (3,), (1,)))

    def intersect(self, rays: Rays, t_min: float) -> Hit:
        return Hit(disc_hits(rays, self.blade, t_min), np.full(len(rays), np.nan))

    def reflect(self, rays: Rays, points: np.ndarray, param: np.ndarray) -> np.ndarray:
        """L' = (C ^ n_inf) L (C ^ n_inf) (section 4.2)."""
        return cga.reflect_in_plane(rays.lines, self.carrier)

    def normals(self, points: np.ndarray, param: np.ndarray) -> np.ndarray:
        n = np.asarray(self.normal, dtype=np.float64)
        return np.broadcast_to(n / np.linalg.norm(n), points.shape)


def disc_hits(rays: Rays, circle: np.ndarray, t_min: float, edge_rtol: float = EDGE_RTOL) -> np.ndarray:
    """Distances (N,) to the discs bounded by circles (32,) or (N, 32) (section 4.1.3).

    Y = L v C: Y^2 < 0 the ray passes through the disc, Y^2 = 0 through its edge (counted as a
    hit up to edge_rtol), Y^2 > 0 outside; the point is then L v (C ^ n_inf). Y = 0: the ray
    lies in the disc's plane and meets it where it meets the circle: there the circle's
    sphere I5 C (C ^ n_inf) (the sphere of which C is a great circle) and the ray meet in the
    circle's own points, the nearer one in range.
    """
    n = len(rays)
    y = cga.meet(rays.lines, circle, 3, 3)
    size = np.linalg.norm(y, axis=-1)
    in_plane = size <= IN_PLANE_RTOL * np.linalg.norm(rays.lines, axis=-1) * np.linalg.norm(circle, axis=-1)
    inside = ~in_plane & (cga.metric_square(y, 1) <= edge_rtol * size * size)
    t = np.full(n, np.inf)
    if np.any(inside):
        sub = rays.take(inside)
        c = circle if circle.ndim == 1 else circle[inside]
        x, _ = cga.plane_point(cga.meet(sub.lines, cga.outer(c, N_INF, (3,), (1,)), 3, 4))
        t[inside] = nearest_in_range(sub.parameter_of(x)[:, None], sub, t_min)
    if np.any(in_plane):
        sub = rays.take(in_plane)
        c = circle if circle.ndim == 1 else circle[in_plane]
        great_sphere = cga.product(cga.product(cga.I5, c, (5,), (3,), (2,)),
                                          cga.outer(c, N_INF, (3,), (1,)), (2,), (4,), (4,))
        a, b, _ = cga.split_point_pair(cga.meet(sub.lines, great_sphere, 3, 4))
        t[in_plane] = nearest_in_range(np.stack([sub.parameter_of(a), sub.parameter_of(b)], axis=1), sub, t_min)
    return t


@dataclass(frozen=True)
class Facets:
    """Triangles A, B, C (F, 3, 3) traced by co-circular point pairs (section 7.4).

    P1 = A ^ C, P2 = A ^ B, P3 = C ^ B, normalised. A ray L crosses the triangle's plane inside
    it when alpha = P2 v L / (P2 v L - P1 v L) and beta = P3 v L / (P3 v L - P2 v L) are both in
    [0, 1]: the carrier line of alpha P1 + (1 - alpha) P2 (a pencil of lines through A, no
    projection needed for co-circular pairs, section 7.3) sweeps the angle at A, and likewise
    beta the angle at B.
    """

    vertices: np.ndarray
    pairs: np.ndarray = field(init=False, repr=False, compare=False)
    planes: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        v = np.asarray(self.vertices, dtype=np.float64)
        a, b, c = v[:, 0], v[:, 1], v[:, 2]
        pairs = np.stack([point_pair(a, c), point_pair(a, b), point_pair(c, b)], axis=1)  # (F, 3, 32)
        big_a = up(a)
        planes = cga.outer(cga.outer(cga.outer(big_a, up(b), (1,), (1,)), up(c), (2,), (1,)),
                                N_INF, (3,), (1,))
        object.__setattr__(self, "pairs", pairs)
        object.__setattr__(self, "planes", planes)

    def __len__(self) -> int:
        return int(self.vertices.shape[0])

    def intersect_pairs(self, rays: Rays, facet: np.ndarray, t_min: float) -> tuple[np.ndarray, np.ndarray]:
        """For rays (M) paired with facet indices (M,): distances t (M,) (inf: miss) and the
        barycentric weights (M, 3) of the hit point (for interpolating vertex attributes)."""
        pairs = self.pairs[facet]
        meets = cga.meet(rays.lines[:, None, :], pairs, 3, 2)[..., 0]  # (M, 3): P1 v L, P2 v L, P3 v L
        with np.errstate(divide="ignore", invalid="ignore"):
            alpha = meets[:, 1] / (meets[:, 1] - meets[:, 0])
            beta = meets[:, 2] / (meets[:, 2] - meets[:, 1])
        inside = (alpha >= 0.0) & (alpha <= 1.0) & (beta >= 0.0) & (beta <= 1.0)
        x, lam = cga.plane_point(cga.meet(rays.lines, self.planes[facet], 3, 4))
        crossing = inside & (np.abs(lam) > 0.0)
        t = np.where(crossing, rays.parameter_of(np.where(crossing[:, None], x, 0.0)), np.inf)
        t = np.where((t >= t_min) & (t <= rays.t_max), t, np.inf)
        return t, barycentric(self.vertices[facet], np.where(crossing[:, None], x, 0.0))


def barycentric(triangles: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Barycentric weights (M, 3) of points (M, 3) in the planes of triangles (M, 3, 3)."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    normal = np.cross(b - a, c - a)
    area = np.einsum("mi,mi->m", normal, normal)
    area = np.where(area > 0.0, area, 1.0)
    wa = np.einsum("mi,mi->m", np.cross(c - b, points - b), normal) / area
    wb = np.einsum("mi,mi->m", np.cross(a - c, points - c), normal) / area
    return np.stack([wa, wb, 1.0 - wa - wb], axis=1)
