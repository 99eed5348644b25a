"""The mesh against the ray tracer: how far its vertices are from the traced surface, how far
its normals turn from the traced normals, and whether their signs hold together.

For every vertex x with normal n, the ray from x + s n (s puts the start outside the surface's
bounding sphere) along -n is traced through the analytic surface (and its caps), never the
mesh. Of all its hits the one nearest the vertex is kept; its distance from the vertex
(relative to the radius of the surface's bounding sphere) and the angle between the traced
normal's line and the vertex normal's line are reported (|cos|: the sign of a normal is a
convention, checked apart). Where hits lie equally near, within the distance threshold (a
vertex on a cap's rim, or on a crease at a spline joint, belongs to two sheets), the one whose
normal agrees best is kept. A ray with no hit at all counts as missed.

Signs. The traced normal keeps the raw sign of eq. 25, continuous over the surface except
across a fold (where it passes through zero and reverses). So across every mesh edge whose
two traced normals agree in sign (n_u . n_v > 0: no fold between them), the mesh normals must
keep the same side of them: sign(m_u . n_u) = sign(m_v . n_v). A vertex with a broken edge is
a sign break; a single flipped normal breaks all its edges. For circle surfaces the mesh's
field must also point away from the circles' centres on the whole, as the scene format
requires: sum over surface vertices of m . (x - centre of x's circle) > 0.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cgamesh.errors import InvalidInputError
from cgamesh.geometry.objects import circle_euclidean
from cgamesh.tracer import cga
from cgamesh.tracer.evolved import TracedSurface
from cgamesh.tracer.surface_normals import euclidean_velocity, pair_fractions
from cgamesh.tracer.rays import Rays

# Defaults of the thresholds (cgamesh verify --max-angle / --max-distance / --max-missed).
MAX_ANGLE_DEGREES = 0.1
MAX_DISTANCE = 1e-5
MAX_MISSED = 0.0
# Open edges (a ribbon's sides, a cap's rim, the end objects of an open curve) are widened by
# this many times the distance threshold (relative), so that vertices stored on them with the
# file's rounding still hit them.
EDGE_SLACK_FACTOR = 100.0


@dataclass(frozen=True)
class Thresholds:
    max_angle: float = MAX_ANGLE_DEGREES
    max_distance: float = MAX_DISTANCE
    max_missed: float = MAX_MISSED


@dataclass(frozen=True)
class VertexCheck:
    """Per vertex: distance (relative, NaN if missed), angle (degrees, NaN if missed), the hit's
    parameter, the traced unit normal (raw sign; NaN if missed) and the hit point."""

    distance: np.ndarray
    angle: np.ndarray
    param: np.ndarray
    normal: np.ndarray
    point: np.ndarray

    @property
    def missed(self) -> np.ndarray:
        return np.isnan(self.distance)


@dataclass(frozen=True)
class SurfaceReport:
    name: str
    vertices: int
    missed: float
    distance_max: float
    distance_p99: float
    angle_max: float
    angle_p99: float
    sign_breaks: int
    outward: bool | None
    passed: bool


def line_angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angles in degrees (N,) between the lines of unit vectors a, b (N, 3), in [0, 90]."""
    cross = np.linalg.norm(np.cross(a, b), axis=1)
    return np.degrees(np.arctan2(cross, np.abs(np.einsum("ni,ni->n", a, b))))


