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

One implementation for any number of motions: ``Motions`` builds and evaluates M motions (nodes
concatenated, ``MotionNodes``; each with its own kind and parameters) as arrays, at rows (motion,
t). A surface's ``MotionSpline`` is a batch of one; the batched passes run the same code on more.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np

from cgamesh.errors import DegenerateGeometryError
from cgamesh.geometry.curves import split_parameter
from cgamesh.geometry.curves.bezier import bernstein, bernstein_derivative, rational_weights
from cgamesh.geometry.curves.kochanek_bartels import hermite
from cgamesh.geometry.objects import perpendicular_unit

PIECEWISE_KINDS = ("linear", "kb", "catmull_rom")
GLOBAL_KINDS = ("bezier", "rational_bezier")
KINDS = PIECEWISE_KINDS + GLOBAL_KINDS  # a motion's ``kind`` indexes this
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


# The normal spline H(t) must stay at least this long (its nodes are unit vectors).
MIN_NORMAL_LENGTH = 1e-3
# The largest |h10| and |h11| of the cubic Hermite basis on [0, 1] (at s = 1/3 and 2/3).
HERMITE_SLOPE_BASIS_MAX = 4.0 / 27.0
# A span is certified when the lower bound of |H| exceeds MIN_NORMAL_LENGTH by this factor.
CERTIFY_FACTOR = 2.0


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

    @classmethod
    def of(cls, value: np.ndarray, rate: np.ndarray) -> "MotionState":
        """The state from the 7 spline components (A, 7) and their d/dt: the normal is H / |H|."""
        h, dh = value[:, 3:6], rate[:, 3:6]
        length = np.linalg.norm(h, axis=1)
        normal = h / length[:, None]
        d_normal = (dh - normal * np.einsum("ai,ai->a", normal, dh)[:, None]) / length[:, None]
        return cls(value[:, :3], normal, value[:, 6], rate[:, :3], d_normal, rate[:, 6], length)


