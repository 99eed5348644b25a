"""The circles of a group's surfaces at any parameters, as each surface's ``sample`` gives them.

A sampler stands for S surfaces of one shape of work: ``at(surface, t)`` gives the normalised
circle blades C(t) and dC/dt (local frame) of rows (surface index, parameter) and whether each
row has a circle (the per-surface ``sample`` refuses it otherwise); ``scan_ok(t)`` whether each
surface's ``check_projection_exists(sampled=t)`` passes without refining. Both compute every
row with the operations of the per-surface classes (EvolvedSurface, MotorSurface), so rows are
the same bits.
"""

from __future__ import annotations

import numpy as np

from cgamesh.geometry.curves import split_parameter
from cgamesh.geometry.curves.bezier import Bezier, RationalBezier
from cgamesh.geometry.curves.kochanek_bartels import hermite
from cgamesh.geometry.motor_surface import SCAN_SAMPLES_PER_SEGMENT, circle_blades_and_rates
from cgamesh.geometry.motors import GLOBAL_KINDS, MIN_NORMAL_LENGTH, MotionState
from cgamesh.geometry.projection import project
from cgamesh.geometry.surface import MIN_MARGIN
from cgamesh.meshing.scene_batch.projection_scan import exactly_projectable, surely_projectable


class BladeSampler:
    """Blade-interpolated circles: the curve's basis times each surface's controls (S, n, 32),
    projected (EvolvedSurface.sample)."""

    def __init__(self, curve, controls: np.ndarray):
        self.curve, self.controls = curve, controls
        self.segment_count = curve.segment_count

    def scan_ok(self, t: np.ndarray) -> np.ndarray:
        """The quick scan from the controls' products; the surfaces it cannot vouch for (a carrier
        that flips between samples, a small margin) scanned exactly, as the per-surface path."""
        ok = surely_projectable(self.curve, t, self.controls)
        doubtful = np.flatnonzero(~ok)
        if doubtful.size:
            ok[doubtful] = exactly_projectable(self.curve, t, self.controls[doubtful])
        return ok

    def at(self, surface: np.ndarray, t: np.ndarray):
        n = self.controls.shape[1]
        basis = self.curve.basis(t)
        picked = self.controls.reshape(-1, 32)[basis.indices + (surface * n)[:, None]]
        interpolant = np.einsum("ak,akm->am", basis.weights, picked)
        derivative = np.einsum("ak,akm->am", basis.derivatives, picked)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            projection = project(interpolant, derivative, 3, basis.weight_sum())
        return projection.blades, projection.derivatives, projection.margin >= MIN_MARGIN


class MotorSampler:
    """Motor-interpolated circles: each surface's MotionSpline (same kind, node count, closed and
    rational weights) stacked, evaluated as MotionSpline.evaluate does (MotorSurface.sample)."""

    def __init__(self, paths):
        first = paths[0]
        self.kind, self.closed, self.weights = first.kind, first.closed, first.weights
        self.nodes = np.stack([path.nodes for path in paths])
        self.segment_count = first.segment_count
        if self.kind not in GLOBAL_KINDS:
            self.spans = np.stack([path.spans for path in paths])
            self.bumps = np.stack([path.bumps for path in paths])
            if self.kind != "linear":
                self.slopes_out = np.stack([path.slopes_out for path in paths])
                self.slopes_in = np.stack([path.slopes_in for path in paths])

    def _values(self, surface: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """MotionSpline._values of rows (surface, t)."""
        count, n = self.nodes.shape[:2]
        if self.kind in GLOBAL_KINDS:
            curve = Bezier(n) if self.kind == "bezier" else RationalBezier(self.weights)
            basis = curve.basis(t)
            picked = self.nodes.reshape(-1, 7)[basis.indices + (surface * n)[:, None]]
            return (np.einsum("ak,akm->am", basis.weights, picked),
                    np.einsum("ak,akm->am", basis.derivatives, picked))
        segment, s = split_parameter(t, self.segment_count)
        i, j = segment, (segment + 1) % n
        start, end = self.nodes[surface, i], self.nodes[surface, j]
        if self.kind == "linear":
            value = (1.0 - s)[:, None] * start + s[:, None] * end
            rate = end - start
        else:
            h, dh = hermite(s)
            span = self.spans[surface, segment][:, None]
            terms = np.stack([start, span * self.slopes_out[surface, i], end, span * self.slopes_in[surface, j]],
                             axis=1)
            value = np.einsum("ah,ahk->ak", h, terms)
            rate = np.einsum("ah,ahk->ak", dh, terms)
        bump = self.bumps[surface, segment]
        value[:, 3:6] += (16.0 * s * s * (1.0 - s) ** 2)[:, None] * bump
        rate[:, 3:6] += (32.0 * s * (1.0 - s) * (1.0 - 2.0 * s))[:, None] * bump
        return value, rate

    def scan_ok(self, t: np.ndarray) -> np.ndarray:
        """MotionSpline.check_normals: the normal spline stays at least MIN_NORMAL_LENGTH long."""
        count = len(self.nodes)
        dense = np.linspace(0.0, self.segment_count, SCAN_SAMPLES_PER_SEGMENT * self.segment_count + 1)
        value, _ = self._values(np.repeat(np.arange(count), len(dense)), np.tile(dense, count))
        length = np.linalg.norm(value[:, 3:6], axis=1)
        bad = ~(length >= MIN_NORMAL_LENGTH) | ~np.all(np.isfinite(value), axis=1)
        return ~bad.reshape(count, -1).any(axis=1)

    def at(self, surface: np.ndarray, t: np.ndarray):
        value, rate = self._values(surface, t)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            h, dh = value[:, 3:6], rate[:, 3:6]
            length = np.linalg.norm(h, axis=1)
            normal = h / length[:, None]
            d_normal = (dh - normal * np.einsum("ai,ai->a", normal, dh)[:, None]) / length[:, None]
            state = MotionState(value[:, :3], normal, value[:, 6], rate[:, :3], d_normal, rate[:, 6], length)
            blades, rates = circle_blades_and_rates(state)
        return blades, rates, np.ones(len(t), dtype=bool)
