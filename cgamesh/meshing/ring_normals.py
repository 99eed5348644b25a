"""Which way the normals of circle rings point: the per-ring normal field, its continuity across
folds, and the outward choice, for rows of rings of any number of surfaces.

The normal field of each ring is a trigonometric polynomial in theta (cgamesh.meshing.normals,
paper section 5.2). It is made continuous over each surface's (t, theta) grid: only rings whose
field can reverse between two columns are examined vertex by vertex (``fold_screen``), a
reversal counts as a fold (and flips the sign after it) only when ``normals.fold_sines``
confirms it from the ring and the same ring a tiny step before and after, and consecutive rings
whose normals are all but opposite lie on the two sides of a fold between them. The whole field
of a surface is then turned outward: the sum over its vertices of n . (x - centre) is positive.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from cgamesh.meshing import normals as normal_field
from cgamesh.meshing.ring_rows import Resample, RingRows, SurfaceRows

# A ring moving slower than this fraction of its radius per unit alpha is stationary (e.g. a
# Kochanek-Bartels control with tension 1): its normals come from just past it.
STATIONARY_FRACTION = 1e-9
STATIONARY_OFFSET = 1e-6
# Consecutive rings whose normals agree less than this (mean cosine below minus it) lie on
# the two sides of a fold.
FOLD_AGREEMENT = 0.9
# Consecutive rings whose normals (after any fold's flip) are on average more than a right angle
# apart are too far apart for the field's orientation to tell the winding of the triangles
# between them (the chord need not run along d/dt): those are wound by their own geometry.
TURNED_AGREEMENT = 0.0
# The seven-sample estimate of the outward sum decides its sign when the mean |cosine| between
# normals and radial directions is at least this.
OUTWARD_TRUST = 0.25
# An outward estimate or sum this close (relative) to its decision is summed again as the sum of
# that one surface's rows alone (numpy's sums over all rows at once round in another order).
DECISION_MARGIN = 1e-9


@dataclass(frozen=True)
class RingNormals:
    """The normal field of each ring as trigonometric polynomials in theta.

    frame: (R, 7, 2) coefficients of (zeta, rho); raw: (R, 7, 3) coefficients of N in world
    axes; speed: (R,) the ring's largest velocity (in its surface's working units, world / frame
    scale); samples: (R, 7, 3) points at the sample angles; sample_normals: (R, 7, 3) N there.
    """

    frame: np.ndarray
    raw: np.ndarray
    speed: np.ndarray
    samples: np.ndarray
    sample_normals: np.ndarray

    @classmethod
    def of(cls, rings: RingRows, u: np.ndarray, v: np.ndarray) -> "RingNormals":
        points, radial = normal_field.sample_points(rings.centre, rings.radius, u, v)
        # In each surface's working units (world / frame scale): a tube 1e-300 or 1e300 across
        # has normals whose squared lengths neither underflow nor overflow.
        velocity = rings.velocity(points)  # a fresh array, divided in place
        velocity /= rings.scale[:, None, None]
        zeta_rho = normal_field.frame_coordinates(velocity, radial, rings.normal)
        sampled = normal_field.normal_samples(zeta_rho, radial, rings.normal)
        speed = normal_field.row_lengths(velocity).max(axis=1)
        return cls(normal_field.fit(zeta_rho), normal_field.fit(sampled), speed, points, sampled)

    def replace_rings(self, which: np.ndarray, other: "RingNormals") -> "RingNormals":
        """These normals with the rings ``which`` (bool (R,)) taken from ``other`` (one row each)."""
        fields = {}
        for name in ("frame", "raw", "speed", "sample_normals"):
            mine = getattr(self, name).copy()
            mine[which] = getattr(other, name)
            fields[name] = mine
        return RingNormals(samples=self.samples, **fields)


def nearby_normals(rings: RingRows, u: np.ndarray) -> RingNormals:
    """Normals of rings read at nearby parameters, their phase carried from axes u (n, 3) nearby."""
    u = u - np.einsum("ki,ki->k", u, rings.normal)[:, None] * rings.normal
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    return RingNormals.of(rings, u, np.cross(rings.normal, u))


def step_inside(t: np.ndarray, end: np.ndarray, sign: float) -> np.ndarray:
    """t + sign * STATIONARY_OFFSET, or the other way where that would leave [0, end]."""
    moved = t + sign * STATIONARY_OFFSET
    return np.where((moved >= 0.0) & (moved <= end), moved, t - sign * STATIONARY_OFFSET)


def fold_screen(field: RingNormals, smallest: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(suspicious (R,): rings whose smallest |N| over the columns is within what |dN/dtheta|
    can change over one column step, so N may vanish between columns; agreement (R - 1,): the
    mean cosine between consecutive rings' normals at the seven sample angles)."""
    suspicious = smallest <= normal_field.derivative_bound(field.raw) * (theta[1] - theta[0])
    unit = normal_field.unit_rows(field.sample_normals)  # each ring's once, for both its pairs
    agreement = np.einsum("ksc,ksc->k", unit[:-1], unit[1:]) / field.sample_normals.shape[1]
    return suspicious, agreement