@dataclass(frozen=True)
class MotionNodes:
    """The nodes of M motions, concatenated: ``first`` (M,) index of each motion's first node,
    ``count`` (M,) its nodes (>= 2), ``closed`` (M,) bool (None: all open). A motion's spans join
    its consecutive nodes (and, closed, its last node to its first); spans are numbered motion
    after motion. The index arrays derived from them are made once (``cached_property``)."""

    first: np.ndarray
    count: np.ndarray
    closed: np.ndarray | None = None

    @staticmethod
    @lru_cache(maxsize=1024)
    def one(count: int, closed: bool = False) -> "MotionNodes":
        """The nodes of one motion, made once per shape: its index arrays are derived once."""
        return MotionNodes(np.zeros(1, dtype=np.int64), np.array([count]), np.array([closed]))

    @cached_property
    def is_closed(self) -> np.ndarray:
        return np.zeros(len(self.count), dtype=bool) if self.closed is None else np.asarray(self.closed, dtype=bool)

    @cached_property
    def motion(self) -> np.ndarray:
        """The motion of every node (N,)."""
        return np.repeat(np.arange(len(self.count)), self.count)

    @cached_property
    def local(self) -> np.ndarray:
        """Each node's index within its motion (N,)."""
        return np.arange(int(self.count.sum())) - np.repeat(self.first, self.count)

    @cached_property
    def is_last(self) -> np.ndarray:
        return self.local == np.repeat(self.count - 1, self.count)

    @cached_property
    def span_count(self) -> np.ndarray:
        """Spans of every motion (M,): one per node when closed, else one fewer."""
        return self.count - 1 + self.is_closed

    @cached_property
    def span_first(self) -> np.ndarray:
        """Index of each motion's first span in the span arrays (M,)."""
        return np.concatenate([[0], np.cumsum(self.span_count)[:-1]]).astype(np.int64)

    @cached_property
    def span_start(self) -> np.ndarray:
        """Node at the start of every span (S,)."""
        return np.flatnonzero(~self.is_last | self.is_closed[self.motion])

    @cached_property
    def span_end(self) -> np.ndarray:
        """Node at the end of every span (S,): the next one, or the first where a closed motion wraps."""
        i = self.span_start
        return np.where(self.is_last[i], self.first[self.motion[i]], i + 1)

    @cached_property
    def node_spans(self) -> tuple[np.ndarray, np.ndarray]:
        """The span before and after every node (N,); an open end's missing one repeats the other."""
        after = self.span_first[self.motion] + self.local
        closed = self.is_closed[self.motion]
        last_span = (self.span_first + self.span_count - 1)[self.motion]
        before = np.where(self.local == 0, np.where(closed, last_span, after), after - 1)
        after = np.where(self.is_last & ~closed, before, after)
        return before, after

    @cached_property
    def neighbours(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The node after, before (at an open end: the node itself) and preceding (N,) every node."""
        before, after = self.node_spans
        return self.span_end[after], self.span_start[before], np.maximum(np.arange(len(self.motion)) - 1, 0)


def orient_normals(centre: np.ndarray, normal: np.ndarray, radius: np.ndarray, nodes: MotionNodes) -> np.ndarray:
    """The control normals (N, 3) with signs chosen so each motion turns the least relative to its path.

    A circle has no preferred side; its normal's sign decides which way the motion turns it.
    Node i keeps the side of the direction of travel d_i = c_{i+1} - c_{i-1} (one-sided at an
    open end) that node i - 1 has (the signs of n . d agree) when both normals are within 60
    degrees of their directions, so a tube that turns by more than a quarter turn between two
    nodes keeps its rings across the path (the shortest rotation would fold them back); else
    node i takes the side of node i - 1 (n_{i-1} . n_i >= 0, the shortest rotation). Node 0
    keeps the sign it was given.

    The choice is sequential (node i's sign depends on node i - 1's): node i flips when
    s_{i-1} q_i < 0, with q_i = (n_i . d_i)(n_{i-1} . d_{i-1}) (both near the path) or
    n_{i-1} . n_i, so s_i is the product of sign(q_k) since the motion's start or the last
    q_k = 0 (which resets the sign to +1): a segmented parity.
    """
    ahead, behind, previous = nodes.neighbours
    direction = centre[ahead] - centre[behind]
    length = np.linalg.norm(direction, axis=1)
    reliable = length > PATH_FRACTION * radius
    unit = np.where(reliable[:, None], direction / np.where(reliable, length, 1.0)[:, None], 0.0)
    along = np.einsum("ni,ni->n", normal, unit)
    near_path = reliable & (np.abs(along) >= PATH_COSINE)
    case_path = near_path & near_path[previous]
    q = np.where(case_path, along * along[previous], np.einsum("ni,ni->n", normal[previous], normal))
    reset = (nodes.local == 0) | (q == 0.0)
    count = np.cumsum((q < 0.0) & ~reset)
    start = np.maximum.accumulate(np.where(reset, np.arange(len(q)), 0))
    sign = 1.0 - 2.0 * ((count - count[start]) % 2)  # the negatives after the reset (its own is 0)
    return normal * sign[:, None]


def span_lengths(centre: np.ndarray, normal: np.ndarray, radius: np.ndarray, i: np.ndarray,
                 j: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Delta (S,): the circle distance from node i (S,) to node j (S,), and the cosine (S,) of
    the angle between their normals."""
    cosine = np.clip(np.einsum("ni,ni->n", normal[i], normal[j]), -1.0, 1.0)
    # angle from the cross product's length near 0 and pi (arccos loses half the digits there)
    sine = np.linalg.norm(np.cross(normal[i], normal[j]), axis=1)
    angle = np.arctan2(sine, cosine)
    # the largest of the three distances, not their sum: a tube whose centres move further than
    # its radii change and its rings turn (every tube along a path) is then parametrised by the
    # chord length of its centres alone, so its centre spline is the chord-length spline of the
    # centres and its tangent at a node is the bisector of the unit chords
    length = np.maximum(np.maximum(np.linalg.norm(centre[j] - centre[i], axis=1), np.abs(radius[j] - radius[i])),
                        0.5 * (radius[i] + radius[j]) * angle)
    return np.maximum(length, MIN_SPAN), cosine


def monotone_slopes(slopes: np.ndarray, before: np.ndarray, after: np.ndarray) -> np.ndarray:
    """Node slopes (N,) of a scalar limited so every cubic Hermite span stays between its end
    values, from each node's neighbouring secants: zero at a local extremum, else of the secants'
    sign and at most MONOTONE_LIMIT times the smaller one (a sufficient condition of Fritsch and
    Carlson)."""
    same_sign = before * after > 0.0
    bound = MONOTONE_LIMIT * np.minimum(np.abs(before), np.abs(after))
    limited = np.sign(after) * np.minimum(np.abs(slopes) * (np.sign(slopes) == np.sign(after)), bound)
    return np.where(same_sign, limited, 0.0)


def _bumps(centre_i: np.ndarray, centre_j: np.ndarray, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    """Per span (S, 3): lambda w, pushing the normal spline towards the direction of travel w
    (the chord between the centres, made perpendicular to the first normal; any perpendicular
    when the chord runs along it) by lambda = max(0, -n_i . n_{i+1})^2: nothing on spans
    turning a quarter turn or less, the whole of w on a half turn, where the normalised
    spline would otherwise pass through zero."""
    weight = np.maximum(0.0, -np.einsum("si,si->s", start, end)) ** 2
    chord = centre_j - centre_i
    chord = chord - start * np.einsum("si,si->s", chord, start)[:, None]
    length = np.linalg.norm(chord, axis=1)
    usable = length > 1e-9 * np.maximum(1.0, np.linalg.norm(centre_j - centre_i, axis=1))
    direction = chord / np.where(usable, length, 1.0)[:, None]
    if not usable.all():  # the fallback row by row, made only where it is taken
        direction[~usable] = perpendicular_unit(start[~usable])
    return weight[:, None] * direction


@dataclass(frozen=True)
class Motions:
    """The splined similarity motions of M surfaces (or chains), each in its own local frame.

    One implementation for any M: a single surface is a batch of one (``MotionSpline``).
    ``kind`` (M,) indices into KINDS (a Bezier curve is open, whatever ``nodes.closed`` says);
    ``values`` (N, 7) centre, oriented unit normal, radius of every node; ``weights`` (N,) the
    rational Bezier weights (ones elsewhere); ``spans`` (S,) the knot lengths Delta and ``cosine``
    (S,) of the angle between each span's end normals; ``slopes_out`` / ``slopes_in`` (N, 7) per
    unit knot (zero for linear and the Bezier kinds); ``bumps`` (S, 3) the direction (times
    weight) the normal is pushed to mid-span. The Bezier kinds use none of the span arrays.
    """

    nodes: MotionNodes
    kind: np.ndarray
    values: np.ndarray
    weights: np.ndarray
    spans: np.ndarray
    cosine: np.ndarray
    slopes_out: np.ndarray
    slopes_in: np.ndarray
    bumps: np.ndarray

    @classmethod
    def through(cls, centre: np.ndarray, normal: np.ndarray, radius: np.ndarray, nodes: MotionNodes,
                kind="catmull_rom", tension=0.0, bias=0.0, continuity=0.0, weights=None, align=True) -> "Motions":
        """The motions through control circles (centre (N, 3), normal (N, 3), radius (N,)), the
        nodes of motion m being first[m] ... first[m] + count[m] - 1, motion after motion. kind,
        tension, bias, continuity (kb), align: one for all or (M,); weights (N,) or None (ones)."""
        centre = np.asarray(centre, dtype=np.float64)
        normal = np.asarray(normal, dtype=np.float64)
        normal = normal / np.linalg.norm(normal, axis=1, keepdims=True)
        radius = np.asarray(radius, dtype=np.float64)
        motion = nodes.motion
        names, code = ([kind], 0) if isinstance(kind, str) else np.unique(kind, return_inverse=True)  # one or (M,)
        kind = np.resize(np.array([KINDS.index(name) for name in names])[code], nodes.count.shape)
        align = np.asarray(align)
        if align.any():
            oriented = orient_normals(centre, normal, radius, nodes)
            normal = oriented if align.all() else np.where(align[motion][:, None], oriented, normal)
        is_global = kind >= len(PIECEWISE_KINDS)  # one open segment (its normals oriented as closed if asked)
        values = np.hstack([centre, normal, radius[:, None]])
        weights = np.ones(len(values)) if weights is None else np.asarray(weights, dtype=np.float64)
        if is_global.all():  # Bezier curves alone: their spans, slopes and bumps are not used
            spans = cosine = np.ones(len(nodes.span_start))
            return cls(nodes, kind, values, weights, spans, cosine, np.zeros_like(values), np.zeros_like(values),
                       np.zeros((len(spans), 3)))
        i, j = nodes.span_start, nodes.span_end
        spans, cosine = span_lengths(centre, normal, radius, i, j)
        secant = (values[j] - values[i]) / spans[:, None]  # (S, 7)
        span_before, span_after = nodes.node_spans
        before, after = secant[span_before], secant[span_after]
        catmull_rom = kind == KINDS.index("catmull_rom")  # kb with tension = bias = continuity = 0
        t, b, c = (0.0, 0.0, 0.0) if catmull_rom.all() else (tension, bias, continuity)  # one set: weights made once
        if np.ndim(t) or np.ndim(b) or np.ndim(c) or catmull_rom.any() and not catmull_rom.all():  # one per motion
            t, b, c = (np.where(catmull_rom, 0.0, v)[motion][:, None] for v in (tension, bias, continuity))
        # the Kochanek-Bartels weights of the secant slopes before and after each node
        slopes_out = (1 - t) * (1 + b) * (1 + c) / 2 * before + (1 - t) * (1 - b) * (1 - c) / 2 * after
        slopes_in = (1 - t) * (1 + b) * (1 - c) / 2 * before + (1 - t) * (1 - b) * (1 + c) / 2 * after
        slopes_out[:, 6] = monotone_slopes(slopes_out[:, 6], before[:, 6], after[:, 6])
        slopes_in[:, 6] = monotone_slopes(slopes_in[:, 6], before[:, 6], after[:, 6])
        hermite_node = ((kind == KINDS.index("kb")) | catmull_rom)[motion]
        if not hermite_node.all():  # linear and Bezier motions have no slopes
            slopes_out[~hermite_node] = slopes_in[~hermite_node] = 0.0
        bumps = _bumps(centre[i], centre[j], normal[i], normal[j])
        return cls(nodes, kind, values, weights, spans, cosine, slopes_out, slopes_in, bumps)

    @classmethod
    def concatenate(cls, parts: list["Motions"]) -> "Motions":
        """The motions of every part, in order, as one batch (no arithmetic: the parts' arrays joined)."""
        count = np.concatenate([p.nodes.count for p in parts])
        nodes = MotionNodes(np.cumsum(count) - count, count, np.concatenate([p.nodes.is_closed for p in parts]))
        joined = {name: np.concatenate([getattr(p, name) for p in parts])
                  for name in ("kind", "values", "weights", "spans", "cosine", "slopes_out", "slopes_in", "bumps")}
        return cls(nodes, **joined)

    @cached_property
    def certified(self) -> np.ndarray:
        """(M,) whether every span's normal spline H(s) provably stays above MIN_NORMAL_LENGTH.

        H = h00 n_i + h01 n_j + h10 D m_i + h11 D m_j + b(s) w with h00 + h01 = 1, both >= 0, so
        |h00 n_i + h01 n_j| >= sqrt((1 + cos) / 2); |h10|, |h11| <= 4/27 and b <= 1 (a linear span
        has no slope terms). The Bezier kinds are not certified: their sampled check decides.
        """
        nodes, values = self.nodes, self.values
        i, j = nodes.span_start, nodes.span_end
        secant = (values[j] - values[i]) / self.spans[:, None]
        floor = np.sqrt(np.maximum(0.0, 0.5 * (1.0 + self.cosine)))
        slack = HERMITE_SLOPE_BASIS_MAX * self.spans * (np.linalg.norm(self.slopes_out[i, 3:6], axis=1)
                                                         + np.linalg.norm(self.slopes_in[j, 3:6], axis=1))
        bound = floor - slack - np.linalg.norm(self.bumps, axis=1)
        good = (bound > CERTIFY_FACTOR * MIN_NORMAL_LENGTH) & np.isfinite(bound) & np.all(np.isfinite(secant), axis=1)
        bad = np.bincount(nodes.motion[i[~good]], minlength=len(self.kind))
        bad += np.bincount(nodes.motion[~np.all(np.isfinite(values), axis=1)], minlength=len(self.kind))
        return (bad == 0) & (self.kind < len(PIECEWISE_KINDS))

    @property
    def segment_count(self) -> np.ndarray:
        """Segments of every motion (M,): its spans, or 1 for a Bezier curve."""
        return np.where(self.kind >= len(PIECEWISE_KINDS), 1, self.nodes.span_count)

    def evaluate(self, motion: np.ndarray, t: np.ndarray) -> MotionState:
        """Centre, unit normal, radius and their d/dt of rows (motion (A,), parameter t (A,) in
        [0, segment_count[motion]])."""
        return MotionState.of(*self._values(np.asarray(motion), np.asarray(t, dtype=np.float64)))

    def span_state(self, span: np.ndarray, s: np.ndarray) -> MotionState:
        """The state of rows (global span index (A,), local parameter s (A,) in [0, 1]) of piecewise motions."""
        return MotionState.of(*self._span_values(span, s))

    def _values(self, motion: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The 7 spline components and their d/dt (A, 7) of rows (motion, t), before the normal is normalised."""
        is_global = self.kind >= len(PIECEWISE_KINDS)
        if not is_global.any():
            return self._piecewise_values(motion, t)
        orders = np.unique(self.nodes.count[is_global]) - 1  # one Bernstein basis per order present (a handful)
        if is_global.all() and len(orders) == 1:
            return self._bezier_values(motion, t, orders[0])
        is_global = is_global[motion]
        value, rate = np.empty((len(t), 7)), np.empty((len(t), 7))
        rows = np.flatnonzero(~is_global)
        if rows.size:
            value[rows], rate[rows] = self._piecewise_values(motion[rows], t[rows])
        count = self.nodes.count[motion]
        for order in orders:
            rows = np.flatnonzero(is_global & (count == order + 1))
            value[rows], rate[rows] = self._bezier_values(motion[rows], t[rows], order)
        return value, rate

    def _piecewise_values(self, motion: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        segment, s = split_parameter(t, self.nodes.span_count[motion])
        return self._span_values(self.nodes.span_first[motion] + segment, s)

    def _bezier_values(self, motion: np.ndarray, t: np.ndarray, order: int) -> tuple[np.ndarray, np.ndarray]:
        """``_values`` of rows of Bezier motions of one order: the Bernstein basis (the rational
        one, its weights row by row, for rational_bezier) times the controls."""
        b, db = bernstein(order, t), bernstein_derivative(order, t)
        index = self.nodes.first[motion][:, None] + np.arange(order + 1)
        rational = self.kind == KINDS.index("rational_bezier")
        if rational.any():
            rational = slice(None) if rational.all() else np.flatnonzero(rational[motion])
            w = self.weights[index[rational]]
            b[rational], db[rational] = rational_weights(b[rational], db[rational], w / w.max(axis=1)[:, None])
        picked = self.values[index]
        return np.einsum("ak,akm->am", b, picked), np.einsum("ak,akm->am", db, picked)

    def _span_values(self, span: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The 7 components and d/dt (A, 7) at local parameters s (A,) of spans (A,): the cubic
        Hermite basis times (X_i, Delta M_i^out, X_j, Delta M_j^in); on a linear span the basis
        (1 - s, 0, s, 0), the linear interpolation (its two products are the only terms)."""
        i, j = self.nodes.span_start[span], self.nodes.span_end[span]
        start, end = self.values[i], self.values[j]
        linear = self.kind == KINDS.index("linear")
        if linear.all():  # that basis's two products alone
            value, rate = (1.0 - s)[:, None] * start + s[:, None] * end, end - start
        else:
            h, dh = hermite(s)
            if linear.any():
                linear, zero = linear[self.nodes.motion[i]][:, None], np.zeros_like(s)
                h = np.where(linear, np.stack([1.0 - s, zero, s, zero], axis=1), h)
                dh = np.where(linear, np.array([-1.0, 0.0, 1.0, 0.0]), dh)
            width = self.spans[span][:, None]
            terms = np.stack([start, width * self.slopes_out[i], end, width * self.slopes_in[j]], axis=1)
            value, rate = np.einsum("ah,ahk->ak", h, terms), np.einsum("ah,ahk->ak", dh, terms)
        # The bump 16 s^2 (1 - s)^2 w: zero with zero slope at both ends, so the nodes and
        # the slopes there are untouched (C1 kept); 1 at mid-span.
        bump = self.bumps[span]
        value[:, 3:6] += (16.0 * s * s * (1.0 - s) ** 2)[:, None] * bump
        rate[:, 3:6] += (32.0 * s * (1.0 - s) * (1.0 - 2.0 * s))[:, None] * bump
        return value, rate

    def _normal_scan(self, samples_per_segment: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Rows (motion, t) of samples_per_segment per segment of every motion (each motion's
        np.linspace(0, segments, samples_per_segment * segments + 1), bit for bit), the length
        |H| of the normal spline there and whether it is too short or not finite."""
        segments = self.segment_count
        dense = samples_per_segment * segments + 1
        motion = np.repeat(np.arange(len(segments)), dense)
        local = np.arange(len(motion)) - np.repeat(np.cumsum(dense) - dense, dense)
        t = local * (segments / (dense - 1.0))[motion]
        t[np.cumsum(dense) - 1] = segments
        value, _ = self._values(motion, t)
        length = np.linalg.norm(value[:, 3:6], axis=1)
        return motion, t, length, ~(length >= MIN_NORMAL_LENGTH) | ~np.all(np.isfinite(value), axis=1)

    def normals_ok(self, samples_per_segment: int) -> np.ndarray:
        """(M,) whether each motion's normal spline stays at least MIN_NORMAL_LENGTH long on the scan."""
        motion, _, _, bad = self._normal_scan(samples_per_segment)
        return np.bincount(motion[bad], minlength=len(self.kind)) == 0

    def lost_planes(self, names, samples_per_segment: int) -> dict[int, DegenerateGeometryError]:
        """The error of each motion (by index; names (M,) for the messages) whose normal spline
        comes near zero on the scan (the plane's direction is lost there)."""
        motion, t, length, bad = self._normal_scan(samples_per_segment)
        errors = {}
        for m in np.flatnonzero(np.bincount(motion[bad], minlength=len(self.kind))):
            rows = np.flatnonzero(motion == m)
            worst = rows[int(np.argmin(np.where(np.isfinite(length[rows]), length[rows], -np.inf)))]
            segment = min(int(t[worst]), int(self.segment_count[m]) - 1)
            errors[int(m)] = DegenerateGeometryError(
                f"surface '{names[m]}': the motor interpolation loses the circle's plane at segment "
                f"{segment}, alpha = {t[worst] - segment:.6g} (the control normals cancel there; turn fewer "
                "degrees between neighbouring controls, or add a control)")
        return errors

    def check_normals(self, names, samples_per_segment: int) -> None:
        """Raise for the first motion (names (M,) for the message) whose normal spline comes near
        zero on the scan (``lost_planes``)."""
        errors = self.lost_planes(names, samples_per_segment)
        if errors:
            raise errors[min(errors)]


@dataclass(frozen=True)
class MotionSpline:
    """One motor surface's motion (local frame), ``Motions`` of one: ``kind`` the curve kind, ``nodes``
    (n, 7) the controls' centre, oriented normal, radius, ``weights`` (Bezier kinds only) or None."""

    motions: Motions

    @classmethod
    def through(cls, centre: np.ndarray, normal: np.ndarray, radius: np.ndarray, kind: str,
                closed: bool = False, tension: float = 0.0, bias: float = 0.0, continuity: float = 0.0,
                weights: tuple[float, ...] | None = None, align: bool = True) -> "MotionSpline":
        """The spline through control circles (centre (n, 3), normal (n, 3), radius (n,))."""
        return cls(Motions.through(centre, normal, radius, MotionNodes.one(len(centre), closed), kind, tension, bias,
                                   continuity, weights, align))

    @property
    def kind(self) -> str:
        return KINDS[int(self.motions.kind[0])]

    @property
    def closed(self) -> bool:
        return bool(self.motions.nodes.is_closed[0]) and self.kind not in GLOBAL_KINDS

    @property
    def nodes(self) -> np.ndarray:
        return self.motions.values

    @property
    def weights(self) -> tuple[float, ...] | None:
        return tuple(self.motions.weights.tolist()) if self.kind in GLOBAL_KINDS else None

    @property
    def segment_count(self) -> int:
        return int(self.motions.segment_count[0])

    def evaluate(self, t: np.ndarray) -> MotionState:
        """Centre, unit normal, radius and their d/dt at parameters t (A,) in [0, segment_count]."""
        t = np.asarray(t, dtype=np.float64)
        return self.motions.evaluate(np.zeros(t.shape, dtype=np.int64), t)

    def check_normals(self, name: str, samples_per_segment: int) -> None:
        """Raise where the normal spline comes near zero (the plane's direction is lost there)."""
        self.motions.check_normals([name], samples_per_segment)
