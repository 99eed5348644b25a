"""Similarity motions of many open Catmull-Rom motor chains at once (geometry.motors, batched).

The arithmetic is that of ``MotionSpline.through`` and ``MotionSpline._values`` for the
curve kind centrelines use (catmull_rom, open, aligned), written over the nodes of every
chain concatenated: spans are the pairs of consecutive nodes of one chain, and every per-node
or per-span formula is evaluated elementwise with the chain ends handled as the per-chain
code handles an open end. The one sequential step of the per-chain code, the sign choice of
``orient_normals``, is a running product of signs and is computed as a segmented parity.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from cgamesh.geometry.curves.kochanek_bartels import hermite
from cgamesh.geometry.motors import (MIN_NORMAL_LENGTH, MIN_SPAN, MONOTONE_LIMIT, PATH_COSINE, PATH_FRACTION,
                                     MotionState)
from cgamesh.geometry.objects import perpendicular_unit

# The largest |h10| and |h11| of the cubic Hermite basis on [0, 1] (at s = 1/3 and 2/3).
HERMITE_SLOPE_BASIS_MAX = 4.0 / 27.0
# A span is certified when the lower bound of |H| exceeds MIN_NORMAL_LENGTH by this factor.
CERTIFY_FACTOR = 2.0


@dataclass(frozen=True)
class ChainNodes:
    """Nodes of many chains, concatenated: ``first`` (C,) index of each chain's first node,
    ``count`` (C,) nodes per chain (>= 2); ``chain`` (N,) the chain of every node. The index
    arrays derived from them are made once per instance (``cached_property``): the motion's
    construction and evaluation read them several times."""

    first: np.ndarray
    count: np.ndarray

    @cached_property
    def chain(self) -> np.ndarray:
        return np.repeat(np.arange(len(self.count)), self.count)

    @cached_property
    def local(self) -> np.ndarray:
        """Each node's index within its chain (N,)."""
        return np.arange(int(self.count.sum())) - np.repeat(self.first, self.count)

    @cached_property
    def is_first(self) -> np.ndarray:
        return self.local == 0

    @cached_property
    def is_last(self) -> np.ndarray:
        return self.local == np.repeat(self.count - 1, self.count)

    @cached_property
    def span_start(self) -> np.ndarray:
        """Global node index of the first node of every span (S,), chain after chain."""
        return np.flatnonzero(~self.is_last)

    @cached_property
    def span_first(self) -> np.ndarray:
        """Index of each chain's first span in the span arrays (C,)."""
        return self.first - np.arange(len(self.count))


def orient_normals(centre: np.ndarray, normal: np.ndarray, radius: np.ndarray, nodes: ChainNodes) -> np.ndarray:
    """``motors.orient_normals`` of every open chain: the same sign rule, as a segmented parity.

    Node i flips when s_{i-1} q_i < 0 with q_i = along_i along_{i-1} (both near the path) or
    n_{i-1} . n_i; so s_i is the product of sign(q_k) since the chain's start or the last
    q_k = 0 (which resets the sign to +1).
    """
    is_first, is_last = nodes.is_first, nodes.is_last
    index = np.arange(len(centre))
    ahead = centre[np.where(is_last, index, index + 1)]
    behind = centre[np.where(is_first, index, index - 1)]
    direction = ahead - behind
    length = np.linalg.norm(direction, axis=1)
    reliable = length > PATH_FRACTION * radius
    unit = np.where(reliable[:, None], direction / np.where(reliable, length, 1.0)[:, None], 0.0)
    along = np.einsum("ni,ni->n", normal, unit)
    previous = np.maximum(index - 1, 0)
    near_path = reliable & (np.abs(along) >= PATH_COSINE)
    case_path = near_path & near_path[previous]
    q = np.where(case_path, along * along[previous], np.einsum("ni,ni->n", normal[previous], normal))
    reset = is_first | (q == 0.0)
    negative = np.where(reset, 0, q < 0.0).astype(np.int64)
    count = np.cumsum(negative)
    start = np.maximum.accumulate(np.where(reset, index, 0))
    parity = (count - count[start] + negative[start]) % 2  # negatives after the reset (its own is 0)
    sign = np.where(reset & ~is_first, 1.0, 1.0 - 2.0 * parity)
    sign[is_first] = 1.0
    return normal * sign[:, None]


