"""Evolved surfaces of circles and point pairs as traceable objects (paper sections 5.1, 7.1, 7.2).

``TracedSurface`` works in the surface's local frame (the ray enters it as the line through its
point nearest the frame's origin, which keeps the conformal coefficients small), skips the
rays that miss the bounding spheres (``bounds``: the whole surface's, then pieces of each
segment), finds the roots per segment (``roots``), turns them into hit points, and supplies
the normals (``surface_normals``) and reflected rays the shading needs. A tube meshed with caps
is traced with them, as discs.

The hit point of a circle root is L v (C ^ n_inf) (eq. 4). When the ray crosses the circle's
plane at a small angle that point is ill-conditioned, and when the ray lies in the plane
(L v C = 0, a double root) it does not exist; then the hit is where the ray meets the
circle's great sphere I5 C (C ^ n_inf) (eq. 5; in the plane both points are hits). The hit
point of a point-pair root is where the ray meets the pair's carrier line P ^ n_inf (their
closest approach, from the end points of eq. 5), kept when it lies between the end points
(the paper's test against the sphere through the pair, section 7.2, in Euclidean form).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cgamesh.geometry.algebra.conformal import N_INF
from cgamesh.geometry.objects import circle_euclidean, point_pair_endpoints
from cgamesh.geometry.surface import EvolvedSurface
from cgamesh.tracer import bounds, cga, surface_normals
from cgamesh.tracer.primitives import EDGE_RTOL, Disc, Hit, PhongMaterial, disc_hits
from cgamesh.tracer.rays import Rays
from cgamesh.tracer.roots import FINDERS, ROOT_RTOL, RootFinder, SurfaceRoots  # noqa: F401 (re-exported)

# Objects per segment whose spheres make the segment's bounding spheres, and pieces per segment.
BOUND_SAMPLES = 32
BOUND_PIECES = 4
# |cos| between a ray and a circle's plane normal below which the ray lies in the plane.
IN_PLANE_COS = 1e-6
# Below this |cos| the hit point comes from the circle's great sphere instead of its plane.
OBLIQUE_COS = 0.1
# End points of a pair: a carrier-line hit within this fraction past an end still counts.
SEGMENT_SLACK = 1e-9
START_CAP, END_CAP = -1.0, -2.0


@dataclass(frozen=True)
class _LocalRays:
    """Rays in the surface's frame: lines through ``base`` (the point nearest the frame's
    origin), unit directions; a local distance u from base is the world distance
    scale * (u - shift) from the ray's origin."""

    rays: Rays
    shift: np.ndarray


