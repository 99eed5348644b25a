"""Kochanek-Bartels cubic Hermite splines through control objects (paper section 8.6).

Segment i runs from C_i to C_{i+1} with tangents
  V_i     = (1-t)(1+b)(1+c)/2 (C_i - C_{i-1})     + (1-t)(1-b)(1-c)/2 (C_{i+1} - C_i),
  V_{i+1} = (1-t)(1+b)(1-c)/2 (C_{i+1} - C_i)     + (1-t)(1-b)(1+c)/2 (C_{i+2} - C_{i+1}).
At an open end the missing neighbour is the end control itself (C_{-1} = C_0,
C_{n} = C_{n-1}); a closed spline wraps around. Catmull-Rom is t = b = c = 0.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cgamesh.geometry.curves import CurveBasis, split_parameter


def hermite(alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cubic Hermite basis (h00, h10, h01, h11) and its derivative, each (A, 4)."""
    a = np.asarray(alpha, dtype=np.float64)
    a2, a3 = a * a, a * a * a
    value = np.stack([2 * a3 - 3 * a2 + 1, a3 - 2 * a2 + a, -2 * a3 + 3 * a2, a3 - a2], axis=1)
    derivative = np.stack([6 * a2 - 6 * a, 3 * a2 - 4 * a + 1, -6 * a2 + 6 * a, 3 * a2 - 2 * a], axis=1)
    return value, derivative


@dataclass(frozen=True)
class KochanekBartels:
    control_count: int
    tension: float = 0.0
    bias: float = 0.0
    continuity: float = 0.0
    closed: bool = False

    @property
    def segment_count(self) -> int:
        return self.control_count if self.closed else self.control_count - 1

    def _neighbours(self, segment: np.ndarray) -> np.ndarray:
        """Control indices (A, 4) of C_{i-1}, C_i, C_{i+1}, C_{i+2} for each sample's segment."""
        offsets = segment[:, None] + np.arange(-1, 3)
        if self.closed:
            return offsets % self.control_count
        return np.clip(offsets, 0, self.control_count - 1)

    def _tangent_weights(self) -> np.ndarray:
        """(4,) weights of C_{i-1}, C_i, C_{i+1}, C_{i+2} in V_i, and (4,) in V_{i+1}."""
        t, b, c = self.tension, self.bias, self.continuity
        out_left, out_right = (1 - t) * (1 + b) * (1 + c) / 2, (1 - t) * (1 - b) * (1 - c) / 2
        in_left, in_right = (1 - t) * (1 + b) * (1 - c) / 2, (1 - t) * (1 - b) * (1 + c) / 2
        v_start = np.array([-out_left, out_left - out_right, out_right, 0.0])
        v_end = np.array([0.0, -in_left, in_left - in_right, in_right])
        return v_start, v_end

    def basis(self, t: np.ndarray) -> CurveBasis:
        segment, alpha = split_parameter(t, self.segment_count)
        h, dh = hermite(alpha)
        v_start, v_end = self._tangent_weights()
        point_start = np.array([0.0, 1.0, 0.0, 0.0])
        point_end = np.array([0.0, 0.0, 1.0, 0.0])
        # Each sample's curve is h00 C_i + h10 V_i + h01 C_{i+1} + h11 V_{i+1}, written as
        # weights of the four neighbouring controls (clamped ends repeat an index; the
        # repeated weights simply add when the basis is evaluated).
        mix = np.stack([point_start, v_start, point_end, v_end])  # (4 hermite, 4 controls)
        # explicit sums over the four Hermite terms, not h @ mix: a matrix product sums a lone
        # parameter in another order than many, and the basis must not depend on how many it gets
        return CurveBasis(self._neighbours(segment), (h[:, :, None] * mix).sum(axis=1),
                          (dh[:, :, None] * mix).sum(axis=1))


def catmull_rom(control_count: int, closed: bool = False) -> KochanekBartels:
    return KochanekBartels(control_count, closed=closed)
