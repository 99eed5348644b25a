"""Centrelines read from real data: one in-memory type for SWC skeletons, tractograms and arrays.

A file becomes a ``Centerlines``: points with optional radii, either a tree (``parents``, -1 for
a root, several roots allowed) or separate polylines (``offsets``), per-point scalars by name,
the file's length unit and, for messages, where each point came from. The readers
(swc.py, streamlines.py, arrays.py; which one reads a file: the table in formats.py) validate
every record; what is built from a Centerlines (cgamesh.pipelines.centerlines) may assume its
arrays are finite and consistent.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from cgamesh.inputs import formats
from cgamesh.inputs.units import METERS_PER_UNIT


@dataclass(frozen=True)
class Centerlines:
    """Points along centrelines, as read from one file (arrays are read-only).

    points:  (N, 3) float64, in ``units``.
    radii:   (N,) float64 >= 0, or None when the file has none (a constant radius is then needed).
    parents: (N,) int64 index of each point's parent point, -1 for a root (a tree: SWC, or
             arrays with ``parents``); None for polylines.
    offsets: (M + 1,) int64 boundaries of M polylines in ``points`` (offsets[0] = 0,
             offsets[-1] = N); None for a tree.
    scalars: per-point values by name, each (N,) float64 (e.g. a tractogram's ``fa``).
    units:   the length unit of ``points`` and ``radii`` (a key of METERS_PER_UNIT).
    source:  the file's path as given (``<arrays>`` for arrays handed over in memory).
    ids:     (N,) int64 the file's own ids of the points (SWC node ids), or None (then the
             point index is the id).
    kinds:   (N,) int64 SWC structure type of each node (1 = soma), or None.
    lines:   (N,) int64 1-based line of each point in the file, or None.
    """

    points: np.ndarray
    radii: np.ndarray | None = None
    parents: np.ndarray | None = None
    offsets: np.ndarray | None = None
    scalars: dict[str, np.ndarray] = field(default_factory=dict)
    units: str = "m"
    source: str = "<arrays>"
    ids: np.ndarray | None = None
    kinds: np.ndarray | None = None
    lines: np.ndarray | None = None

    def __post_init__(self) -> None:
        if (self.parents is None) == (self.offsets is None):
            raise ValueError("a Centerlines is either a tree (parents) or polylines (offsets)")
        for value in (self.points, self.radii, self.parents, self.offsets, self.ids, self.kinds, self.lines,
                      *self.scalars.values()):
            if value is not None:
                value.flags.writeable = False

    @property
    def is_tree(self) -> bool:
        return self.parents is not None

    @property
    def meters_per_unit(self) -> float:
        return METERS_PER_UNIT[self.units]

    def node_name(self, index: int) -> str:
        """How a message names point ``index``: ``node 17 (line 23)``, or ``point 17``."""
        if self.ids is None:
            return f"point {index}"
        line = f" (line {int(self.lines[index])})" if self.lines is not None else ""
        return f"node {int(self.ids[index])}{line}"


def readonly(array: np.ndarray) -> np.ndarray:
    """``array`` as a contiguous array of its own that nobody can write to."""
    array = np.array(array, copy=True, order="C")
    array.flags.writeable = False
    return array


def is_centerline_file(path) -> bool:
    """Whether ``path`` is of a centreline format of the input table (cgamesh.inputs.formats)."""
    found = formats.find(path)
    return found is not None and found.kind is formats.InputKind.CENTERLINES


def read_centerlines(path, units: str | None = None) -> Centerlines:
    """Any centreline file, by its format in the input table; ``units`` overrides the format's own unit."""
    return formats.read_centerlines(path, units)
