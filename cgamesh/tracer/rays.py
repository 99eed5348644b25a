"""Batches of rays: normalised CGA lines with the Euclidean origin each ray starts from.

A ray is the line L = X0 ^ P ^ n_inf (section 3), oriented from its origin X0 through P and
normalised to L^2 = 1; ``origins`` says where on the line it starts and ``t_max`` how far it
goes (shadow rays stop at their light). Distances along a ray are Euclidean:
x = origin + t direction with the unit direction read from the line.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cgamesh.geometry.algebra.conformal import down
from cgamesh.tracer import cga


@dataclass(frozen=True)
class Rays:
    """lines (N, 32) normalised; origins (N, 3); directions (N, 3) unit; t_max (N,)."""

    lines: np.ndarray
    origins: np.ndarray
    directions: np.ndarray
    t_max: np.ndarray

    @classmethod
    def through_points(cls, x0: np.ndarray, p: np.ndarray, t_max: np.ndarray | None = None) -> "Rays":
        """Rays L = X0 ^ P ^ n_inf from conformal points X0 through conformal points P (N, 32)."""
        lines = cga.normalise_line(cga.line_through(x0, p))
        origins = down(x0)
        return cls._make(lines, np.broadcast_to(origins, lines.shape[:-1] + (3,)).copy(), t_max)

    @classmethod
    def from_lines(cls, lines: np.ndarray, origins: np.ndarray, t_max: np.ndarray | None = None) -> "Rays":
        """Rays along given lines (N, 32) (normalised here) starting at points (N, 3) on them."""
        return cls._make(cga.normalise_line(lines), np.asarray(origins, dtype=np.float64), t_max)

    @classmethod
    def from_origin_direction(cls, origins: np.ndarray, directions: np.ndarray,
                              t_max: np.ndarray | None = None) -> "Rays":
        """Rays from Euclidean origins along directions (N, 3) (normalised here)."""
        o = np.asarray(origins, dtype=np.float64)
        d = np.asarray(directions, dtype=np.float64)
        d = d / np.linalg.norm(d, axis=-1, keepdims=True)
        return cls._make(cga.line(o, d), o, t_max)

    @classmethod
    def _make(cls, lines, origins, t_max) -> "Rays":
        n = lines.shape[0]
        t_max = np.full(n, np.inf) if t_max is None else np.broadcast_to(np.asarray(t_max, dtype=np.float64), (n,))
        return cls(lines, origins, cga.line_direction(lines), t_max)

    def __len__(self) -> int:
        return int(self.lines.shape[0])

    def take(self, index: np.ndarray) -> "Rays":
        """The rays at ``index`` (an integer array or a boolean mask)."""
        return Rays(self.lines[index], self.origins[index], self.directions[index], self.t_max[index])

    def at(self, t: np.ndarray) -> np.ndarray:
        """Points origin + t direction (N, 3)."""
        return self.origins + np.asarray(t)[:, None] * self.directions

    def parameter_of(self, points: np.ndarray) -> np.ndarray:
        """t (N,) of points (N, 3) on (or projected onto) the rays."""
        return np.einsum("ni,ni->n", points - self.origins, self.directions)
