"""Piecewise linear interpolation C' = (1 - alpha) C_i + alpha C_{i+1} (paper eq. 9, section 8.1)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cgamesh.geometry.curves import CurveBasis, split_parameter


@dataclass(frozen=True)
class Linear:
    control_count: int

    @property
    def segment_count(self) -> int:
        return self.control_count - 1

    def basis(self, t: np.ndarray) -> CurveBasis:
        segment, alpha = split_parameter(t, self.segment_count)
        indices = np.stack([segment, segment + 1], axis=1)
        weights = np.stack([1.0 - alpha, alpha], axis=1)
        derivatives = np.broadcast_to(np.array([-1.0, 1.0]), weights.shape).copy()
        return CurveBasis(indices, weights, derivatives)
