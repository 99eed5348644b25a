"""Rings of circle surfaces as rows: what the circle mesher reads, for one surface or many.

Every ring is a row: its circle in world units (centre, unit normal, radius), the angular-velocity
bivector Omega = C dC/dt of its blade (eq. 19) as grade-2 rows (10, R) in its surface's local
frame, that frame (origin, scale), and its parameter t. A surface's rings are consecutive rows,
surface after surface (``SurfaceRows``). The readers of circles fill them: an evolved surface's
projection (``of_rings``), a group of scene surfaces (cgamesh.meshing.scene_batch) or the motions
of many centreline chains (cgamesh.meshing.batch_pass) read out the same way, so a ring's row has
the same bits whichever reader made it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from cgamesh.geometry.algebra.layout import grade_indices
from cgamesh.geometry.surface import CircleRings, carried_velocity


@dataclass(frozen=True)
class RingRows:
    """Circles of R rings: centre (R, 3), normal (R, 3) unit, radius (R,) in world units; omega
    (10, R) the grade-2 rows of C dC/dt in the local frame of each ring's surface, whose origin
    (R, 3) and scale (R,) they carry; t (R,) each ring's parameter on its surface."""

    centre: np.ndarray
    normal: np.ndarray
    radius: np.ndarray
    omega: np.ndarray
    origin: np.ndarray
    scale: np.ndarray
    t: np.ndarray

    @classmethod
    def of_rings(cls, rings: CircleRings, t: np.ndarray) -> "RingRows":
        """The rows of one surface's circles at parameters t (its frame on every row)."""
        count = len(t)
        frame = rings.frame
        return cls(rings.centre, rings.normal, rings.radius, np.moveaxis(rings.omega[..., grade_indices(2)], -1, 0),
                   np.broadcast_to(np.asarray(frame.origin, dtype=np.float64), (count, 3)),
                   np.full(count, float(frame.scale)), np.asarray(t, dtype=np.float64))

    def __len__(self) -> int:
        return len(self.t)

    def take(self, rows: np.ndarray) -> "RingRows":
        """These rows (an index or bool mask (R,))."""
        return RingRows(self.centre[rows], self.normal[rows], self.radius[rows], self.omega[:, rows],
                        self.origin[rows], self.scale[rows], self.t[rows])

    def velocity(self, points: np.ndarray) -> np.ndarray:
        """World velocity d x / d t (R, n, 3) of world points (R, n, 3) on the circles
        (``CircleRings.velocity`` with each row's frame)."""
        scale = self.scale[:, None, None]
        local = np.subtract(points, self.origin[:, None, :])
        local /= scale
        velocity = carried_velocity(self.omega, local)
        velocity *= scale
        return velocity


@dataclass(frozen=True)
class SurfaceRows:
    """Which rows are whose: surface s has rows first[s] .. first[s] + count[s] - 1 (S,), one
    surface after another from row 0."""

    first: np.ndarray
    count: np.ndarray

    @classmethod
    def of_counts(cls, count: np.ndarray) -> "SurfaceRows":
        count = np.asarray(count, dtype=np.int64)
        return cls(np.concatenate([[0], np.cumsum(count)[:-1]]).astype(np.int64), count)

    @property
    def rows(self) -> int:
        return int(self.count.sum())

    @cached_property
    def surface(self) -> np.ndarray:
        """(R,) the surface of every row."""
        return np.repeat(np.arange(len(self.count)), self.count)

    @cached_property
    def local(self) -> np.ndarray:
        """(R,) every row's index within its surface."""
        return np.arange(self.rows) - np.repeat(self.first, self.count)

    @property
    def last(self) -> np.ndarray:
        return self.first + self.count - 1

    @cached_property
    def within(self) -> np.ndarray:
        """(R - 1,) whether rows r and r + 1 are rings of one surface."""
        return self.surface[1:] == self.surface[:-1]

    def kept(self, keep: np.ndarray) -> "SurfaceRows":
        """The layout after dropping rows (keep (R,) bool); a surface may be left with no rows."""
        return SurfaceRows.of_counts(np.bincount(self.surface[keep], minlength=len(self.count)))


# Circles at other parameters of the surfaces being meshed, for the rare repairs: (surface (n,),
# t (n,)) -> (their rows, (n,) whether each has a circle there). The single-surface reader raises
# the surface's own error where it has none.
Resample = Callable[[np.ndarray, np.ndarray], tuple[RingRows, np.ndarray]]


def padded_rows(first: np.ndarray, count: np.ndarray):
    """Per-surface rows for row-wise numpy reductions, grouped by length class so padding stays
    under 2x: yields (surfaces, row index grid (c, L) or -1, valid (c, L))."""
    lengths_class = np.ceil(np.log2(np.maximum(count, 1))).astype(np.int64)
    # the classes present, ascending (np.unique would import numpy.ma to look for a mask)
    for cls in np.flatnonzero(np.bincount(lengths_class)):
        members = np.flatnonzero(lengths_class == cls)
        width = int(count[members].max())
        grid = first[members][:, None] + np.arange(width)[None, :]
        valid = np.arange(width)[None, :] < count[members][:, None]
        yield members, np.where(valid, grid, -1), valid
