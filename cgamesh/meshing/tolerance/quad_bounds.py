"""The tolerance bound of one quad of the mesh, per cell of the dense sampling, and the spacing meeting it.

Per cell of a surface's dense sampling (cgamesh.meshing.tolerance.derivative_bounds) the bound
terms of its members (``Cells``: for circles A >= |d2x/dt2|, B >= |d2x/dt dtheta|, the radius,
|n'|, |n''| and the parts the narrower bounds need; for ribbons |a''|, |b''|, |(b - a)'|), and
per interval of rings the bound E of its quads from the maxima of those terms over the cells it
touches (``circle_error``, ``ribbon_error``: the smallest of the lemma's bound, the bound without
the twist's tangential part and, for circles, the bound by the error normal to the surface), and
per cell the spacing h whose bound meets a tolerance (``circle_spacing``, ``ribbon_spacing``).
The planner (cgamesh.meshing.tolerance.tolerance_plan) chooses the counts and places the rings
from these; docs/tolerance.md proves the bounds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cgamesh.geometry.surface import EvolvedSurface
from cgamesh.meshing import ring_frames
from cgamesh.meshing.tolerance.derivative_bounds import cell_derivatives, lengths
from cgamesh.meshing.tolerance.normal_projection import (full_second_derivatives, normal_projection_error,
                                                         normal_projection_spacing, spin_bounds)
from cgamesh.meshing.tolerance.ribbon_twist import ribbon_twist_error, ribbon_twist_spacing, ribbon_twist_terms

# Angles at which the largest |d2x/dt2| around a circle is looked for (plus a margin between).
ANGLES = 32


@dataclass(frozen=True)
class Cells:
    """Per-cell bound terms (segments, cells) of a surface's members, in world units."""

    cells: int
    terms: dict
    closed_rate: float  # angular rate of a closed loop's holonomy correction, about n

    @property
    def segments(self) -> int:
        return next(iter(self.terms.values())).shape[0]


