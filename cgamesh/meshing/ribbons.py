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
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cgamesh.meshing import uv as uv_map
from cgamesh.geometry.algebra import products
from cgamesh.geometry.algebra.conformal import EUCLIDEAN, up, weight
from cgamesh.errors import DegenerateGeometryError, InvalidInputError
from cgamesh.geometry.frame import LocalFrame
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.meshing.circles import drop_zero_area, grid_faces
from cgamesh.meshing.normals import expand
from cgamesh.geometry.objects import point_pair_endpoints
from cgamesh.geometry.projection import Projection
from cgamesh.geometry.surface import EvolvedSurface

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
        a, b = point_pair_endpoints(projection.blades)
        ends = np.stack([a, b], axis=1)  # (K, 2, 3), local frame
        # Omega = P dP/dt (eq. 19); X' = X . Omega (eq. 20) with weight rate w' = -X' . n_inf,
        # so the Euclidean velocity is x' = X'_E - w' x.
        omega = products.geometric(projection.blades, projection.derivatives, (2,), (2,), (2,))
        moved = products.inner(up(ends), omega[:, None, :], (1,), (2,))
        velocity = frame.scale * (moved[..., EUCLIDEAN] - weight(moved)[..., None] * ends)
        return cls(frame.to_world(a), frame.to_world(b), velocity[:, 0], velocity[:, 1])


def _ruling_normals(surface: EvolvedSurface, t: np.ndarray, rings: PairRings, d: np.ndarray):
    """N_a, N_b (K, 3) and the field's scale |d| max(|a'|, |b'|) (K,).

    A ruling whose N_a and N_b both vanish (a ring that stands still, e.g. at a Kochanek-Bartels
    control with tension 1) takes the velocities from just past it: the limit of the direction.
    """
    da, db = rings.da, rings.db
    n_a, n_b = np.cross(d, da), np.cross(d, db)
    length = np.linalg.norm(d, axis=1)
    scale = length * np.maximum(np.linalg.norm(da, axis=1), np.linalg.norm(db, axis=1))
    flat = np.maximum(np.linalg.norm(n_a, axis=1), np.linalg.norm(n_b, axis=1)) <= ZERO_FRACTION * scale
    if np.any(flat):
        end = surface.segment_count
        nearby_t = np.where(t[flat] + NEARBY_OFFSET <= end, t[flat] + NEARBY_OFFSET, t[flat] - NEARBY_OFFSET)
        nearby = PairRings.from_projection(surface.sample(nearby_t), surface.frame)
        n_a[flat], n_b[flat] = np.cross(d[flat], nearby.da), np.cross(d[flat], nearby.db)
        speed = np.maximum(np.linalg.norm(nearby.da, axis=1), np.linalg.norm(nearby.db, axis=1))
        scale[flat] = length[flat] * speed
        size = np.maximum(np.linalg.norm(n_a, axis=1), np.linalg.norm(n_b, axis=1))
        still = flat & ~(size > ZERO_FRACTION * scale)
        if np.any(still):
            k = int(np.flatnonzero(still)[0])
            segment = min(int(t[k]), end - 1)
            raise DegenerateGeometryError(
                f"surface '{surface.name}': the ribbon has no area at segment {segment}, alpha = "
                f"{t[k] - segment:.6g} (its segments stand still or slide along their own line)"
            )
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


