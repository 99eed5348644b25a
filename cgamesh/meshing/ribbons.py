"""Meshing evolved point-pair surfaces (ribbons) by TRS-rotor stepping (paper sections 7 and 11).

README: a ribbon's normal at x = a + s (b - a) points to the side of (b - a) x dx/dt (at mid-width
(b - a) x d((a + b)/2)/dt), where a, b are the end points of the interpolated point pair in the
order of paper eq. 5 (u = 0 on the a edge) and t runs from the first control to the last; where
the ribbon folds back over itself the field stays continuous instead, and the formula then holds
at most vertices. Ribbons are exported double-sided.

Ring k is the segment between the end points a_k, b_k of P(t_k) (eq. 5), with N vertices at the
fractions s_j = j / (N - 1). The TRS rotor from P(t_k) to P(t_{k+1}) (section 11: translation
a_k -> a_{k+1}, the smallest rotation between the directions d_k = b_k - a_k and d_{k+1},
dilation by |d_{k+1}| / |d_k|) carries x_kj to x_{k+1,j}, so the composed rotors place

    x_kj = a_k + s_j (b_k - a_k),

which is Z X ~Z evaluated as the similarity it is (a segment has no phase to carry, unlike a
circle: its end points fix it). End points are read from P(t_k) at every ring, so no error
accumulates; all conformal work is per ring, and each vertex is a row of one matrix product.

Normals. The ribbon is the ruled surface x(s, t) = a + s d, so its normal is

    N = d x dx/dt = (1 - s) N_a + s N_b,    N_a = d x a',  N_b = d x b',

with the end-point velocities exact from X' = X . Omega, Omega = P dP/dt (eqs. 19-20: for point
pairs too P^2 = 1 and P ^ P = 0 make Omega a bivector and keep X on P) and dP/dt the closed-form
derivative of the projection (section 6). (Not the line P ^ n_inf of section 7.2: that normal is
exact only at the edges.) N is linear in s, so N_a and N_b describe a whole ruling.

Continuity. N vanishes where the ruling and the velocity are parallel. Along a ruling N runs on
a straight line, so it can reverse at most once, and only where that line passes near zero.
Around an isolated zero (a pinch point) the raw field is the continuous one; along a fold curve
(a ribbon folding back over itself, e.g. the flat chords of fig. 12 crossing their neighbours)
it reverses, and its sign is flipped there so both sheets agree. Exactly at a zero the normal is
its limit along the ruling.

Batches. ``mesh_ribbons`` meshes S surfaces of one curve, one set of parameters t and one count
across as rows of one set of arrays: row r = s K + k is ruling k of surface s, and every step
below runs over all rows at once, a single surface being a batch of one
(``mesh_ribbon_surface``). Steps that compare rulings (consecutive pairs, the parity of their
signs, the documented side) stay within a surface. The rare repairs (rulings that stand still,
rulings along which the field may reverse, quads wound by geometry, triangles of zero area) run
on the rows flagged for them, of whichever surfaces. A surface the mesher must refuse is named
by its own ``EvolvedSurface`` (``check_projection_exists``, ``sample``) or here, and the batch
goes on without it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cgamesh.meshing import uv as uv_map
from cgamesh.geometry.algebra import products
from cgamesh.geometry.algebra.conformal import EUCLIDEAN, up, weight
from cgamesh.geometry.curves import CurveBasis
from cgamesh.errors import CgameshError, DegenerateGeometryError, InvalidInputError
from cgamesh.geometry.frame import LocalFrame
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.meshing.circles import drop_zero_area, grid_faces
from cgamesh.meshing.normals import expand
from cgamesh.geometry.objects import point_pair_endpoints
from cgamesh.geometry.projection import Projection, project, project_scalar
from cgamesh.geometry.surface import MIN_MARGIN, SCAN_SAMPLES_PER_SEGMENT, EvolvedSurface

# |N| below this fraction of |d| max(|a'|, |b'|) is a zero of the normal field.
ZERO_FRACTION = 1e-8
# Triangles touching vertices with |N| below this fraction are checked for zero area.
NEAR_ZERO_FRACTION = 1e-6
# A ruling whose normal vanishes everywhere (it does not move, or slides along itself) takes
# its velocities from this far along the curve.
NEARBY_OFFSET = 1e-6
# Rings whose |N|^2 falls below this fraction of its quadratic's terms get |N| from N itself.
CANCELLATION = 1e-2
# A reversal of the field along a ruling is a fold when the sine of the angle between dN/ds and
# dN/dt is below this. A ribbon folds only where it is developable (flat or conical pieces,
# where the sine is 0 to rounding); a generic ribbon has isolated pinch points, where the sine
# can be small (0.08 in examples/ribbon_loop.yaml) yet the raw field is the continuous one.
FOLD_SINE = 1e-2
# Fractions along each ruling at which consecutive rulings are compared when neither can reverse.
_COMPARE_AT = np.array([0.0, 0.5, 1.0])
# Consecutive rulings whose normals at those fractions neither agree nor oppose (mean cosine, or
# its negative after a flip, below this) are too far apart for their signs to tell the winding
# of the quad between them (a fold crossing it diagonally): that quad is wound by geometry.
TURNED_AGREEMENT = 0.5


@dataclass(frozen=True)
class PairRings:
    """Point pairs P(t_k) read out in world coordinates.

    a, b (K, 3): end points in the order of eq. 5; da, db (K, 3): their velocities d/dt.
    """

    a: np.ndarray
    b: np.ndarray
    da: np.ndarray
    db: np.ndarray

    @classmethod
    def from_projection(cls, projection: Projection, frame: LocalFrame) -> "PairRings":
        return cls(*_pair_rings(projection.blades, projection.derivatives, frame.origin, frame.scale))


def _pair_rings(blades: np.ndarray, derivatives: np.ndarray, origin, scale):
    """World a, b, da, db (R, 3) of projected point pairs (R, 32) and their d/dt, each row in the
    frame ``origin`` (3,) or (R, 3), ``scale`` a number or (R,)."""
    a, b = point_pair_endpoints(blades)
    # (R, 2, 3) in the local frame, laid out coordinate-major (as np.stack lays out two or more
    # rows of a and b): a row's sums in ``up`` then take the same order alone as among many
    ends = np.empty((3, len(a), 2)).transpose(1, 2, 0)
    ends[:, 0], ends[:, 1] = a, b
    # Omega = P dP/dt (eq. 19); X' = X . Omega (eq. 20) with weight rate w' = -X' . n_inf,
    # so the Euclidean velocity is x' = X'_E - w' x.
    omega = products.geometric(blades, derivatives, (2,), (2,), (2,))
    moved = products.inner(up(ends), omega[:, None, :], (1,), (2,))
    scale = np.reshape(scale, (-1, 1))
    velocity = scale[:, None] * (moved[..., EUCLIDEAN] - weight(moved)[..., None] * ends)
    return origin + scale * a, origin + scale * b, velocity[:, 0], velocity[:, 1]


class _Refused(Exception):
    """Surfaces of a batch (by position) refused, with the error naming why."""

    def __init__(self, errors: dict[int, CgameshError]):
        super().__init__(errors)
        self.errors = errors


class _Batch:
    """Surfaces (S) of one curve meshed on parameters t (K,): their controls, frames and rows."""

    def __init__(self, surfaces: Sequence[EvolvedSurface], t: np.ndarray):
        self.surfaces, self.t = list(surfaces), t
        self.curve = self.surfaces[0].curve
        self.end = self.curve.segment_count
        self.controls = np.stack([surface.controls for surface in self.surfaces])  # (S, n, 32)
        self.origin = np.array([surface.frame.origin for surface in self.surfaces], dtype=np.float64)
        self.scale = np.array([surface.frame.scale for surface in self.surfaces], dtype=np.float64)
        self.scalar = np.array([surface.four_vector_free for surface in self.surfaces])
        self.owner = np.repeat(np.arange(len(self.surfaces)), len(t))  # (R,) the surface of each row
        self.t_rows = np.tile(t, len(self.surfaces))  # (R,)
        # (S (K - 1),) the first row of each pair of consecutive rulings of a surface
        self.pair_first = (np.arange(len(self.surfaces))[:, None] * len(t) + np.arange(len(t) - 1)).ravel()

    def rings(self, owner: np.ndarray, t: np.ndarray, basis: CurveBasis | None = None) -> PairRings:
        """PairRings.from_projection(surface.sample(t)) of rows of surfaces ``owner`` (R,) at t (R,),
        each row as alone; _Refused for the surfaces whose ``sample`` refuses any of theirs."""
        basis = self.curve.basis(t) if basis is None else basis
        n = self.controls.shape[1]
        picked = self.controls.reshape(-1, self.controls.shape[2])[basis.indices + (owner * n)[:, None]]
        interpolant = np.einsum("ak,akm->am", basis.weights, picked)
        derivative = np.einsum("ak,akm->am", basis.derivatives, picked)
        size, scalar = basis.weight_sum(), self.scalar[owner]
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            blades, rates, margin = np.empty_like(interpolant), np.empty_like(interpolant), np.empty(len(t))
            for rows, projector in ((~scalar, project), (scalar, project_scalar)):  # as ``sample`` chooses
                if rows.any():
                    projected = projector(interpolant[rows], derivative[rows], 2, size[rows])
                    blades[rows], rates[rows], margin[rows] = projected.blades, projected.derivatives, projected.margin
            a, b, da, db = _pair_rings(blades, rates, self.origin[owner], self.scale[owner])
        bad = ~(margin >= MIN_MARGIN) | ~np.isfinite(a).all(axis=1) | ~np.isfinite(b).all(axis=1)
        if bad.any():  # the rare refusal, named by the surface's own ``sample``
            self.refuse({s: lambda s=s: self.surfaces[s].sample(t[owner == s]) for s in np.unique(owner[bad])})
        return PairRings(a, b, da, db)

    @staticmethod
    def refuse(checks: dict) -> None:
        """_Refused for the surfaces whose check (a callable) raises."""
        errors = {}
        for s, check in checks.items():
            try:
                check()
            except CgameshError as error:
                errors[int(s)] = error
        if errors:
            raise _Refused(errors)


def _unscanned(surfaces: Sequence[EvolvedSurface]) -> dict[int, CgameshError]:
    """The errors of ``check_projection_exists`` (the dense scan) of surfaces that fail it, by position.

    Many surfaces take the quick scan from their controls' products first
    (scene_batch.projection_scan: passes only what the dense scan passes, and decides the rest
    exactly); a surface it refuses, or a single one, is scanned by its own check, which names why.
    """
    doubtful = list(range(len(surfaces)))
    general = [i for i in doubtful if not surfaces[i].four_vector_free]  # the scalar projection: its own scan
    if len(surfaces) > 1 and general:
        from cgamesh.meshing.scene_batch.projection_scan import exactly_projectable, surely_projectable

        curve = surfaces[0].curve
        dense = np.linspace(0.0, curve.segment_count, SCAN_SAMPLES_PER_SEGMENT * curve.segment_count + 1)
        controls = np.stack([surfaces[i].controls for i in general])
        passed = surely_projectable(curve, dense, controls, grade=2)
        if not passed.all():
            passed[~passed] = exactly_projectable(curve, dense, controls[~passed], grade=2)
        doubtful = sorted(set(doubtful) - {i for i, ok in zip(general, passed) if ok})
    try:
        _Batch.refuse({i: surfaces[i].check_projection_exists for i in doubtful})
    except _Refused as refused:
        return refused.errors
    return {}


def mesh_ribbons(surfaces: Sequence[EvolvedSurface], around: int, along: int | None = None, closed: bool = False,
                 t: np.ndarray | None = None) -> list[SurfaceMesh | None]:
    """Each surface's ``mesh_ribbon_surface(surface, around, along, closed, t)``, or None for one
    it refuses; the surfaces share one curve (kind, control count, parameters)."""
    return [None if isinstance(mesh, CgameshError) else mesh for mesh in _meshes(surfaces, around, along, closed, t)]


def mesh_ribbon_surface(surface: EvolvedSurface, around: int, along: int | None = None,
                        closed: bool = False, t: np.ndarray | None = None) -> SurfaceMesh:
    """Triangulate an evolved point-pair surface on ``along`` rulings of ``around`` vertices each
    (at parameters ``t`` when given).

    Returns a double-sided SurfaceMesh (along * around vertices, ruling-major) in world
    coordinates; u = s across, v along by arc length. ``closed``: the curve ends where it
    starts (kb / catmull_rom loops), and the last ruling repeats the first bit for bit.
    """
    (mesh,) = _meshes([surface], around, along, closed, t)
    if isinstance(mesh, CgameshError):
        raise mesh
    return mesh


def _meshes(surfaces, around: int, along: int | None, closed: bool, t) -> list[SurfaceMesh | CgameshError]:
    if not surfaces:
        return []
    if len({surface.curve for surface in surfaces}) > 1:
        raise ValueError("mesh_ribbons: the surfaces of a batch share one curve")
    if t is None and along is not None and along >= 2:
        t = np.linspace(0.0, surfaces[0].segment_count, along)
    along = None if t is None else len(t)
    if around < 2 or along is None or along < 2:
        return [InvalidInputError(f"surface '{surface.name}': a ribbon needs around >= 2 and along >= 2, "
                                  f"got around = {around}, along = {along}") for surface in surfaces]
    results: dict[int, SurfaceMesh | CgameshError] = _unscanned(surfaces)
    live = [i for i in range(len(surfaces)) if i not in results]
    while live:
        try:
            results.update(zip(live, _mesh_batch(_Batch([surfaces[i] for i in live], t), around, closed)))
            break
        except _Refused as refused:  # met by few surfaces: the batch is meshed again without them
            results.update((live[i], error) for i, error in refused.errors.items())
            live = [i for j, i in enumerate(live) if j not in refused.errors]
    return [results[i] for i in range(len(surfaces))]


def _mesh_batch(batch: _Batch, around: int, closed: bool) -> list[SurfaceMesh]:
    """The meshes of the batch's surfaces (module doc); _Refused for those it must refuse."""
    count, along = len(batch.surfaces), len(batch.t)
    basis = batch.curve.basis(batch.t)
    if count > 1:  # every surface's rulings at the same parameters
        basis = CurveBasis(*(np.tile(x, (count, 1)) for x in (basis.indices, basis.weights, basis.derivatives)))
    rings = batch.rings(batch.owner, batch.t_rows, basis)
    d = rings.b - rings.a
    n_a, n_b, scale = _ruling_normals(batch, rings, d)
    s = np.linspace(0.0, 1.0, around)
    signs, rows, turned = _continuous_signs(batch, d, n_a, n_b, s, scale)
    # The documented side: the raw field d x dx/dt at most vertices of each surface.
    backwards = signs.reshape(count, -1).sum(axis=1) * (around if signs.shape[1] == 1 else 1) < 0.0
    if np.any(backwards):
        signs = np.where(np.repeat(backwards, along)[:, None], -signs, signs)

    positions = expand(np.stack([rings.a, d], axis=1), np.stack([np.ones_like(s), s], axis=1))
    normals, size_sq = _unit_normals(n_a, n_b, s, scale, signs)
    positions, normals = positions.reshape(count, along, around, 3), normals.reshape(count, along, around, 3)
    if closed:  # the last ruling is the first one again: same vertices, same normals
        positions[:, -1] = positions[:, 0]
        agree = np.sign(np.einsum("smc,smc->s", normals[:, -1], normals[:, 0]))
        seam = normals[:, 0] * np.where(agree == 0.0, 1.0, agree)[:, None, None]
        # where that turns a vertex of the last ruling over, the quad before it is wound by geometry
        turned_over = np.einsum("smc,smc->sm", normals[:, -1], seam).min(axis=1) < 0.0
        rows = np.union1d(rows, (np.flatnonzero(turned_over) + 1) * along - 1)
        normals[:, -1] = seam
    positions, normals = positions.reshape(count, -1, 3), normals.reshape(count, -1, 3)
    faces = _wound_faces(batch, positions, normals, signs[:, 0].reshape(count, along), rows, turned, around)
    near_zero = size_sq.reshape(count, -1) <= NEAR_ZERO_FRACTION**2  # zero-area triangles are looked for there
    ends = np.stack([rings.a, 0.5 * (rings.a + rings.b), rings.b], axis=1).reshape(count, along, 3, 3)
    uvs = uv_map.grid_uvs(uv_map.along_coordinates(ends), around)
    return [SurfaceMesh(name=surface.name, positions=positions[i], normals=normals[i], uvs=uvs[i],
                        faces=drop_zero_area(positions[i], faces[i], np.flatnonzero(near_zero[i])), double_sided=True)
            for i, surface in enumerate(batch.surfaces)]