def frame_values(frame: np.ndarray, theta: np.ndarray, speed: np.ndarray) -> np.ndarray:
    """(zeta, rho) (R, M, 2) at theta, zeros replaced by their limit d/dtheta along the circle."""
    values = normal_field.expand(frame, normal_field.trig_basis(theta))
    zero = np.hypot(values[..., 0], values[..., 1]) <= normal_field.ZERO_FRACTION * speed[:, None]
    if np.any(zero):
        ring, column = np.nonzero(zero)
        values[ring, column] = np.einsum("za,zac->zc", normal_field.trig_basis_derivative(theta[column]),
                                         frame[ring])
    return values


def turned_pairs(agreement: np.ndarray) -> np.ndarray:
    """Consecutive rings (R - 1,) bool whose normals, after a fold's flip (agreement below
    -FOLD_AGREEMENT), still agree less than TURNED_AGREEMENT: the step between them is too
    long for the analytic orientation to wind their triangles (see TURNED_AGREEMENT)."""
    return (agreement < TURNED_AGREEMENT) & (agreement >= -FOLD_AGREEMENT)


@dataclass(frozen=True)
class RingSigns:
    """Signs making each surface's normal field continuous and outward.

    ring: (R,) +-1 per ring; vertex: (N, M) +-1 per vertex of the ``examined`` rings (N,) (rows
    whose field may turn fast, ``fold_screen``), which replace ``ring`` there; examined_surface
    (S,) surfaces with such rings (their signs are per vertex); agreement (R - 1,) of
    consecutive rings after that examination; missing (S,) surfaces whose rings a step before
    and after a reversal could not be read (``Resample``)."""

    ring: np.ndarray
    vertex: np.ndarray
    examined: np.ndarray
    examined_surface: np.ndarray
    agreement: np.ndarray
    missing: np.ndarray

    def at(self, rows: np.ndarray, columns: int) -> np.ndarray:
        """The signs (n, M) of rows (n,) at every column."""
        signs = np.repeat(self.ring[rows, None], columns, axis=1)
        row_of = self.row_of
        examined = row_of[rows] >= 0
        signs[examined] = self.vertex[row_of[rows[examined]]] * self.ring[rows[examined], None]
        return signs

    @cached_property
    def row_of(self) -> np.ndarray:
        """(R,) each ring's row of ``vertex``, -1 for rings not examined."""
        row_of = np.full(len(self.ring), -1)
        row_of[self.examined] = np.arange(len(self.examined))
        return row_of

    @property
    def examined_rows(self) -> np.ndarray:
        """(R,) bool: the examined rings."""
        return self.row_of >= 0

    def flipped(self, flip: np.ndarray, surface: np.ndarray) -> "RingSigns":
        """These signs with surfaces ``flip`` (S,) bool turned over (``surface`` (R,): each row's)."""
        factor = np.where(flip[surface], -1.0, 1.0)
        return RingSigns(self.ring * factor, self.vertex, self.examined, self.examined_surface, self.agreement,
                         self.missing)


def continuous_signs(field: RingNormals, smallest: np.ndarray, theta: np.ndarray, rings: RingRows,
                     layout: SurfaceRows, ends: np.ndarray, u: np.ndarray, resample: Resample) -> RingSigns:
    """The signs making the field continuous over each surface's grid (module doc). ``ends`` (S,)
    each surface's last parameter; ``resample`` reads circles of surfaces by their index."""
    columns = len(theta)
    surface, within = layout.surface, layout.within
    suspicious, agreement = fold_screen(field, smallest, theta)
    agreement[~within] = 1.0  # no pair across two surfaces
    missing = np.zeros(len(layout.count), dtype=bool)
    near = np.flatnonzero(suspicious)
    vertex = np.ones((len(near), columns))
    if near.size:
        values = frame_values(field.frame[near], theta, field.speed[near])
        folds = normal_field.reversals(values)
        if np.any(folds):
            row, column = np.nonzero(folds)
            ring = near[row]
            end = ends[surface[ring]]
            before_t = np.maximum(rings.t[ring] - STATIONARY_OFFSET, 0.0)
            after_t = np.minimum(rings.t[ring] + STATIONARY_OFFSET, end)
            count = len(ring)
            both = np.concatenate([surface[ring], surface[ring]])
            read, exists = resample(both, np.concatenate([before_t, after_t]))
            missing[both[~exists]] = True
            with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
                nearby = nearby_normals(read, np.concatenate([u[ring], u[ring]]))
                sines = normal_field.fold_sines(field.frame[ring], nearby.frame[:count], nearby.frame[count:],
                                                after_t - before_t, theta[column], theta[column + 1])
            folds[row, column] = sines <= normal_field.FOLD_SINE
        vertex = normal_field.ring_signs(folds)
        # Pairs of examined rings are compared at every column.
        row_of = np.full(len(smallest), -1)
        row_of[near] = np.arange(len(near))
        unit = normal_field.unit_rows(values) * vertex[..., None]
        pairs = np.flatnonzero((row_of[:-1] >= 0) & (row_of[1:] >= 0) & within)
        agreement[pairs] = np.einsum("kmc,kmc->k", unit[row_of[pairs]], unit[row_of[pairs + 1]]) / columns
    # A fold between two rings reverses the field along a line: the rings' normals are then
    # all but opposite. A crease (a joint of a linear or C0 spline) turns them by less, and the
    # field there is simply discontinuous: no flip.
    reversed_pairs = np.concatenate([[0], np.cumsum(agreement < -FOLD_AGREEMENT)])
    # (a surface left with no rings has its first row past the last: it is no row's surface)
    parity = (reversed_pairs - reversed_pairs[np.minimum(layout.first, len(surface) - 1)][surface]) % 2
    examined_surface = np.bincount(surface[near], minlength=len(layout.count)) > 0
    return RingSigns(1.0 - 2.0 * parity, vertex, near, examined_surface, agreement, missing)


