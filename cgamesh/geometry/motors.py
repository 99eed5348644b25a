"""Similarity motions through control circles: the splined centre, normal and radius of motor surfaces.

A circle is fixed by its centre c, its unit normal n and its radius r; the similarity
(TRS versor, paper section 11) Z = T(c) D(r) R with R e3 ~R = n carries the unit circle of the
e1e2 plane onto it. A motor surface carries its first control circle through every other one
by the motion Z(t) = T(c(t)) D(r(t)) R(t), whose three parts are splined separately in the
same parameter (docs/interpolation.md):

- the centre c(t): the curve kind's Euclidean spline of the control centres;
- the radius r(t): the same spline of the radii, its node slopes limited (Fritsch-Carlson) so
  the radius never leaves the range of the two radii of its span (linear on a linear span: the
  frustum of a skeleton's segment, as SWC files mean it);
- the normal n(t) = H(t) / |H(t)|, H the same spline of the control normals (a normalised
  vector spline: on a span it moves along the great circle joining its ends for `linear`),
  with a bump towards the direction of travel on spans whose end normals are more than a
  quarter turn apart, so that H never passes through zero on a half turn; R(t) turns with
  the angular velocity omega = n x dn/dt, the least rotation that keeps the normal on n(t)
  (no twist about n: a circle does not change when turned about its own axis).

Splines with knots (linear, kb, catmull_rom) place node i at t = i but take their tangents
per unit of "circle distance" (chord-length parametrisation): the span from circle i to
i + 1 has length Delta_i = max(|c_{i+1} - c_i|, |r_{i+1} - r_i|, (r_i + r_{i+1}) / 2 * angle(n_i, n_{i+1})),
the chord length of the centres wherever they move furthest (every tube along a path), so the
centre curve is the chord-length spline of the centres. Every component uses the same knots and
the same basis, so on both sides of a node the derivatives of (c, n, r) are one vector
scaled by Delta_{i-1} or Delta_i: the point velocity fields are parallel there and the
surface is tangent-continuous (C1 of its tangent planes) wherever the curve kind is C1.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cgamesh.errors import DegenerateGeometryError
from cgamesh.geometry.curves import split_parameter
from cgamesh.geometry.curves.bezier import Bezier, RationalBezier
from cgamesh.geometry.curves.kochanek_bartels import hermite
from cgamesh.geometry.objects import perpendicular_unit

PIECEWISE_KINDS = ("linear", "kb", "catmull_rom")
GLOBAL_KINDS = ("bezier", "rational_bezier")
# Spans shorter than this (local frame units: the controls lie in the unit ball) count as
# this long: the slopes of identical consecutive circles stay finite (and are zero).
MIN_SPAN = 1e-12
# Fritsch-Carlson: node slopes at most this multiple of each neighbouring secant keep a
# cubic Hermite span monotone.
MONOTONE_LIMIT = 3.0
# Normals within 60 degrees of the direction of travel orient by it (see ``orient_normals``).
PATH_COSINE = 0.5
# Centres moving less than this fraction of the radius between neighbours give no direction.
PATH_FRACTION = 1e-9


@dataclass(frozen=True)
class MotionState:
    """Circles and their rates at parameters t (A,): centre, normal (unit), radius and d/dt of
    each; ``normal_length`` |H| (A,) of the normal spline before normalisation (> 0)."""

    centre: np.ndarray
    normal: np.ndarray
    radius: np.ndarray
    d_centre: np.ndarray
    d_normal: np.ndarray
    d_radius: np.ndarray
    normal_length: np.ndarray

    @property
    def omega(self) -> np.ndarray:
        """Angular velocity (A, 3) of the least rotation keeping the plane normal on n(t)."""
        return np.cross(self.normal, self.d_normal)

    def velocity(self, points: np.ndarray) -> np.ndarray:
        """d x / dt (A, S, 3) of points x (A, S, 3) carried by the similarity motion:
        dc/dt + omega x (x - c) + (dr/dt / r) (x - c)."""
        offset = points - self.centre[:, None, :]
        return (self.d_centre[:, None, :] + np.cross(self.omega[:, None, :], offset)
                + (self.d_radius / self.radius)[:, None, None] * offset)


def orient_normals(centre: np.ndarray, normal: np.ndarray, radius: np.ndarray, closed: bool) -> np.ndarray:
    """The control normals (n, 3) with signs chosen so the motion turns the least relative to the path.

    A circle has no preferred side; its normal's sign decides which way the motion turns it.
    Node i keeps the side of the direction of travel d_i = c_{i+1} - c_{i-1} (one-sided at an
    open end) that node i - 1 has (the signs of n . d agree) when both normals are within 60
    degrees of their directions, so a tube that turns by more than a quarter turn between two
    nodes keeps its rings across the path (the shortest rotation would fold them back); else
    node i takes the side of node i - 1 (n_{i-1} . n_i >= 0, the shortest rotation). Node 0
    keeps the sign it was given.
    """
    count = len(centre)
    ahead = np.roll(centre, -1, axis=0) if closed else np.vstack([centre[1:], centre[-1:]])
    behind = np.roll(centre, 1, axis=0) if closed else np.vstack([centre[:1], centre[:-1]])
    direction = ahead - behind
    length = np.linalg.norm(direction, axis=1)
    reliable = length > PATH_FRACTION * radius
    unit = np.where(reliable[:, None], direction / np.where(reliable, length, 1.0)[:, None], 0.0)
    along = np.einsum("ni,ni->n", normal, unit)
    out = normal.copy()
    for i in range(1, count):
        if (reliable[i] and reliable[i - 1] and abs(along[i]) >= PATH_COSINE
                and abs(along[i - 1]) >= PATH_COSINE):
            flip = along[i] * np.dot(out[i - 1], unit[i - 1]) < 0.0
        else:
            flip = np.dot(out[i - 1], out[i]) < 0.0
        if flip:
            out[i] = -out[i]
    return out


def span_lengths(centre: np.ndarray, normal: np.ndarray, radius: np.ndarray, closed: bool) -> np.ndarray:
    """Delta_i (S,): the circle distance from control i to i + 1 (wrapping when closed)."""
    nxt = (lambda a: np.roll(a, -1, axis=0)) if closed else (lambda a: a[1:])
    here = (lambda a: a) if closed else (lambda a: a[:-1])
    cosine = np.clip(np.einsum("ni,ni->n", here(normal), nxt(normal)), -1.0, 1.0)
    # angle from the cross product's length near 0 and pi (arccos loses half the digits there)
    sine = np.linalg.norm(np.cross(here(normal), nxt(normal)), axis=1)
    angle = np.arctan2(sine, cosine)
    # the largest of the three distances, not their sum: a tube whose centres move further than
    # its radii change and its rings turn (every tube along a path) is then parametrised by the
    # chord length of its centres alone, so its centre spline is the chord-length spline of the
    # centres and its tangent at a node is the bisector of the unit chords
    length = np.maximum(np.maximum(np.linalg.norm(nxt(centre) - here(centre), axis=1),
                                   np.abs(nxt(radius) - here(radius))),
                        0.5 * (here(radius) + nxt(radius)) * angle)
    return np.maximum(length, MIN_SPAN)


def _kb_slopes(values: np.ndarray, spans: np.ndarray, closed: bool, tension: float, bias: float,
               continuity: float) -> tuple[np.ndarray, np.ndarray]:
    """Outgoing and incoming node slopes (n, k) per unit knot (Kochanek-Bartels weights of the
    secant slopes; an open end repeats its one secant)."""
    nxt = np.roll(values, -1, axis=0) if closed else values[1:]
    secant = (nxt - (values if closed else values[:-1])) / spans[:, None]  # (S, k)
    if closed:
        before, after = np.roll(secant, 1, axis=0), secant
    else:
        before = np.vstack([secant[:1], secant])
        after = np.vstack([secant, secant[-1:]])
    t, b, c = tension, bias, continuity
    out = (1 - t) * (1 + b) * (1 + c) / 2 * before + (1 - t) * (1 - b) * (1 - c) / 2 * after
    into = (1 - t) * (1 + b) * (1 - c) / 2 * before + (1 - t) * (1 - b) * (1 + c) / 2 * after
    return out, into


def _monotone(slopes: np.ndarray, values: np.ndarray, spans: np.ndarray, closed: bool) -> np.ndarray:
    """Node slopes (n,) of a scalar limited so every cubic Hermite span stays between its end
    values: zero at a local extremum, else of the secants' sign and at most MONOTONE_LIMIT times
    the smaller neighbouring secant (a sufficient condition of Fritsch and Carlson)."""
    nxt = np.roll(values, -1) if closed else values[1:]
    secant = (nxt - (values if closed else values[:-1])) / spans
    if closed:
        before, after = np.roll(secant, 1), secant
    else:
        before, after = np.concatenate([secant[:1], secant]), np.concatenate([secant, secant[-1:]])
    same_sign = before * after > 0.0
    bound = MONOTONE_LIMIT * np.minimum(np.abs(before), np.abs(after))
    limited = np.sign(after) * np.minimum(np.abs(slopes) * (np.sign(slopes) == np.sign(after)), bound)
    return np.where(same_sign, limited, 0.0)


@dataclass(frozen=True)
class MotionSpline:
    """The splined similarity parameters of a motor surface, in its local frame.

    nodes (n, 7): centre, oriented unit normal, radius of each control. ``kind`` is the
    scene's curve kind. Piecewise kinds: spans (S,), slopes_out / slopes_in (n, 7) per unit
    knot, bumps (S, 3) the direction (times weight) the normal is pushed to mid-span.
    Global kinds (Bezier): ``weights`` of the rational form (ones for a plain Bezier).
    """

    kind: str
    closed: bool
    nodes: np.ndarray
    spans: np.ndarray | None = None
    slopes_out: np.ndarray | None = None
    slopes_in: np.ndarray | None = None
    bumps: np.ndarray | None = None
    weights: tuple[float, ...] | None = None

    @classmethod
    def through(cls, centre: np.ndarray, normal: np.ndarray, radius: np.ndarray, kind: str,
                closed: bool = False, tension: float = 0.0, bias: float = 0.0, continuity: float = 0.0,
                weights: tuple[float, ...] | None = None, align: bool = True) -> "MotionSpline":
        """The spline through control circles (centre (n, 3), normal (n, 3), radius (n,))."""
        centre = np.asarray(centre, dtype=np.float64)
        normal = np.asarray(normal, dtype=np.float64)
        normal = normal / np.linalg.norm(normal, axis=1, keepdims=True)
        radius = np.asarray(radius, dtype=np.float64)
        if align:
            normal = orient_normals(centre, normal, radius, closed)
        nodes = np.hstack([centre, normal, radius[:, None]])
        if kind in GLOBAL_KINDS:
            return cls(kind, False, nodes, weights=tuple(weights) if weights is not None else (1.0,) * len(nodes))
        spans = span_lengths(centre, normal, radius, closed)
        if kind == "linear":
            slopes_out = slopes_in = None
        else:
            if kind == "catmull_rom":
                tension = bias = continuity = 0.0
            slopes_out, slopes_in = _kb_slopes(nodes, spans, closed, tension, bias, continuity)
            slopes_out[:, 6] = _monotone(slopes_out[:, 6], nodes[:, 6], spans, closed)
            slopes_in[:, 6] = _monotone(slopes_in[:, 6], nodes[:, 6], spans, closed)
        return cls(kind, closed, nodes, spans, slopes_out, slopes_in, _bumps(centre, normal, closed))

    @property
    def segment_count(self) -> int:
        if self.kind in GLOBAL_KINDS:
            return 1
        return len(self.nodes) if self.closed else len(self.nodes) - 1

    def _values(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The 7 spline components and their d/dt (A, 7) at t, before the normal is normalised."""
        if self.kind in GLOBAL_KINDS:
            curve = Bezier(len(self.nodes)) if self.kind == "bezier" else RationalBezier(self.weights)
            return curve.basis(t).evaluate(self.nodes)
        segment, s = split_parameter(t, self.segment_count)
        i, j = segment, (segment + 1) % len(self.nodes)
        start, end = self.nodes[i], self.nodes[j]
        if self.kind == "linear":
            value = (1.0 - s)[:, None] * start + s[:, None] * end
            rate = end - start
        else:
            h, dh = hermite(s)
            span = self.spans[segment][:, None]
            terms = np.stack([start, span * self.slopes_out[i], end, span * self.slopes_in[j]], axis=1)
            value = np.einsum("ah,ahk->ak", h, terms)
            rate = np.einsum("ah,ahk->ak", dh, terms)
        # The bump 16 s^2 (1 - s)^2 w: zero with zero slope at both ends, so the nodes and
        # the slopes there are untouched (C1 kept); 1 at mid-span.
        bump = self.bumps[segment]
        value[:, 3:6] += (16.0 * s * s * (1.0 - s) ** 2)[:, None] * bump
        rate[:, 3:6] += (32.0 * s * (1.0 - s) * (1.0 - 2.0 * s))[:, None] * bump
        return value, rate

    def evaluate(self, t: np.ndarray) -> MotionState:
        """Centre, unit normal, radius and their d/dt at parameters t (A,) in [0, segment_count]."""
        t = np.asarray(t, dtype=np.float64)
        value, rate = self._values(t)
        h, dh = value[:, 3:6], rate[:, 3:6]
        length = np.linalg.norm(h, axis=1)
        normal = h / length[:, None]
        d_normal = (dh - normal * np.einsum("ai,ai->a", normal, dh)[:, None]) / length[:, None]
        return MotionState(value[:, :3], normal, value[:, 6], rate[:, :3], d_normal, rate[:, 6], length)

    def check_normals(self, name: str, samples_per_segment: int) -> None:
        """Raise where the normal spline comes near zero (the plane's direction is lost there)."""
        t = np.linspace(0.0, self.segment_count, samples_per_segment * self.segment_count + 1)
        value, _ = self._values(t)
        error = lost_plane(name, t, np.linalg.norm(value[:, 3:6], axis=1), np.all(np.isfinite(value), axis=1),
                           self.segment_count)
        if error is not None:
            raise error


