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

from cgamesh.geometry.motor_surface import SCAN_SAMPLES_PER_SEGMENT, circle_blades_and_rates
from cgamesh.geometry.motors import Motions
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
    """Motor-interpolated circles, kept for scene.py: the surfaces' motions (``MotionSpline``s)
    joined into one ``Motions`` batch, evaluated by its code as MotorSurface.sample does."""

    def __init__(self, paths):
        self.motions = Motions.concatenate([path.motions for path in paths])
        self.segment_count = paths[0].segment_count

    def scan_ok(self, t: np.ndarray) -> np.ndarray:
        """MotorSurface.check_projection_exists: the normal spline stays at least MIN_NORMAL_LENGTH long."""
        return self.motions.normals_ok(SCAN_SAMPLES_PER_SEGMENT)

    def at(self, surface: np.ndarray, t: np.ndarray):
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            blades, rates = circle_blades_and_rates(self.motions.evaluate(surface, t))
        return blades, rates, np.ones(len(t), dtype=bool)