def check_vertices(surface: TracedSurface, positions: np.ndarray, normals: np.ndarray,
                   tie: float = MAX_DISTANCE, chunk: int = 16384) -> VertexCheck:
    """Trace the ray through every vertex along its normal and compare (see the module doc).

    ``tie``: hits within this distance (relative to the bounding radius) of the nearest are ties
    (the distance threshold); open edges are widened by EDGE_SLACK_FACTOR times it, and rays
    that pass within about that distance of touching the surface count as touching it.
    Vertices are traced ``chunk`` at a time (bounding the memory of the root finder).
    """
    if len(positions) > chunk:
        parts = [check_vertices(surface, positions[k:k + chunk], normals[k:k + chunk], tie, chunk)
                 for k in range(0, len(positions), chunk)]
        return VertexCheck(*(np.concatenate([getattr(p, name) for p in parts])
                             for name in ("distance", "angle", "param", "normal", "point")))
    count = len(positions)
    centre, radius = surface.bound_centre, surface.bound_radius
    reach = np.linalg.norm(positions - centre, axis=1) + 1.01 * radius
    rays = Rays.from_origin_direction(positions + reach[:, None] * normals, -normals)
    rows, t, param = surface.candidates(rays, -np.inf, EDGE_SLACK_FACTOR * tie, root_rtol=tie)
    gap = np.abs(t - reach[rows])
    nearest = np.full(count, np.inf)
    np.minimum.at(nearest, rows, gap)
    tied = gap <= nearest[rows] + tie * radius
    rows, t, param, gap = rows[tied], t[tied], param[tied], gap[tied]
    # A hit at an interior segment joint belongs to both sheets meeting there; where the
    # analytic normal vanishes there (a spline that stops at its controls), each sheet's
    # one-sided normal is a candidate of its own, and the better one is kept like any tie.
    joint = (np.abs(param - np.round(param)) <= 1e-9) & (param > 0.5) & (param < surface.end - 0.5)
    rows = np.concatenate([rows, rows[joint], rows[joint]])
    t, gap = np.concatenate([t, t[joint], t[joint]]), np.concatenate([gap, gap[joint], gap[joint]])
    sides = np.concatenate([np.zeros(len(param)), np.full(joint.sum(), -1.0), np.full(joint.sum(), 1.0)])
    param = np.concatenate([param, param[joint], param[joint]])
    points = rays.origins[rows] + t[:, None] * rays.directions[rows]
    traced = np.empty(points.shape)
    for side in (0.0, -1.0, 1.0):
        which = sides == side
        traced[which] = surface.normals(points[which], param[which], side)
    angle = line_angle(traced, normals[rows])
    order = np.lexsort((angle, rows))
    first = order[np.concatenate([[True], rows[order][1:] != rows[order][:-1]])]
    out = {"distance": np.full(count, np.nan), "angle": np.full(count, np.nan),
           "param": np.full(count, np.nan), "normal": np.full((count, 3), np.nan),
           "point": np.full((count, 3), np.nan)}
    which = rows[first]
    out["distance"][which] = gap[first] / radius
    out["angle"][which] = angle[first]
    out["param"][which] = param[first]
    out["normal"][which] = traced[first]
    out["point"][which] = points[first]
    return VertexCheck(**out)


# A stored vertex may lie this many times its distance from the surface away from its true
# place along the surface (rounding moves it every way, the ray measures only one).
PLACE_UNCERTAINTY = 4.0
SETTLE_SAMPLES = 65
SETTLE_PASSES = 4
# Vertices whose angle is above this fraction of the threshold, and whose range of t is wider
# than SETTLE_MIN_REACH, are settled (a regular tube's range is ~1e-7: nothing to gain).
SETTLE_FROM = 0.1
SETTLE_MIN_REACH = 1e-6