def _rates(surface: EvolvedSurface, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """dN_a/dt, dN_b/dt (R, 3) at parameters t (R,): central differences of the exact N_a, N_b
    over +-NEARBY_OFFSET (one-sided at the ends of the curve)."""
    end = surface.segment_count
    low, high = np.maximum(t - NEARBY_OFFSET, 0.0), np.minimum(t + NEARBY_OFFSET, end)
    near = PairRings.from_projection(surface.sample(np.concatenate([low, high])), surface.frame)
    d = near.b - near.a
    width = np.concatenate([high - low, high - low])[:, None]
    n_a, n_b = np.cross(d, near.da) / width, np.cross(d, near.db) / width
    count = len(t)
    return n_a[count:] - n_a[:count], n_b[count:] - n_b[:count]


def _may_reverse(n_a: np.ndarray, n_b: np.ndarray, step: float) -> np.ndarray:
    """(K,) bool: rulings along which N can turn by more than 90 degrees between two columns.

    N(s) = N_a + s m runs along a straight line; over one column step it turns by more than
    90 degrees only if that line passes within |m| step / 2 of zero at some s* in [0, 1].
    """
    m = n_b - n_a
    m_sq = np.einsum("kc,kc->k", m, m)
    closest = -np.einsum("kc,kc->k", n_a, m)
    miss = np.linalg.norm(np.cross(n_a, m), axis=1)  # |m| times the distance of the line from 0
    return (m_sq > 0.0) & (closest >= -step * m_sq) & (closest <= (1.0 + step) * m_sq) & (miss <= step * m_sq)


def _continuous_signs(surface: EvolvedSurface, t: np.ndarray, d: np.ndarray, n_a: np.ndarray,
                      n_b: np.ndarray, s: np.ndarray, scale: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Signs (K, M), or (K, 1) when no ruling can reverse, making the field continuous; the
    rings (R,) examined vertex by vertex (those that may reverse, with their neighbours); and
    the consecutive pairs (K - 1,) bool turned apart (``turned_pairs``).

    A reversal between two columns is a fold when dN/ds = N_b - N_a and dN/dt (differentiated
    on the surface) are nearly parallel: the Jacobian of N over (s, t) is singular, as along a
    fold curve; at a pinch point it is regular and the raw field is kept. Consecutive rings are
    then compared and a ring is flipped when it disagrees with the previous one.
    """
    count = len(n_a)
    suspicious = _may_reverse(n_a, n_b, s[1] - s[0])
    samples = _unit(_ruling_values(n_a, n_b, _COMPARE_AT, scale))
    agreement = np.einsum("kmc,kmc->k", samples[:-1], samples[1:])
    turned = turned_pairs(agreement)
    # Each suspicious ring with its two neighbours (np.convolve's "same" mode would return
    # three entries for two rings).
    near = np.array(suspicious, dtype=bool)
    near[1:] |= suspicious[:-1]
    near[:-1] |= suspicious[1:]
    rows = np.flatnonzero(near)
    if rows.size == 0:
        flipped = np.cumsum(np.concatenate([[False], agreement < 0.0])) % 2 == 1
        return np.where(flipped, -1.0, 1.0)[:, None], rows, turned
    signs = np.ones((count, len(s)))
    unit = _unit(_ruling_values(n_a[rows], n_b[rows], s, scale[rows]))
    row, column = np.nonzero(np.einsum("rmc,rmc->rm", unit[:, :-1], unit[:, 1:]) < 0.0)
    if row.size:
        ring = rows[row]
        dn_a, dn_b = _rates(surface, t[ring])
        d_t = dn_a + 0.5 * (s[column] + s[column + 1])[:, None] * (dn_b - dn_a)
        along = d[ring] / np.linalg.norm(d[ring], axis=1, keepdims=True)
        d_t -= np.einsum("rc,rc->r", d_t, along)[:, None] * along  # N stays across the ruling
        d_s = n_b[ring] - n_a[ring]
        sine = np.linalg.norm(np.cross(d_s, d_t), axis=1)
        fold = sine <= FOLD_SINE * np.linalg.norm(d_s, axis=1) * np.linalg.norm(d_t, axis=1)
        flips = np.zeros(unit.shape[:2], dtype=np.int64)
        flips[row[fold], column[fold] + 1] = 1
        signs[rows] = 1.0 - 2.0 * (np.cumsum(flips, axis=1) % 2)
    # Pairs of rings next to a reversing one are compared at every column.
    signed = unit * signs[rows][..., None]
    pairs = np.flatnonzero(np.isin(np.arange(count - 1), rows) & np.isin(np.arange(1, count), rows))
    position = np.searchsorted(rows, pairs)
    agreement[pairs] = np.einsum("pmc,pmc->p", signed[position], signed[position + 1])
    ring_parity = np.concatenate([[0], np.cumsum(agreement < 0.0)]) % 2
    return signs * (1.0 - 2.0 * ring_parity)[:, None], rows, turned


def turned_pairs(agreement: np.ndarray) -> np.ndarray:
    """Consecutive rulings (K - 1,) bool whose normals at the _COMPARE_AT fractions (``agreement``,
    their cosines summed) agree or oppose by less than TURNED_AGREEMENT on average."""
    return np.abs(agreement) < TURNED_AGREEMENT * len(_COMPARE_AT)


def wound_faces(positions: np.ndarray, normals: np.ndarray, signs: np.ndarray, rows: np.ndarray, along: int,
                around: int, turned: np.ndarray) -> np.ndarray:
    """The ruling grid's triangles: whole rings wound by their sign (``signs`` (K, M) or (K, 1));
    by their own geometry against their normals, the quads next to the rings examined vertex by
    vertex (``rows``), those between consecutive rings of opposite sign, whose two triangles
    a vote of vertex signs would wind apart (two vertices of one ring, one of the other; seen on
    a ribbon starting on a repeated control, where the field's sign at the first ring is a limit),
    and those between rings ``turned`` (K - 1,) apart (``turned_pairs``)."""
    faces = grid_faces(along, around, signs[:, :1])
    examined = np.union1d(rows, np.flatnonzero((signs[1:, 0] != signs[:-1, 0]) | turned))
    return _orient_faces(positions, normals, faces, examined, around) if examined.size else faces


def _orient_faces(positions: np.ndarray, normals: np.ndarray, faces: np.ndarray, rows: np.ndarray,
                  columns: int) -> np.ndarray:
    """Wind the triangles of the quads next to rings ``rows`` like their vertex normals (in place).

    Near a fold or a pinch point a triangle can straddle the place where the field turns; the
    vertex signs alone cannot say how it lies, its own geometric normal can.
    """
    quads = np.unique(np.concatenate([rows - 1, rows]))
    quads = quads[(quads >= 0) & (quads * columns < len(positions) - columns)]
    per_ring = 2 * (columns - 1)
    index = (quads[:, None] * per_ring + np.arange(per_ring)).ravel()
    corners = positions[faces[index]]
    geometric = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    wrong = index[np.einsum("fi,fi->f", geometric, normals[faces[index]].sum(axis=1)) < 0.0]
    faces[wrong] = faces[wrong][:, [0, 2, 1]]
    return faces


def _unit_normals(n_a: np.ndarray, n_b: np.ndarray, s: np.ndarray, scale: np.ndarray,
                  signs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """signs * N / |N| (K, M, 3), zeros replaced by their limit along the ruling, and the raw
    (|N| / scale)^2 (K, M).

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


def mesh_ribbon_surface(surface: EvolvedSurface, around: int, along: int | None = None,
                        closed: bool = False, t: np.ndarray | None = None,
                        rings: PairRings | None = None) -> SurfaceMesh:
    """Triangulate an evolved point-pair surface on ``along`` rulings of ``around`` vertices each.

    Returns a double-sided SurfaceMesh (along * around vertices, ruling-major) in world
    coordinates; u = s across, v along by arc length. ``closed``: the curve ends where it
    starts (kb / catmull_rom loops), and the last ruling repeats the first bit for bit.
    """
    if t is None and along is not None and along >= 2:
        t = np.linspace(0.0, surface.segment_count, along)
    along = None if t is None else len(t)
    if around < 2 or along is None or along < 2:
        raise InvalidInputError(f"surface '{surface.name}': a ribbon needs around >= 2 and along >= 2, "
                                f"got around = {around}, along = {along}")
    if rings is None:
        surface.check_projection_exists()
        rings = PairRings.from_projection(surface.sample(t), surface.frame)
    d = rings.b - rings.a
    n_a, n_b, scale = _ruling_normals(surface, t, rings, d)
    s = np.linspace(0.0, 1.0, around)
    signs, rows, turned = _continuous_signs(surface, t, d, n_a, n_b, s, scale)
    # The documented side: the raw field d x dx/dt at most vertices.
    if np.sum(signs) * (around if signs.shape[1] == 1 else 1) < 0.0:
        signs = -signs

    positions = expand(np.stack([rings.a, d], axis=1), np.stack([np.ones_like(s), s], axis=1))
    normals, size_sq = _unit_normals(n_a, n_b, s, scale, signs)
    if closed:  # the last ruling is the first one again: same vertices, same normals
        positions[-1] = positions[0]
        normals[-1] = normals[0] * np.sign(np.einsum("mc,mc->", normals[-1], normals[0]) or 1.0)

    positions = positions.reshape(-1, 3)
    normals = normals.reshape(-1, 3)
    faces = wound_faces(positions, normals, signs, rows, along, around, turned)
    faces = drop_zero_area(positions, faces, np.flatnonzero(size_sq <= NEAR_ZERO_FRACTION**2))
    ends = np.stack([rings.a, 0.5 * (rings.a + rings.b), rings.b], axis=1)
    uvs = uv_map.grid_uvs(uv_map.along_coordinates(ends), around)
    return SurfaceMesh(name=surface.name, positions=positions, normals=normals, uvs=uvs, faces=faces,
                       double_sided=True)