def _ruling_normals(batch: _Batch, rings: PairRings, d: np.ndarray):
    """N_a, N_b (R, 3) and the field's scale |d| max(|a'|, |b'|) (R,).

    A ruling whose N_a and N_b both vanish (a ring that stands still, e.g. at a Kochanek-Bartels
    control with tension 1) takes the velocities from just past it: the limit of the direction.
    A surface with a ruling whose normal vanishes there too is refused.
    """
    da, db = rings.da, rings.db
    n_a, n_b = np.cross(d, da), np.cross(d, db)
    length = np.linalg.norm(d, axis=1)
    scale = length * np.maximum(np.linalg.norm(da, axis=1), np.linalg.norm(db, axis=1))
    flat = np.maximum(np.linalg.norm(n_a, axis=1), np.linalg.norm(n_b, axis=1)) <= ZERO_FRACTION * scale
    if np.any(flat):
        t = batch.t_rows[flat]
        nearby_t = np.where(t + NEARBY_OFFSET <= batch.end, t + NEARBY_OFFSET, t - NEARBY_OFFSET)
        nearby = batch.rings(batch.owner[flat], nearby_t)
        n_a[flat], n_b[flat] = np.cross(d[flat], nearby.da), np.cross(d[flat], nearby.db)
        speed = np.maximum(np.linalg.norm(nearby.da, axis=1), np.linalg.norm(nearby.db, axis=1))
        scale[flat] = length[flat] * speed
        size = np.maximum(np.linalg.norm(n_a, axis=1), np.linalg.norm(n_b, axis=1))
        still = np.flatnonzero(flat & ~(size > ZERO_FRACTION * scale))
        if still.size:  # each such surface named at its first ruling that stands still
            owners, first = np.unique(batch.owner[still], return_index=True)
            at = batch.t_rows[still[first]]
            segment = np.minimum(at.astype(int), batch.end - 1)
            raise _Refused({int(s): DegenerateGeometryError(
                f"surface '{batch.surfaces[s].name}': the ribbon has no area at segment {k}, alpha = {t - k:.6g} "
                "(its segments stand still or slide along their own line)") for s, k, t in zip(owners, segment, at)})
    return n_a, n_b, scale