@dataclass(frozen=True)
class ChainMotions:
    """The splined motions of every chain, in each chain's local frame.

    nodes_values (N, 7): centre, oriented normal, radius; spans (S,); slopes_out / slopes_in
    (N, 7) per unit knot; bumps (S, 3); ``certified`` (C,): the normal spline of every span of
    the chain provably stays longer than MIN_NORMAL_LENGTH (else the per-chain check decides).
    """

    nodes: ChainNodes
    values: np.ndarray
    spans: np.ndarray
    slopes_out: np.ndarray
    slopes_in: np.ndarray
    bumps: np.ndarray
    certified: np.ndarray

    @classmethod
    def through(cls, centre: np.ndarray, normal: np.ndarray, radius: np.ndarray, nodes: ChainNodes) -> "ChainMotions":
        normal = normal / np.linalg.norm(normal, axis=1, keepdims=True)
        normal = orient_normals(centre, normal, radius, nodes)
        values = np.hstack([centre, normal, radius[:, None]])
        i = nodes.span_start
        j = i + 1
        cosine = np.clip(np.einsum("ni,ni->n", normal[i], normal[j]), -1.0, 1.0)
        sine = np.linalg.norm(np.cross(normal[i], normal[j]), axis=1)
        angle = np.arctan2(sine, cosine)
        spans = np.maximum(np.maximum(np.maximum(np.linalg.norm(centre[j] - centre[i], axis=1),
                                                 np.abs(radius[j] - radius[i])),
                                      0.5 * (radius[i] + radius[j]) * angle), MIN_SPAN)
        secant = (values[j] - values[i]) / spans[:, None]  # (S, 7)
        # node n's spans: the one before (span n - 1 - chain) and after (span n - chain)
        chain = nodes.chain
        span_after = np.arange(len(values)) - chain
        span_before = span_after - 1
        span_after = np.where(nodes.is_last, span_before, span_after)
        span_before = np.where(nodes.is_first, span_after, span_before)
        before, after = secant[span_before], secant[span_after]
        slopes = 0.5 * before + 0.5 * after  # Kochanek-Bartels with t = b = c = 0
        slopes_out, slopes_in = slopes, slopes.copy()
        radius_slope = _monotone(slopes[:, 6], before[:, 6], after[:, 6])
        slopes_out[:, 6] = radius_slope
        slopes_in[:, 6] = radius_slope
        bumps = _bumps(centre[i], centre[j], normal[i], normal[j])
        certified = _certified(cosine, spans, slopes_out[i, 3:6], slopes_in[j, 3:6], bumps, values, secant, nodes)
        return cls(nodes, values, spans, slopes_out, slopes_in, bumps, certified)

    def evaluate(self, span: np.ndarray, s: np.ndarray) -> MotionState:
        """The motion state at local parameters s (A,) of global spans (A,) (``MotionSpline.evaluate``)."""
        i = self.nodes.span_start[span]
        j = i + 1
        start, end = self.values[i], self.values[j]
        h, dh = hermite(s)
        width = self.spans[span][:, None]
        terms = np.stack([start, width * self.slopes_out[i], end, width * self.slopes_in[j]], axis=1)
        value = np.einsum("ah,ahk->ak", h, terms)
        rate = np.einsum("ah,ahk->ak", dh, terms)
        bump = self.bumps[span]
        value[:, 3:6] += (16.0 * s * s * (1.0 - s) ** 2)[:, None] * bump
        rate[:, 3:6] += (32.0 * s * (1.0 - s) * (1.0 - 2.0 * s))[:, None] * bump
        h, dh = value[:, 3:6], rate[:, 3:6]
        length = np.linalg.norm(h, axis=1)
        normal = h / length[:, None]
        d_normal = (dh - normal * np.einsum("ai,ai->a", normal, dh)[:, None]) / length[:, None]
        return MotionState(value[:, :3], normal, value[:, 6], rate[:, :3], d_normal, rate[:, 6], length)


def _monotone(slopes: np.ndarray, before: np.ndarray, after: np.ndarray) -> np.ndarray:
    """``motors._monotone`` from each node's neighbouring secants."""
    same_sign = before * after > 0.0
    bound = MONOTONE_LIMIT * np.minimum(np.abs(before), np.abs(after))
    limited = np.sign(after) * np.minimum(np.abs(slopes) * (np.sign(slopes) == np.sign(after)), bound)
    return np.where(same_sign, limited, 0.0)


def _bumps(centre_i, centre_j, start, end) -> np.ndarray:
    """``motors._bumps`` per span."""
    weight = np.maximum(0.0, -np.einsum("si,si->s", start, end)) ** 2
    chord = centre_j - centre_i
    chord = chord - start * np.einsum("si,si->s", chord, start)[:, None]
    length = np.linalg.norm(chord, axis=1)
    usable = length > 1e-9 * np.maximum(1.0, np.linalg.norm(centre_j - centre_i, axis=1))
    direction = chord / np.where(usable, length, 1.0)[:, None]
    if not usable.all():  # the fallback row by row, made only where it is taken
        direction[~usable] = perpendicular_unit(start[~usable])
    return weight[:, None] * direction


def _certified(cosine, spans, slope_out, slope_in, bumps, values, secant, nodes: ChainNodes) -> np.ndarray:
    """(C,) whether every span's normal spline H(s) stays above MIN_NORMAL_LENGTH, by a bound.

    H = h00 n_i + h01 n_j + h10 D m_i + h11 D m_j + b(s) w with h00 + h01 = 1, both >= 0, so
    |h00 n_i + h01 n_j| >= sqrt((1 + cos) / 2); |h10|, |h11| <= 4/27 and b <= 1. Where the
    bound does not prove it, the chain goes to the per-chain path, whose sampled check decides.
    """
    floor = np.sqrt(np.maximum(0.0, 0.5 * (1.0 + cosine)))
    slack = HERMITE_SLOPE_BASIS_MAX * spans * (np.linalg.norm(slope_out, axis=1) + np.linalg.norm(slope_in, axis=1))
    bound = floor - slack - np.linalg.norm(bumps, axis=1)
    good_span = (bound > CERTIFY_FACTOR * MIN_NORMAL_LENGTH) & np.isfinite(bound) & np.all(np.isfinite(secant), axis=1)
    chains = len(nodes.count)
    bad = np.bincount(nodes.chain[nodes.span_start][~good_span], minlength=chains)
    finite_nodes = np.all(np.isfinite(values), axis=1)
    bad += np.bincount(nodes.chain[~finite_nodes], minlength=chains)
    return bad == 0