def outward_flips(field: RingNormals, signs: RingSigns, rings: RingRows, layout: SurfaceRows,
                  positions: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """(S,) the surfaces whose field, with these signs, points inward: the sum over their
    vertices of s n . (x - centre) = s r zeta / |N| is negative.

    normals: the unit field (R, M, 3) before the signs. Where each ring has one sign, the seven
    sample angles estimate each ring's mean of zeta / |N| (a cosine); only when that estimate
    is too near zero to trust its sign (mean |cosine| under OUTWARD_TRUST) is the sum taken over
    every vertex.
    """
    surface, surfaces = layout.surface, len(layout.count)
    cosine = field.frame[..., 0] @ normal_field.trig_basis(normal_field.SAMPLE_ANGLES).T  # zeta (R, 7)
    lengths = np.linalg.norm(field.sample_normals, axis=-1)
    # a vanishing sample is on a stationary ring (replaced) or an examined one (summed in full)
    cosine = np.divide(cosine, lengths, out=np.zeros_like(cosine), where=lengths > 0.0)
    weighted = cosine.mean(axis=1) * signs.ring
    estimate = np.bincount(surface, weights=weighted * rings.radius, minlength=surfaces)
    threshold = OUTWARD_TRUST * np.bincount(surface, weights=rings.radius, minlength=surfaces)
    per_ring = ~signs.examined_surface
    unsure = per_ring & (np.abs(np.abs(estimate) - threshold) <= DECISION_MARGIN * threshold)
    for s in np.flatnonzero(unsure):  # as that surface's rows alone sum them
        rows = slice(layout.first[s], layout.first[s] + layout.count[s])
        estimate[s] = float(weighted[rows] @ rings.radius[rows])
        threshold[s] = OUTWARD_TRUST * rings.radius[rows].sum()
    trusted = per_ring & (np.abs(estimate) >= threshold)
    total = estimate
    if not trusted.all():
        untrusted = ~trusted[surface]
        if untrusted.all():  # every ring (the usual case where rings are examined): no gathers
            rows = np.arange(len(surface))
            outward = np.einsum("kmi,kmi->km", normals, positions - rings.centre[:, None, :])
        else:
            rows = np.flatnonzero(untrusted)
            outward = np.einsum("kmi,kmi->km", normals[rows], positions[rows] - rings.centre[rows, None, :])
        # a ring of one sign sums its vertices first; an examined ring's vertices take their own signs
        row_of = signs.row_of[rows]
        examined = row_of >= 0
        summed = outward.sum(axis=1) * signs.ring[rows]
        if examined.any():
            summed[examined] = np.einsum("km,km->k", outward[examined],
                                         signs.vertex[row_of[examined]]) * signs.ring[rows[examined]]
        total = np.where(trusted, estimate, np.bincount(surface[rows], weights=summed, minlength=surfaces))
        columns = positions.shape[1]
        close = np.flatnonzero(~trusted & (np.abs(total) <= DECISION_MARGIN * threshold * columns))
        for s in close:  # a sign this close to zero: summed as that surface's rows alone sum it
            mine = np.arange(layout.first[s], layout.first[s] + layout.count[s])
            block = np.einsum("kmi,kmi->km", normals[mine], positions[mine] - rings.centre[mine, None, :])
            total[s] = float(np.sum(block * signs.at(mine, columns)))
    return total < 0.0