def _ruling_values(n_a: np.ndarray, n_b: np.ndarray, s: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """N (R, M, 3) = (1 - s) N_a + s N_b at fractions s (M,), zeros replaced by their limit.

    n_a, n_b (R, 3); scale (R,). Exactly at a zero the direction is the limit along the ruling
    from below (from above at s = 0): -/+ (N_b - N_a).
    """
    slope = n_b - n_a
    values = n_a[:, None, :] + s[None, :, None] * slope[:, None, :]
    zero = np.einsum("rmc,rmc->rm", values, values) <= (ZERO_FRACTION * scale[:, None]) ** 2
    if np.any(zero):
        row, column = np.nonzero(zero)
        values[row, column] = np.where(s[column] > 0.0, -1.0, 1.0)[:, None] * slope[row]
    return values


def _unit(values: np.ndarray) -> np.ndarray:
    return values / np.maximum(np.linalg.norm(values, axis=-1, keepdims=True), np.finfo(float).tiny)


def _rates(batch: _Batch, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """dN_a/dt, dN_b/dt (R', 3) at rows ``rows`` (R',): central differences of the exact N_a, N_b
    over +-NEARBY_OFFSET (one-sided at the ends of the curve)."""
    owner, t = batch.owner[rows], batch.t_rows[rows]
    low, high = np.maximum(t - NEARBY_OFFSET, 0.0), np.minimum(t + NEARBY_OFFSET, batch.end)
    near = batch.rings(np.concatenate([owner, owner]), np.concatenate([low, high]))
    d = near.b - near.a
    width = np.concatenate([high - low, high - low])[:, None]
    n_a, n_b = np.cross(d, near.da) / width, np.cross(d, near.db) / width
    count = len(t)
    return n_a[count:] - n_a[:count], n_b[count:] - n_b[:count]


def _may_reverse(n_a: np.ndarray, n_b: np.ndarray, step: float) -> np.ndarray:
    """(R,) bool: rulings along which N can turn by more than 90 degrees between two columns.

    N(s) = N_a + s m runs along a straight line; over one column step it turns by more than
    90 degrees only if that line passes within |m| step / 2 of zero at some s* in [0, 1].
    """
    m = n_b - n_a
    m_sq = np.einsum("kc,kc->k", m, m)
    closest = -np.einsum("kc,kc->k", n_a, m)
    miss = np.linalg.norm(np.cross(n_a, m), axis=1)  # |m| times the distance of the line from 0
    return (m_sq > 0.0) & (closest >= -step * m_sq) & (closest <= (1.0 + step) * m_sq) & (miss <= step * m_sq)


def _continuous_signs(batch: _Batch, d: np.ndarray, n_a: np.ndarray, n_b: np.ndarray, s: np.ndarray,
                      scale: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Signs (R, M), or (R, 1) when no ruling can reverse, making each surface's field continuous;
    the rows (R',) examined vertex by vertex (those that may reverse, with their neighbours); and
    the consecutive pairs (S (K - 1),) bool turned apart (``turned_pairs``).

    A reversal between two columns is a fold when dN/ds = N_b - N_a and dN/dt (differentiated
    on the surface) are nearly parallel: the Jacobian of N over (s, t) is singular, as along a
    fold curve; at a pinch point it is regular and the raw field is kept. Consecutive rings are
    then compared and a ring is flipped when it disagrees with the previous one.
    """
    count, along, first = len(batch.surfaces), len(batch.t), batch.pair_first
    suspicious = _may_reverse(n_a, n_b, s[1] - s[0])
    samples = _unit(_ruling_values(n_a, n_b, _COMPARE_AT, scale)).reshape(count, along, len(_COMPARE_AT), 3)
    agreement = np.einsum("kmc,kmc->k", *(np.ascontiguousarray(pair).reshape(-1, len(_COMPARE_AT), 3)
                                          for pair in (samples[:, :-1], samples[:, 1:])))
    turned = turned_pairs(agreement)
    # Each suspicious ring with its neighbours on its own surface.
    near = np.array(suspicious, dtype=bool)
    near[first + 1] |= suspicious[first]
    near[first] |= suspicious[first + 1]
    rows = np.flatnonzero(near)
    if rows.size == 0:
        return (1.0 - 2.0 * _ring_parity(agreement, count))[:, None], rows, turned
    signs = np.ones((len(n_a), len(s)))
    unit = _unit(_ruling_values(n_a[rows], n_b[rows], s, scale[rows]))
    row, column = np.nonzero(np.einsum("rmc,rmc->rm", unit[:, :-1], unit[:, 1:]) < 0.0)
    if row.size:
        ring = rows[row]
        dn_a, dn_b = _rates(batch, ring)
        d_t = dn_a + 0.5 * (s[column] + s[column + 1])[:, None] * (dn_b - dn_a)
        along_ruling = d[ring] / np.linalg.norm(d[ring], axis=1, keepdims=True)
        d_t -= np.einsum("rc,rc->r", d_t, along_ruling)[:, None] * along_ruling  # N stays across the ruling
        d_s = n_b[ring] - n_a[ring]
        sine = np.linalg.norm(np.cross(d_s, d_t), axis=1)
        fold = sine <= FOLD_SINE * np.linalg.norm(d_s, axis=1) * np.linalg.norm(d_t, axis=1)
        flips = np.zeros(unit.shape[:2], dtype=np.int64)
        flips[row[fold], column[fold] + 1] = 1
        signs[rows] = 1.0 - 2.0 * (np.cumsum(flips, axis=1) % 2)
    # Pairs of rings next to a reversing one are compared at every column.
    signed = unit * signs[rows][..., None]
    examined = np.zeros(len(n_a), dtype=bool)
    examined[rows] = True
    pairs = np.flatnonzero(examined[first] & examined[first + 1])
    position = np.searchsorted(rows, first[pairs])
    agreement[pairs] = np.einsum("pmc,pmc->p", signed[position], signed[position + 1])
    return signs * (1.0 - 2.0 * _ring_parity(agreement, count))[:, None], rows, turned


def _ring_parity(agreement: np.ndarray, count: int) -> np.ndarray:
    """(S K,) 0 or 1: whether each ring is flipped against its surface's first, from the
    agreement (S (K - 1),) of consecutive rings (negative: they disagree)."""
    flips = np.cumsum((agreement < 0.0).reshape(count, -1), axis=1)
    return np.concatenate([np.zeros((count, 1), dtype=flips.dtype), flips], axis=1).ravel() % 2


def turned_pairs(agreement: np.ndarray) -> np.ndarray:
    """Consecutive rulings (P,) bool whose normals at the _COMPARE_AT fractions (``agreement``,
    their cosines summed) agree or oppose by less than TURNED_AGREEMENT on average."""
    return np.abs(agreement) < TURNED_AGREEMENT * len(_COMPARE_AT)


def _wound_faces(batch: _Batch, positions: np.ndarray, normals: np.ndarray, ring_signs: np.ndarray,
                 rows: np.ndarray, turned: np.ndarray, around: int) -> np.ndarray:
    """Each surface's triangles (S, F, 3) int32 on its (K, M) grid: quad (k, j) splits into
    (k,j)(k,j+1)(k+1,j) and (k,j+1)(k+1,j+1)(k+1,j), wound like d/ds x d/dt, reversed where the
    sum of the triangle's vertex signs is negative (``ring_signs`` (S, K): each ring's first
    column). Wound by their own geometry against their normals: the quads next to the rings
    in ``rows`` (examined vertex by vertex; a closed surface's seam), those between consecutive rings of opposite sign (whose
    two triangles a vote of vertex signs would wind apart: two vertices of one ring, one of the
    other; seen on a ribbon starting on a repeated control, where the field's sign at the first
    ring is a limit), and those between rings ``turned`` (S (K - 1),) apart (``turned_pairs``)."""
    count, along = ring_signs.shape
    faces = grid_faces(along, around, np.ones((1, 1)))
    faces = np.tile(faces, (count, 1, 1)) if count > 1 else faces[None]
    quads = faces.reshape(count, along - 1, around - 1, 2, 3)
    # triangle 0 has two vertices on ring k, triangle 1 two on ring k + 1: the vote is that ring's
    for triangle, reversed_ in ((0, ring_signs[:, :-1] < 0.0), (1, ring_signs[:, 1:] < 0.0)):
        if reversed_.any():
            corners = quads[:, :, :, triangle]
            corners[reversed_] = corners[reversed_][..., [0, 2, 1]]
    examined = np.union1d(rows, batch.pair_first[(ring_signs[:, 1:] != ring_signs[:, :-1]).ravel() | turned])
    if examined.size == 0:
        return faces
    # the quads (S (K - 1) of them, surface-major) before and after each examined ring, on its surface
    ring = np.concatenate([examined % along - 1, examined % along])
    quad = np.unique((np.concatenate([examined, examined]) // along * (along - 1) + ring)[(ring >= 0) & (ring < along - 1)])
    per_quad = 2 * (around - 1)
    index = (quad[:, None] * per_quad + np.arange(per_quad)).ravel()
    flat = faces.reshape(-1, 3)
    vertices = flat[index] + (index // faces.shape[1] * positions.shape[1])[:, None].astype(flat.dtype)
    corners = positions.reshape(-1, 3)[vertices]
    geometric = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    wrong = index[np.einsum("fi,fi->f", geometric, normals.reshape(-1, 3)[vertices].sum(axis=1)) < 0.0]
    flat[wrong] = flat[wrong][:, [0, 2, 1]]
    return faces


def _unit_normals(n_a: np.ndarray, n_b: np.ndarray, s: np.ndarray, scale: np.ndarray,
                  signs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """signs * N / |N| (R, M, 3), zeros replaced by their limit along the ruling, and the raw
    (|N| / scale)^2 (R, M).

    N = N_a + s (N_b - N_a) is one matrix product over all vertices (``expand``), and
    |N|^2 = |N_a|^2 + 2 s N_a . m + s^2 |m|^2 a quadratic per ring; rings where that sum
    cancels (|N| small against its terms) have |N| recomputed from N itself.
    """
    m = n_b - n_a
    normals = expand(np.stack([n_a, m], axis=1), np.stack([np.ones_like(s), s], axis=1))
    inv_sq = 1.0 / scale**2
    c0 = np.einsum("kc,kc->k", n_a, n_a) * inv_sq
    c1 = 2.0 * np.einsum("kc,kc->k", n_a, m) * inv_sq
    c2 = np.einsum("kc,kc->k", m, m) * inv_sq
    size_sq = np.multiply.outer(c2, s)  # c0 + s (c1 + s c2), in place
    size_sq += c1[:, None]
    size_sq *= s
    size_sq += c0[:, None]
    cancels = np.flatnonzero(size_sq.min(axis=1) <= CANCELLATION * (c0 + np.abs(c1) + c2))
    if cancels.size:
        exact = n_a[cancels][:, None, :] + s[None, :, None] * m[cancels][:, None, :]
        normals[cancels] = exact
        size_sq[cancels] = np.einsum("kmc,kmc->km", exact, exact) * inv_sq[cancels, None]
    length = np.sqrt(size_sq)
    length *= scale[:, None]
    zero = size_sq <= ZERO_FRACTION**2
    if np.any(zero):  # the limit along the ruling, as in _ruling_values
        ring, column = np.nonzero(zero)
        normals[ring, column] = np.where(s[column] > 0.0, -1.0, 1.0)[:, None] * m[ring]
        length[ring, column] = np.linalg.norm(m[ring], axis=1)
    np.divide(signs, length, out=length)
    normals *= length[..., None]
    return normals, size_sq