class TracedSurface:
    """An evolved surface as a traceable object, with its caps when the mesh has them."""

    def __init__(self, surface: EvolvedSurface, material: PhongMaterial = PhongMaterial(),
                 caps: bool = False, finder: RootFinder = RootFinder()):
        self.surface = surface
        self.material = material
        self.finder = finder
        self.grade = surface.grade
        self.frame = surface.frame
        self.end = float(surface.segment_count)
        self.roots = SurfaceRoots(surface)
        self.segment_bounds = [self._segment_bound(k) for k in range(surface.segment_count)]
        self._piece_centres = np.array([c for pieces in self.segment_bounds for c, _ in pieces])
        self._piece_radii = np.array([r for pieces in self.segment_bounds for _, r in pieces])
        self._piece_segment = np.repeat(np.arange(surface.segment_count), BOUND_PIECES)
        centre, radius = bounds.dual_centre_radius(bounds.enclose(cga.dual_sphere(self._piece_centres, self._piece_radii)))
        self._local_bound = (centre, float(radius))
        self.bound_centre = self.frame.to_world(centre)
        self.bound_radius = float(radius) * self.frame.scale
        self.caps = self._caps() if caps else ()

    @property
    def name(self) -> str:
        return self.surface.name

    def with_finder(self, finder: RootFinder) -> "TracedSurface":
        """The same surface traced with another root finder (prepared data is shared)."""
        other = object.__new__(TracedSurface)
        other.__dict__.update(self.__dict__)
        other.finder = finder
        return other

    # --- preparation -----------------------------------------------------------------------------

    def _segment_bound(self, segment: int) -> list[tuple[np.ndarray, float]]:
        """Local centres (3,) and radii of BOUND_PIECES spheres that together enclose the segment.

        Each encloses the spheres of its samples (section 5.1.1), grown by the most any point
        moves between neighbouring samples; several per segment hug a bent tube more closely
        than one, so fewer rays need the root finder.
        """
        t = segment + np.linspace(0.0, 1.0, BOUND_SAMPLES + 1)
        blades = self.surface.sample(t).blades
        duals = bounds.object_duals(blades, self.grade)
        if self.grade == 3:
            c, n, r = circle_euclidean(blades)
            # How far any point moves between neighbouring samples (local units), at most.
            step = (np.linalg.norm(np.diff(c, axis=0), axis=1) + np.abs(np.diff(r))
                    + np.maximum(r[1:], r[:-1]) * np.linalg.norm(np.diff(n, axis=0), axis=1))
        else:
            a, b = point_pair_endpoints(blades)
            step = np.maximum(np.linalg.norm(np.diff(a, axis=0), axis=1), np.linalg.norm(np.diff(b, axis=0), axis=1))
        pieces = []
        per_piece = BOUND_SAMPLES // BOUND_PIECES
        for k in range(BOUND_PIECES):
            chunk = slice(k * per_piece, (k + 1) * per_piece + 1)
            centre, radius = bounds.dual_centre_radius(bounds.enclose(duals[chunk]))
            pieces.append((centre, float(radius) + float(step[chunk][:-1].max() if per_piece > 0 else 0.0)))
        return pieces

    def _caps(self) -> tuple[Disc, Disc]:
        blades = self.surface.sample(np.array([0.0, self.end])).blades
        centre, normal, radius = circle_euclidean(blades)
        centre = self.frame.to_world(centre)
        return tuple(Disc(tuple(centre[k]), tuple(normal[k]), float(radius[k] * self.frame.scale), self.material)
                     for k in range(2))

    def polynomial_degree(self, segment: int) -> int:
        """Degree of the intersection polynomial solved on a segment (after the known roots of W-
        are divided out): 8 for linear circles, 4 for linear point pairs (see the module doc)."""
        return self.roots.polynomial_degree(segment)

    def known_roots(self, segment: int) -> np.ndarray:
        """Parameters t in [segment, segment + 1] where W- vanishes for every ray (divided out)."""
        return self.roots.known_roots(segment)

    # --- rays ----------------------------------------------------------------------------------

    def _local(self, rays: Rays) -> _LocalRays:
        o = self.frame.to_local(rays.origins)
        d = rays.directions
        shift = np.einsum("ni,ni->n", o, d)
        base = o - shift[:, None] * d
        local_max = rays.t_max / self.frame.scale + shift
        return _LocalRays(Rays(cga.line(base, d), base, d, local_max), shift)

    def _points(self, local: _LocalRays, rows: np.ndarray, t: np.ndarray, objects: np.ndarray,
                slack: float = SEGMENT_SLACK):
        """Local distances u (R',) from the rays' base points, with their rows and parameters.

        ``objects``: the circles or point pairs at t, any positive scale. ``slack``: how far
        past a segment's end (as a fraction of its length) a point pair's hit still counts.
        """
        lines = local.rays.lines[rows]
        base, d = local.rays.origins[rows], local.rays.directions[rows]
        if self.grade == 2:
            a, b = point_pair_endpoints(objects)
            e = b - a
            w0 = base - a
            de, ee = np.einsum("ri,ri->r", d, e), np.einsum("ri,ri->r", e, e)
            dw, ew = np.einsum("ri,ri->r", d, w0), np.einsum("ri,ri->r", e, w0)
            denominator = ee - de * de
            with np.errstate(divide="ignore", invalid="ignore"):
                u = (de * ew - ee * dw) / denominator
                s = (ew - de * dw) / denominator
            ok = (denominator > 1e-14 * ee) & (s >= -slack) & (s <= 1.0 + slack)
            return rows[ok], u[ok], t[ok]
        carrier = cga.normalise_plane(cga.outer(objects, N_INF, (3,), (1,)))
        x, lam = cga.plane_point(cga.meet(lines, carrier, 3, 4))
        steep = np.abs(lam) >= OBLIQUE_COS
        u = np.einsum("ri,ri->r", np.where(steep[:, None], x, 0.0) - base, d)
        out_rows, out_u, out_t = [rows[steep]], [u[steep]], [t[steep]]
        if not np.all(steep):
            # A ray at a small angle to the circle's plane: the plane point moves by the root's
            # error over that angle; the great sphere's points (met at a large angle) do not.
            flat = ~steep
            c = objects[flat]
            great = cga.product(cga.product(cga.I5, c, (5,), (3,), (2,)),
                                       cga.outer(c, N_INF, (3,), (1,)), (2,), (4,), (4,))
            pa, pb, f2 = cga.split_point_pair(cga.meet(lines[flat], great, 3, 4))
            in_plane = ~(np.abs(lam[flat]) > IN_PLANE_COS)
            a_nearer = np.linalg.norm(pa - x[flat], axis=1) <= np.linalg.norm(pb - x[flat], axis=1)
            for p, keep in ((pa, in_plane | a_nearer), (pb, in_plane | ~a_nearer)):
                ok = (f2 >= 0.0) & keep
                out_rows.append(rows[flat][ok])
                out_u.append(np.einsum("ri,ri->r", p[ok] - base[flat][ok], d[flat][ok]))
                out_t.append(t[flat][ok])
        return np.concatenate(out_rows), np.concatenate(out_u), np.concatenate(out_t)

    def candidates(self, rays: Rays, t_min: float = -np.inf, edge_slack: float = 0.0,
                   root_rtol: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every hit of every ray: (row (R,), world distance (R,), parameter (R,)).

        The parameter is t in [0, segment_count] on the surface, START_CAP / END_CAP on a cap.
        Rays reach from t_min to their t_max. ``edge_slack`` (relative) widens the edges of
        the sheets (a ribbon's sides, a cap's rim, the end objects of every segment) so that
        points stored on them with rounding still hit: a ray passing that close to a segment's
        end object also hits it there. ``root_rtol`` (default ROOT_RTOL) is the largest
        relative residual of an accepted polynomial root; larger values also accept rays that
        pass that close to touching the surface (where it folds, a ray along the normal only
        touches it, and rounding can make it miss by a hair).
        """
        rtol = ROOT_RTOL[self.grade] if root_rtol is None else max(root_rtol, ROOT_RTOL[self.grade])
        local = self._local(rays)
        scale = self.frame.scale
        out_rows, out_t, out_param = [], [], []
        reach_min = t_min / scale + local.shift if np.isfinite(t_min) else np.full(len(rays), -np.inf)
        # The sphere around the whole surface first (by the meet), then the pieces of each segment.
        inside = np.flatnonzero(bounds.meets_sphere(local.rays, self._local_bound[0], self._local_bound[1]))
        enter, leave = bounds.spans(local.rays.take(inside), self._piece_centres, self._piece_radii)
        near_piece = (leave >= reach_min[inside, None]) & (enter <= local.rays.t_max[inside, None])
        for segment in range(len(self.segment_bounds)):
            rows = inside[np.any(near_piece[:, self._piece_segment == segment], axis=1)]
            if rows.size == 0:
                continue
            which, t, objects = self.roots.roots(local.rays.lines[rows], segment, self.finder, rtol)
            cand_rows = rows[which]
            if edge_slack > 0.0:
                # A point stored with rounding on a segment's end circle (the surface's open end,
                # or a crease at a joint) may miss its sheet, which ends there, by a hair.
                for end in (float(segment), segment + 1.0):
                    plus, _ = self.roots.objects(np.full(rows.size, end))
                    close = self.roots.residual(local.rays.lines[rows], plus) <= edge_slack
                    cand_rows = np.concatenate([cand_rows, rows[close]])
                    t = np.concatenate([t, np.full(close.sum(), end)])
                    objects = np.concatenate([objects, plus[close]])
            if cand_rows.size == 0:
                continue
            cand_rows, u, t = self._points(local, cand_rows, t, objects, SEGMENT_SLACK + edge_slack)
            out_rows.append(cand_rows)
            out_t.append(scale * (u - local.shift[cand_rows]))
            out_param.append(t)
        for cap, label in zip(self.caps, (START_CAP, END_CAP)):
            t = disc_hits(rays, cap.blade, t_min, EDGE_RTOL + edge_slack)
            hit = np.flatnonzero(np.isfinite(t))
            out_rows.append(hit)
            out_t.append(t[hit])
            out_param.append(np.full(hit.size, label))
        if not out_rows:
            return np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0)
        return np.concatenate(out_rows), np.concatenate(out_t), np.concatenate(out_param)

    def intersect(self, rays: Rays, t_min: float) -> Hit:
        rows, t, param = self.candidates(rays, t_min)
        ok = (t >= t_min) & (t <= rays.t_max[rows])
        return _nearest(len(rays), rows[ok], t[ok], param[ok])

    # --- normals and reflections -----------------------------------------------------------------

    def normals(self, points: np.ndarray, param: np.ndarray, side: float = 0.0) -> np.ndarray:
        """Analytic unit normals (either side) at world points (K, 3) with parameters (K,).

        Where the analytic normal vanishes (a fold or pinch of the surface, or a joint where
        the curve stops) the numerical one is used, from central differences or, with
        ``side`` -1 / +1, one-sided ones from below / above; on a cap, the cap's normal.
        """
        out = np.zeros(points.shape)
        surface = param >= 0.0
        if np.any(surface):
            out[surface] = self._analytic(points[surface], param[surface])
            zero = surface & ~(np.linalg.norm(out, axis=1) > 0.5)
            if np.any(zero):
                out[zero] = self.numerical_normals(points[zero], param[zero], side)
        for cap, label in zip(self.caps, (START_CAP, END_CAP)):
            on = param == label
            out[on] = cap.normals(points[on], param[on])
        return out

    def _analytic(self, points: np.ndarray, t: np.ndarray) -> np.ndarray:
        projection = self.surface.sample(t)
        local = self.frame.to_local(points)
        if self.grade == 3:
            return surface_normals.circle_normals(projection.blades, projection.derivatives, local)
        return surface_normals.pair_normals(projection.blades, projection.derivatives, local)

    def numerical_normals(self, points: np.ndarray, t: np.ndarray, side: float = 0.0) -> np.ndarray:
        """The second opinion: normals from the neighbouring objects (see ``surface_normals``)."""
        return surface_normals.numerical_normals(self.surface.sample, self.grade, t,
                                                 self.frame.to_local(points), self.end, side)

    def reflect(self, rays: Rays, points: np.ndarray, param: np.ndarray) -> np.ndarray:
        """L' = -N L N with N the normalised normal line through the hit (a half turn about N
        is the reflection in the tangent plane, reversed)."""
        normal_lines = cga.line(points, self.normals(points, param))
        turned = cga.product(cga.product(normal_lines, rays.lines, (3,), (3,), (0, 2, 4)),
                                    normal_lines, (0, 2, 4), (3,), (3,))
        return -turned


def _nearest(count: int, rows: np.ndarray, t: np.ndarray, param: np.ndarray) -> Hit:
    """Per row the smallest t among candidates (rows, t, param); inf / NaN where none."""
    hit = Hit.none(count)
    if rows.size == 0:
        return hit
    order = np.lexsort((t, rows))
    rows, t, param = rows[order], t[order], param[order]
    first = np.concatenate([[True], rows[1:] != rows[:-1]])
    hit.t[rows[first]] = t[first]
    hit.param[rows[first]] = param[first]
    return hit
