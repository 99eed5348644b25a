"""A surface read at the tolerance plan's dense samplings, each parameter once.

The plan bounds a surface's members (circle centres, normals and radii; ribbon end points) per
cell of a sampling at ``segment_samples(segments, cells)`` (cgamesh.meshing.tolerance.derivative_bounds),
first at a few cells per segment and often again at a finer power of two. The finer sampling's
parameters include the coarser one's, the same floats (their spacings are powers of two), and a
parameter's blade and members do not depend on the others read with it (the algebra's products
sum each row's terms in one order, whatever the batch; the members are formed row by row): so
only the new parameters are read and the known ones interleaved, the same bits as one read of
them all.
"""

from __future__ import annotations

import math

import numpy as np

from cgamesh.geometry.objects import circle_euclidean
from cgamesh.geometry.surface import EvolvedSurface
from cgamesh.meshing.tolerance.derivative_bounds import segment_samples

# Samples read out per call (the projection's batched products slow down beyond).
SAMPLE_CHUNK = 512


def _chunks(t: np.ndarray) -> list[np.ndarray]:
    return np.array_split(t, max(1, math.ceil(len(t) / SAMPLE_CHUNK)))


def read_blades(surface: EvolvedSurface, t: np.ndarray) -> np.ndarray:
    """The projected blades at parameters t, read in chunks of SAMPLE_CHUNK."""
    return np.concatenate([surface.sample_blades(part) for part in _chunks(t)])


def circle_members(surface: EvolvedSurface, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The circles' centres, unit normals and radii at parameters t (the surface's frame)."""
    return circle_euclidean(read_blades(surface, t))


def pair_members(surface: EvolvedSurface, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The point pairs' end points a, b at parameters t (the surface's frame): those the read
    found checking them (``sample_pair_ends``), the same bits as point_pair_endpoints of the blades."""
    ends = [surface.sample_pair_ends(part) for part in _chunks(t)]
    return np.concatenate([a for a, _ in ends]), np.concatenate([b for _, b in ends])


class DenseSamples:
    """``members(surface, t)`` (arrays with a row per parameter: ``circle_members`` or
    ``pair_members``) at the surface's samplings, the last one kept so that a finer one reads
    only the parameters it lacks."""

    def __init__(self, surface: EvolvedSurface, members):
        self.surface, self.members = surface, members
        self._last: tuple | None = None  # parameters (segments, cells + 1), members (segments, cells + 1, ...)

    def read(self, cells: int) -> tuple[np.ndarray, ...]:
        """The members at ``segment_samples(segments, cells)``, (segments * (cells + 1), ...) each,
        segment-major."""
        t = segment_samples(self.surface.segment_count, cells)
        values = None
        if self._last is not None:
            known_t, known = self._last
            step, rest = divmod(cells, known_t.shape[1] - 1)
            if step > 1 and rest == 0 and np.array_equal(t[:, ::step], known_t):
                new = np.arange(cells + 1) % step != 0
                values = tuple(np.empty(t.shape + old.shape[2:]) for old in known)
                for value, old, fresh in zip(values, known, self._at(t[:, new])):
                    value[:, ::step] = old
                    value[:, new] = fresh.reshape((len(t), -1) + old.shape[2:])
        if values is None:
            values = tuple(value.reshape(t.shape + value.shape[1:]) for value in self._at(t))
        self._last = t, values
        return tuple(value.reshape((t.size,) + value.shape[2:]) for value in values)

    def _at(self, t: np.ndarray) -> tuple[np.ndarray, ...]:
        return self.members(self.surface, t.ravel())
