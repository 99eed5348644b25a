"""A recentred, rescaled working frame for the conformal computations.

Conformal coordinates mix x and x^2: a unit circle built 1e3 from the origin already loses
about 7e-3 of its radius to cancellation in float64. Interpolation and projection commute
with translations and dilations (both are versors, and C -> C / sqrt(C^2) is invariant
under them), so each surface is computed in a frame where its controls lie in the unit
ball, and only Euclidean results are mapped back.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class LocalFrame:
    """world = origin + scale * local."""

    origin: np.ndarray  # (3,)
    scale: float

    @classmethod
    def enclosing(cls, points: np.ndarray, radii: np.ndarray | None = None) -> "LocalFrame":
        """The frame centred on the points' bounding box that maps them (grown by radii) into the unit ball.

        points: (n, 3); radii: (n,) or None.
        """
        points = np.asarray(points, dtype=np.float64)
        origin = 0.5 * (points.min(axis=0) + points.max(axis=0))
        reach = np.linalg.norm(points - origin, axis=1)
        if radii is not None:
            reach = reach + np.asarray(radii, dtype=np.float64)
        scale = float(reach.max())
        if not scale > 0.0:
            scale = 1.0
        return cls(origin=origin, scale=scale)

    def to_local(self, points: np.ndarray) -> np.ndarray:
        return (np.asarray(points, dtype=np.float64) - self.origin) / self.scale

    def to_world(self, points: np.ndarray) -> np.ndarray:
        return self.origin + self.scale * np.asarray(points, dtype=np.float64)