def circle_cells(surface: EvolvedSurface, cells: int, closed: bool, members: tuple) -> Cells:
    """Per cell: A >= |d2x/dt2| and B >= |d2x/dt dtheta| for x = c + r (cos theta u + sin theta v)
    in the sampled transported frame (u, v), their vectors combined (no triangle inequality
    between the centre's, the radius' and the frame's parts), the largest radius, |n'| and |n''|.
    members: the circles' (centre, normal, radius) at ``segment_samples(segments, cells)``, segment-major."""
    centre, normal, radius = members
    u, v = ring_frames.transported_axes(normal, np.arange(len(normal)))  # the samples as the rings of one surface
    shape = (surface.segment_count, cells + 1)
    scale = surface.frame.scale
    grid = lambda values: values.reshape(shape + values.shape[1:])  # noqa: E731
    # One call on the members side by side (fewer, larger array operations; the same bits).
    bounds = cell_derivatives(grid(np.concatenate(
        [centre, radius[:, None] * u, radius[:, None] * v, radius[:, None], normal], axis=1)))
    path, cosine, sine = bounds.columns(0, 3), bounds.columns(3, 6), bounds.columns(6, 9)
    r0, r1, _ = bounds.columns(9, 10).norms()
    _, n1, n2 = bounds.columns(10, 13).norms()
    # max over theta of |G| = |a + B cos theta + C sin theta|: on ANGLES angles, plus the most
    # g = |G|^2 can grow from the nearest of them to a maximum between (where g' = 0):
    # (spacing^2 / 8) max |g''|, with g'' = 2 |G'|^2 + 2 G . G'' and |G'|, |G''| <= reach.
    a, b, c = path.second, cosine.second, sine.second
    on_circle = _on_circle(a, b, c, 2.0 * np.pi * np.arange(ANGLES) / ANGLES)
    reach = np.sqrt(lengths(b) ** 2 + lengths(c) ** 2)
    curvature = 4.0 * reach * reach + 2.0 * lengths(a) * reach  # >= max |g''|
    spacing = 2.0 * np.pi / ANGLES
    largest = np.sqrt(on_circle.max(axis=-1) ** 2 + spacing * spacing / 8.0 * curvature)
    along = (largest + lengths(path.second_radius)
             + np.hypot(lengths(cosine.second_radius), lengths(sine.second_radius)))
    # max over theta of |-sin theta B1 + cos theta C1|: the larger singular value of [B1 C1].
    b1, c1 = cosine.first, sine.first
    bb, cc, bc = np.sum(b1 * b1, -1), np.sum(c1 * c1, -1), np.sum(b1 * c1, -1)
    largest = np.sqrt(0.5 * (bb + cc) + np.sqrt(0.25 * (bb - cc) ** 2 + bc * bc))
    twist = largest + np.hypot(lengths(cosine.first_radius), lengths(sine.first_radius))
    # The frame's part of d2x/dt2 alone, max over theta of |(r u)'' cos + (r v)'' sin|: the larger
    # singular value of [(r u)'', (r v)''] (the twist's change along t, for the normal twist bound).
    b2, c2 = cosine.second, sine.second
    bb, cc, bc = np.sum(b2 * b2, -1), np.sum(c2 * c2, -1), np.sum(b2 * c2, -1)
    turning = (np.sqrt(0.5 * (bb + cc) + np.sqrt(0.25 * (bb - cc) ** 2 + bc * bc))
               + np.hypot(lengths(cosine.second_radius), lengths(sine.second_radius)))
    axial, across = _axial_speed(grid(normal), path, n1)
    sampled = grid(radius)
    least = np.maximum(np.minimum(sampled[:, :-1], sampled[:, 1:]) - 0.5 * r1 / cells, 0.0)  # <= r in the cell
    terms = dict(A=scale * along, B=scale * twist, Rm=scale * r0, N1=n1, N2=n2, Ar=scale * turning,
                 R1=scale * r1, Cx=scale * across, negCn=-scale * axial, negRmin=-scale * least)
    return Cells(cells, terms, _turn(u, normal) / surface.segment_count if closed else 0.0)