def settle_angles(surface: TracedSurface, check: VertexCheck, normals: np.ndarray, max_angle: float,
                  chunk: int = 16384) -> VertexCheck:
    """Where a vertex's angle breaks ``max_angle``, compare its normal with the surface's
    normals over the stretch of t its place is uncertain by, and keep the nearest.

    A vertex stored ``d`` off the surface (float32 rounding) could belong anywhere within
    about PLACE_UNCERTAINTY d of the hit along the surface, a range of t of that length over
    the evolution's speed |dx/dt|. On a regular tube that range is ~1e-8 and changes nothing;
    on a sheet that barely moves with t (a rational curve with weights 1e3 and 1e-3 parks its
    middle on one circle, moving 1e-5 of its size per unit of t) the normal turns by tens of
    degrees within it, and no file stored in float32 pins it down more closely.

    At most ``chunk`` normals are evaluated at once (one costs less than a traced ray, which
    ``chunk`` is sized for), so the vertices are settled chunk // SETTLE_SAMPLES at a time.
    """
    candidates = np.flatnonzero((check.angle > SETTLE_FROM * max_angle) & (check.param >= 0.0))
    if candidates.size == 0:
        return check
    gap = check.distance[candidates] * surface.bound_radius
    _, speed = _regularity(surface, check.point[candidates], check.param[candidates])
    with np.errstate(divide="ignore", invalid="ignore"):
        reach = np.where(speed > 0.0, PLACE_UNCERTAINTY * gap / speed, 0.0)
    slow = reach > SETTLE_MIN_REACH  # elsewhere the normal cannot turn measurably within reach
    candidates, reach = candidates[slow], reach[slow]
    if candidates.size == 0:
        return check
    out = {name: getattr(check, name).copy() for name in ("distance", "angle", "param", "normal", "point")}
    step = max(1, chunk // SETTLE_SAMPLES)
    for k in range(0, candidates.size, step):
        part = candidates[k:k + step]
        out["param"][part], out["normal"][part], out["angle"][part] = _settle(surface, check, normals, part,
                                                                               reach[k:k + step])
    return VertexCheck(**out)


def _settle(surface: TracedSurface, check: VertexCheck, normals: np.ndarray, candidates: np.ndarray,
            reach: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``settle_angles`` for some vertices: their best (t, traced normal, angle) within reach."""
    point, param = check.point[candidates], check.param[candidates]
    low = np.maximum(param - reach, np.maximum(np.floor(param - JOINT_TOLERANCE), 0.0))
    high = np.minimum(param + reach, np.minimum(np.ceil(param + JOINT_TOLERANCE), surface.end))
    steps = np.linspace(0.0, 1.0, SETTLE_SAMPLES)
    best_t, best_normal, best_angle = param.copy(), check.normal[candidates].copy(), check.angle[candidates].copy()
    for _ in range(SETTLE_PASSES):  # a grid over the range, then finer ones around its best sample
        t = low[:, None] + (high - low)[:, None] * steps[None, :]
        count = t.shape[1]
        traced = surface.normals(np.repeat(point, count, axis=0), t.ravel())
        angle = line_angle(traced, np.repeat(normals[candidates], count, axis=0)).reshape(-1, count)
        k = np.argmin(angle, axis=1)
        rows = np.arange(len(candidates))
        better = angle[rows, k] < best_angle
        best_angle = np.where(better, angle[rows, k], best_angle)
        best_t = np.where(better, t[rows, k], best_t)
        best_normal = np.where(better[:, None], traced.reshape(-1, count, 3)[rows, k], best_normal)
        spacing = (high - low) / (SETTLE_SAMPLES - 1)
        low, high = np.maximum(best_t - spacing, low), np.minimum(best_t + spacing, high)
    return best_t, best_normal, best_angle


def sign_breaks(check: VertexCheck, normals: np.ndarray, faces: np.ndarray, surface: TracedSurface | None = None,
                positions: np.ndarray | None = None, tie: float = MAX_DISTANCE, chunk: int = 16384) -> np.ndarray:
    """Vertices (bool (V,)) with a mesh edge across which the traced field keeps its sign but
    the mesh normal changes sides of it.

    Two traced normals less than 90 degrees apart need not mean the field kept its sign
    between them, nor does every edge have a side to keep. So with ``surface`` and
    ``positions``, an edge that looks broken is traced again at EDGE_SAMPLES points along it
    and stays broken only where (``_judged``) all of them and its ends lie on the surface
    itself (not a cap), on one curve segment (across a joint the tangent plane may turn: a
    crease, with no continuity to follow), on a regular sheet (the circle's tangent and the
    velocity X . (C dC/dt) at least REGULAR_SINE apart, the extremes tests' own measure; near a
    pinch the field turns through a right angle within a degree and a coarse ring cannot tell
    which way), sweeping at least the distance threshold per unit of t (a band between
    controls 1e-9 apart is narrower than what verify resolves), and the field keeps its sign
    from each point to the next. Normal lines there are still judged by angle.
    """
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    u, v = edges[:, 0], edges[:, 1]
    traced = check.normal
    side = np.sign(np.einsum("vi,vi->v", normals, traced))
    continuous = np.einsum("ei,ei->e", traced[u], traced[v]) > 0.0  # NaN (missed) compares False
    broken = continuous & (side[u] * side[v] < 0.0)
    if surface is not None and positions is not None and np.any(broken):
        broken[broken] = _judged(surface, check, positions, normals, u[broken], v[broken], tie, chunk)
    out = np.zeros(len(normals), dtype=bool)
    out[u[broken]] = True
    out[v[broken]] = True
    return out


EDGE_SAMPLES = 7
REGULAR_SINE = 1e-3
# Parameters this close to a segment joint belong to both segments.
JOINT_TOLERANCE = 1e-9


def _judged(surface: TracedSurface, check: VertexCheck, positions: np.ndarray, normals: np.ndarray,
            u: np.ndarray, v: np.ndarray, tie: float, chunk: int = 16384) -> np.ndarray:
    """Which edges (u, v) keep a side along them (see ``sign_breaks``)."""
    s = (np.arange(1, EDGE_SAMPLES + 1) / (EDGE_SAMPLES + 1.0))[None, :, None]
    points = (1.0 - s) * positions[u][:, None] + s * positions[v][:, None]
    directions = (1.0 - s) * normals[u][:, None] + s * normals[v][:, None]
    directions /= np.linalg.norm(directions, axis=2, keepdims=True)
    inner = check_vertices(surface, points.reshape(-1, 3), directions.reshape(-1, 3), tie, chunk)
    count = len(u)

    def chain(ends: np.ndarray, between: np.ndarray) -> np.ndarray:
        between = between.reshape(count, EDGE_SAMPLES, *ends.shape[1:])
        return np.concatenate([ends[u][:, None], between, ends[v][:, None]], axis=1)

    param = chain(check.param, inner.param)
    hit = chain(check.point, inner.point)
    traced = chain(check.normal, inner.normal)
    last = surface.surface.segment_count - 1
    first_segment = np.clip(np.floor(param - JOINT_TOLERANCE), 0, last)  # at a joint k: k - 1 and k
    last_segment = np.clip(np.floor(param + JOINT_TOLERANCE), 0, last)
    one_segment = first_segment.max(axis=1) <= last_segment.min(axis=1)
    on_surface = np.all(param >= 0.0, axis=1)  # NaN (missed) compares False
    sine, speed = _regularity(surface, hit.reshape(-1, 3), param.ravel())
    regular = np.all(sine.reshape(count, -1) >= REGULAR_SINE, axis=1)
    wide = np.all(speed.reshape(count, -1) >= tie * surface.bound_radius, axis=1)
    keeps_sign = np.all(np.einsum("eki,eki->ek", traced[:, 1:], traced[:, :-1]) > 0.0, axis=1)
    return on_surface & one_segment & regular & wide & keeps_sign


def _regularity(surface: TracedSurface, points: np.ndarray, param: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """At surface points (K, 3) of parameters (K,): the sine between the object's direction
    (the circle's tangent, the pair's ruling) and the velocity along t, and the speed |dx/dt|
    in world units; both 0 off the surface. The velocity is X . (C dC/dt) (eq. 20) for
    circles and (1 - s) a' + s b' for point pairs (``surface_normals``)."""
    sine, speed = np.zeros(len(points)), np.zeros(len(points))
    on = np.isfinite(param) & (param >= 0.0)
    if not np.any(on):
        return sine, speed
    projection = surface.surface.sample(param[on])
    g = surface.grade
    omega = cga.product(projection.blades, projection.derivatives, (g,), (g,), (2,))
    x = surface.frame.to_local(points[on])
    if g == 3:
        centre, normal, _ = circle_euclidean(projection.blades)
        direction = np.cross(normal, x - centre)
        velocity = euclidean_velocity(x, omega)
    else:
        a, b, f = pair_fractions(projection.blades, x)
        direction = b - a
        velocity = (1.0 - f)[:, None] * euclidean_velocity(a, omega) + f[:, None] * euclidean_velocity(b, omega)
    size = np.linalg.norm(velocity, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        sines = np.linalg.norm(np.cross(direction, velocity), axis=1) / (np.linalg.norm(direction, axis=1) * size)
    sine[on] = np.nan_to_num(sines)
    speed[on] = size * surface.frame.scale
    return sine, speed


def outward(surface: TracedSurface, check: VertexCheck, normals: np.ndarray) -> bool | None:
    """Circle surfaces: whether sum m . (x - centre of x's circle) > 0 over the traced vertices
    on the surface itself (not on caps); None for point pairs or when no vertex qualifies."""
    on = np.flatnonzero(np.isfinite(check.param) & (check.param >= 0.0))
    if surface.grade != 3 or on.size == 0:
        return None
    centres, _, _ = circle_euclidean(surface.surface.sample(check.param[on]).blades)
    centres = surface.frame.to_world(centres)
    return bool(np.einsum("vi,vi->", normals[on], check.point[on] - centres) > 0.0)


def summarise(name: str, check: VertexCheck, breaks: np.ndarray | None = None, facing: bool | None = None,
              thresholds: Thresholds = Thresholds()) -> SurfaceReport:
    count = len(check.distance)
    missed = float(np.mean(check.missed)) if count else 0.0
    found = ~check.missed
    if np.any(found):
        d, a = check.distance[found], check.angle[found]
        stats = (float(d.max()), float(np.percentile(d, 99)), float(a.max()), float(np.percentile(a, 99)))
    else:
        stats = (np.nan,) * 4
    broken = int(np.count_nonzero(breaks)) if breaks is not None else 0
    passed = (missed <= thresholds.max_missed and np.any(found) and stats[0] <= thresholds.max_distance
              and stats[2] <= thresholds.max_angle and broken == 0 and facing is not False)
    return SurfaceReport(name, count, missed, *stats, broken, facing, bool(passed))


def check_mesh(surface: TracedSurface, mesh, thresholds: Thresholds = Thresholds(), chunk: int = 16384) -> SurfaceReport:
    """The whole check of one mesh (MeshData or SurfaceMesh: positions, normals, faces); its
    vertices (and the edge samples and settling of ``sign_breaks`` and ``settle_angles``)
    traced ``chunk`` at a time."""
    check = check_vertices(surface, mesh.positions, mesh.normals, thresholds.max_distance, chunk)
    check = settle_angles(surface, check, mesh.normals, thresholds.max_angle, chunk)
    breaks = sign_breaks(check, mesh.normals, np.asarray(mesh.faces), surface, mesh.positions,
                         thresholds.max_distance, chunk)
    return summarise(surface.name, check, breaks, outward(surface, check, mesh.normals), thresholds)


def format_reports(reports: list[SurfaceReport], thresholds: Thresholds = Thresholds()) -> str:
    """A table: one row per surface, then the thresholds."""
    header = (f"{'surface':<20} {'vertices':>8} {'missed':>7} {'dist max':>9} {'dist p99':>9} "
              f"{'angle max':>10} {'angle p99':>10} {'sign breaks':>11} {'outward':>7}  result")
    lines = [header, "-" * len(header)]
    for r in reports:
        facing = {None: "-", True: "yes", False: "NO"}[r.outward]
        lines.append(f"{r.name[:20]:<20} {r.vertices:>8} {100 * r.missed:>6.2f}% {r.distance_max:>9.2e} "
                     f"{r.distance_p99:>9.2e} {r.angle_max:>9.4f}° {r.angle_p99:>9.4f}° {r.sign_breaks:>11} "
                     f"{facing:>7}  {'pass' if r.passed else 'FAIL'}")
    lines.append(f"thresholds: distance <= {thresholds.max_distance:g} of the bounding radius, normal angle <= "
                 f"{thresholds.max_angle:g}°, missed <= {100 * thresholds.max_missed:g}%, no sign breaks, "
                 "circle surfaces outward")
    return "\n".join(lines)


def verify_meshes(world_surfaces: list[TracedSurface], meshes, thresholds: Thresholds = Thresholds(),
                  progress=lambda label="": None, max_memory=None) -> list[SurfaceReport]:
    """A report per traced surface, with the mesh of the same name (MeshData) checked against it.

    Raises InvalidInputError when a surface has no mesh of its name in the file. The vertices
    are traced in chunks that fit ``max_memory`` (cgamesh.budget); ResourceLimitError when not
    even one ray fits, or a surface's polynomials are past the tracer's limit.
    """
    from cgamesh.budget import Budget
    from cgamesh.tracer.ray_budget import rays_at_once

    chunk = rays_at_once(world_surfaces, Budget.of(max_memory), "verify", 16384)
    by_name = {mesh.name: mesh for mesh in meshes}
    reports = []
    for surface in world_surfaces:
        mesh = by_name.get(surface.name)
        if mesh is None:
            raise InvalidInputError(f"the mesh file has no mesh named {surface.name!r} (it has "
                                    f"{', '.join(sorted(by_name)) or 'none'})")
        reports.append(check_mesh(surface, mesh, thresholds, chunk))
        progress(surface.name)
    return reports


def comparison_image(world, meshes, width: int, height: int, max_memory=None) -> np.ndarray:
    """[traced | mesh | 4 x |difference|] side by side (height, 3 width, 3), for ``verify --image``.

    ``world``: the scene's surfaces only, without shadows or reflections (both halves are
    shaded alike; the mesh half by ``raster``); ``meshes``: MeshData in the world's surface order.
    """
    from cgamesh.tracer.raster import rasterise
    from cgamesh.tracer.render import render

    traced = render(world, width, height, max_memory=max_memory)
    materials = {s.name: s.material for s in world.surfaces()}
    drawn, _ = rasterise(world, [(m.positions, m.normals, m.faces, materials[m.name]) for m in meshes
                                 if m.name in materials], width, height)
    difference = np.clip(4.0 * np.abs(traced - drawn), 0.0, 1.0)
    return np.concatenate([traced, drawn, difference], axis=1)
