"""Curves through control objects as basis matrices times controls.

Every curve kind maps a global parameter t in [0, segment_count] (segment s covers
alpha = t - s in [0, 1], paper section 8) to a compact basis: for each sample, the indices
of the controls it depends on, their weights, and the weights' derivatives with respect to
alpha. C'(t) = sum_k weights[:, k] * controls[indices[:, k]], and dC'/dalpha likewise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class CurveBasis:
    """indices (A, k) int; weights (A, k); derivatives (A, k) = d weights / d alpha."""

    indices: np.ndarray
    weights: np.ndarray
    derivatives: np.ndarray

    def evaluate(self, controls: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """C'(t) and dC'/dalpha, each (A, 32), for controls (n, 32)."""
        picked = controls[self.indices]  # (A, k, 32)
        value = np.einsum("ak,akm->am", self.weights, picked)
        derivative = np.einsum("ak,akm->am", self.derivatives, picked)
        return value, derivative

    def value(self, controls: np.ndarray) -> np.ndarray:
        """C'(t) (A, 32) alone, for controls (n, 32)."""
        return np.einsum("ak,akm->am", self.weights, controls[self.indices])

    def weight_sum(self) -> np.ndarray:
        """(A,) sum of |weights|: C' has at most this size for unit controls."""
        return np.abs(self.weights).sum(axis=1)


def split_parameter(t: np.ndarray, segment_count: int) -> tuple[np.ndarray, np.ndarray]:
    """Segment index (A,) int and local alpha (A,) for global parameters t (A,).

    t = segment_count (the very end) belongs to the last segment with alpha = 1.
    """
    t = np.asarray(t, dtype=np.float64)
    segment = np.clip(np.floor(t), 0, segment_count - 1).astype(np.int64)
    return segment, t - segment