def lost_plane(name: str, t: np.ndarray, length: np.ndarray, finite: np.ndarray,
               segment_count: int) -> DegenerateGeometryError | None:
    """The error of a motor surface whose normal spline, of lengths (A,) at parameters t (A,)
    (``finite``: whether the spline's values there are), comes near zero; None where it does not."""
    bad = ~(length >= MIN_NORMAL_LENGTH) | ~finite
    if not np.any(bad):
        return None
    worst = int(np.argmin(np.where(np.isfinite(length), length, -np.inf)))
    segment = min(int(t[worst]), segment_count - 1)
    return DegenerateGeometryError(
        f"surface '{name}': the motor interpolation loses the circle's plane at segment {segment}, "
        f"alpha = {t[worst] - segment:.6g} (the control normals cancel there; turn fewer degrees "
        "between neighbouring controls, or add a control)"
    )


# The normal spline H(t) must stay at least this long (its nodes are unit vectors).
MIN_NORMAL_LENGTH = 1e-3


def _bumps(centre: np.ndarray, normal: np.ndarray, closed: bool) -> np.ndarray:
    """Per span (S, 3): lambda w, pushing the normal spline towards the direction of travel w
    (the chord between the centres, made perpendicular to the first normal; any perpendicular
    when the chord runs along it) by lambda = max(0, -n_i . n_{i+1})^2: nothing on spans
    turning a quarter turn or less, the whole of w on a half turn, where the normalised
    spline would otherwise pass through zero."""
    nxt = (lambda a: np.roll(a, -1, axis=0)) if closed else (lambda a: a[1:])
    here = (lambda a: a) if closed else (lambda a: a[:-1])
    start, end = here(normal), nxt(normal)
    weight = np.maximum(0.0, -np.einsum("si,si->s", start, end)) ** 2
    chord = nxt(centre) - here(centre)
    chord = chord - start * np.einsum("si,si->s", chord, start)[:, None]
    length = np.linalg.norm(chord, axis=1)
    fallback = perpendicular_unit(start)
    usable = length > 1e-9 * np.maximum(1.0, np.linalg.norm(nxt(centre) - here(centre), axis=1))
    direction = np.where(usable[:, None], chord / np.where(usable, length, 1.0)[:, None], fallback)
    return weight[:, None] * direction