def _on_circle(a: np.ndarray, b: np.ndarray, c: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """|a + cos(angle) b + sin(angle) c| (..., angles) of vectors (..., 3): the terms formed one
    component at a time on contiguous (..., angles) arrays rather than (..., angles, 3) ones, the
    squares summed x, y, z in order as ``lengths`` (np.sum of three numbers) sums them: the same
    bits at a third of the time."""
    cosine, sine = np.cos(angles), np.sin(angles)
    squared = None
    for k in range(3):
        term = a[..., k, None] + cosine * b[..., k, None]
        term += sine * c[..., k, None]
        term *= term
        squared = term if squared is None else squared + term
    return np.sqrt(squared, out=squared)


def _axial_speed(normal: np.ndarray, path, n1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per cell: a lower bound of |n . c'| and an upper bound of |n x c'| (the centre's speed along
    and across the circle's axis). In a cell, c' is within its radius of the divided difference D1
    and n within delta |n'| of its value at the cell's start."""
    start, d1 = normal[:, :-1], path.first
    spread = lengths(path.first_radius)
    delta = 1.0 / d1.shape[1]
    slack = delta * n1 * (lengths(d1) + spread) + spread
    along = np.abs(np.sum(start * d1, axis=-1))
    across = lengths(np.cross(start, d1))
    return np.maximum(along - slack, 0.0), across + slack


def holonomy(normal: np.ndarray, t: np.ndarray) -> float:
    """|angle| by which transport around a closed loop of these normals turns its frame."""
    u, _ = ring_frames.transported_frames(normal, False, t)
    return _turn(u, normal)


def _turn(u: np.ndarray, normal: np.ndarray) -> float:
    """|angle| between the first and the last of transported axes u (the loop's holonomy)."""
    return abs(float(ring_frames.holonomy(u, normal, np.array([0]), np.array([len(u) - 1]))[0]))


def ribbon_cells(surface: EvolvedSurface, cells: int, members: tuple) -> Cells:
    a, b = members  # the end points at segment_samples(segments, cells), segment-major
    shape = (surface.segment_count, cells + 1, 3)
    scale = surface.frame.scale
    # One call on the members side by side, as for circles (the same bits as three).
    bounds = cell_derivatives(np.concatenate([a, b, b - a], axis=1).reshape(shape[:2] + (9,)))
    ends, other, across = bounds.columns(0, 3), bounds.columns(3, 6), bounds.columns(6, 9)
    _, _, a2 = ends.norms()
    _, _, b2 = other.norms()
    _, d1, _ = across.norms()
    terms = dict(A=scale * np.maximum(a2, b2), B=scale * d1)
    terms.update(ribbon_twist_terms(ends, other, across, (b - a).reshape(shape), scale))
    return Cells(cells, terms, 0.0)


def circle_error(terms: dict, h, around, rate: float, wide: dict | None = None):
    """E for intervals of length h with the given term maxima and M = around (broadcasting).

    The mesh's frame on an interval is the smallest rotation from the first ring's plane,
    which spins about n relative to the sampled transport by psi' (at most turned |n'| / q,
    plus a closed loop's holonomy rate): x(t, theta) = x_G(t, theta + psi(t)) adds
    2 B psi' + r (psi'^2 + |psi''|) to A and r psi' to B. With ``wide`` (the maxima over each
    interval widened within its segment), the bound by the error normal to the surface
    (cgamesh.meshing.tolerance.normal_projection) is a third one: E is the smallest."""
    n1, rm = terms["N1"], terms["Rm"]
    turned = h * n1  # bounds |n(t) - n(t_k)| over the interval
    spin, spin_rate = spin_bounds(n1, terms["N2"], turned, rate)
    a, b = full_second_derivatives(terms, spin, spin_rate)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        sag = rm * (1.0 - np.cos(np.pi / around))
        error = sag + a * h * h / 8.0 + b * h * np.sin(np.pi / around) / 2.0
        error = np.minimum(error, sag + normal_twist_error(terms, h, around, a, b, spin, spin_rate))
    if wide is not None:  # the third bound, on the same mesh frame
        error = np.minimum(error, normal_projection_error(terms, wide, h, around, rate, (spin, spin_rate, a, b)))
    return np.where(turned < 1.0, error, np.inf)


def normal_twist_error(terms: dict, h, around, a, b, spin, spin_rate):
    """The bound of the quad's error without the twist's tangential part (see _normal_twist_terms)."""
    square, linear, valid = _normal_twist_terms(terms, around, a, b, spin, spin_rate)
    with np.errstate(divide="ignore", invalid="ignore"):
        valid = valid & (h * terms["R1"] <= -terms["negRmin"])  # h |gamma_theta| <= 1
    return np.where(valid, square * h * h + linear * h, np.inf)


def _normal_twist_terms(terms: dict, around, a, b, spin, spin_rate):
    """(square, linear, valid): A^ h^2 / 8 + B^ h k / 4 + C^ k^2 / 8 = square h^2 + linear h for the
    map g = P(Phi), where Phi moves each triangle's points by h k gamma lambda_i lambda_j (the
    bubble of its diagonal, zero at the vertices; it stays in the quad while k |gamma_t| <= 1 and
    h |gamma_theta| <= 1), so that the twist of g is P_t theta - gamma_t P_t - gamma_theta P_theta:
    the shear along the ring's axis and around it removed (docs/tolerance.md, "The twist's
    normal part"). a, b: the full bounds of |P_tt| and |P_t theta| / |L'|; spin, spin_rate: the
    mesh frame's |psi'|, |psi''|. valid is False where the centre does not move along the axis
    enough (or the radius changes too fast) for the shear to be removed."""
    rm, n1 = terms["Rm"], terms["N1"]
    k = 2.0 * np.pi / around
    chord = 2.0 * np.sin(np.pi / around) / k  # |L'|
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        rn1, rspin = rm * n1, rm * spin  # each computed once (the same bits as in each term)
        axial = -terms["negCn"] - rn1  # <= |n . P_t|
        gamma = rn1 / axial * chord  # >= |gamma_t|
        shear = terms["R1"] / -terms["negRmin"]  # >= |gamma_theta| = |r'| / r
        tilt = np.minimum(1.0, (terms["Cx"] + terms["R1"] + rspin) / axial)  # >= |n x P_t| / |P_t|
        rest = rspin + rn1 * tilt  # >= |P_t theta - gamma . J| / |L'| where gamma is chosen
        turning = terms["Ar"] + 2.0 * terms["B"] * spin + rm * (spin * spin + spin_rate)  # >= |(r F)''|
        twist = chord * b  # >= |P_t theta|
        reach = k * gamma
        lift = 1.0 + reach
        a_hat = lift ** 2 * a + 2.0 * lift * k * shear * twist
        # B^ = B0 + h B1 (B0: the twist left at the quad's middle; B1: its change over the quad and
        # what Phi's slopes add); C^ = h C1 + h^2 C2.
        b0 = chord * rest + 1.5 * k * gamma * twist
        b1 = (0.5 * chord * turning + 0.5 * gamma * a + 1.5 * shear * twist + 2.0 * k * gamma * shear * twist
              + lift * gamma * a)
        c1 = 2.0 * gamma * twist
        c2 = gamma * gamma * a + 2.0 * gamma * shear * twist
        square = a_hat / 8.0 + k / 4.0 * b1 + k * k / 8.0 * c2
        linear = k / 4.0 * b0 + k * k / 8.0 * c1
        valid = (axial > 0.0) & (reach <= 1.0) & np.isfinite(shear) & np.isfinite(square) & np.isfinite(linear)
    return square, linear, valid


def ribbon_error(terms: dict, h, across, rate: float = 0.0):
    """E of ribbon quads: the lemma's bound, or the one without the twist's tangential part
    (cgamesh.meshing.tolerance.ribbon_twist) where that is smaller."""
    full = terms["A"] * h * h / 8.0 + terms["B"] * h / (4.0 * (across - 1))
    return np.minimum(full, ribbon_twist_error(terms, h, across))


def circle_spacing(terms: dict, around, tolerance: float, rate: float):
    """Per cell (and candidate M) the spacing h meeting the tolerance, leading terms only."""
    rm = terms["Rm"]
    full = terms["A"] + 2.0 * terms["B"] * rate + rm * rate * rate
    twist = terms["B"] + rm * rate
    c = tolerance - rm * (1.0 - np.cos(np.pi / around))
    spacing = _root(full / 8.0, twist * np.sin(np.pi / around) / 2.0, c)
    # The normal twist bound with its leading terms (spin = rate, no spin rate); its condition
    # h |gamma_theta| <= 1 is checked when the rings are bounded.
    square, linear, valid = _normal_twist_terms(terms, around, full, twist, rate, 0.0)
    normal = np.where(valid, _root(np.where(valid, square, 1.0), np.where(valid, linear, 1.0), c), 0.0)
    projected = normal_projection_spacing(terms, around, tolerance, rate, _root)
    return np.maximum(np.maximum(spacing, normal), projected)


def ribbon_spacing(terms: dict, across, tolerance: float, rate: float = 0.0):
    c = np.full(np.shape(terms["A"]), tolerance)
    full = _root(terms["A"] / 8.0, terms["B"] / (4.0 * (across - 1)), c)
    return np.maximum(full, ribbon_twist_spacing(terms, across, c, _root))


def _root(a, b, c):
    """Positive root h of a h^2 + b h = c (0 where c <= 0, inf where a = b = 0)."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        h = 2.0 * c / (b + np.sqrt(b * b + 4.0 * a * np.maximum(c, 0.0)))
    # NaN (0 / 0, inf / inf) is inf; a, b >= 0 (bounds), so h is never -inf where c > 0
    return np.where(c > 0.0, np.where(np.isnan(h), np.inf, h), 0.0)
