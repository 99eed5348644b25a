"""Centrelines read from real data: one in-memory type for SWC skeletons, tractograms and arrays.

A file becomes a ``Centerlines``: points with optional radii, either a tree (``parents``, -1 for
a root, several roots allowed) or separate polylines (``offsets``), per-point scalars by name,
the file's length unit and, for messages, where each point came from. The readers
(swc.py, streamlines.py, arrays.py) validate every record; what is built from a Centerlines
(cgamesh.centerline_pipeline) may assume its arrays are finite and consistent.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

# Length units of real-data inputs, in metres.
METERS_PER_UNIT = {"nm": 1e-9, "um": 1e-6, "mm": 1e-3, "cm": 1e-2, "m": 1.0}


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


# Centreline file kinds by extension: (reader module, function, the format's own length unit).
CENTERLINE_FORMATS = {
    ".swc": ("cgamesh.inputs.swc", "read_swc", "um"),
    ".trk": ("cgamesh.inputs.streamlines", "read_streamlines", "mm"),
    ".tck": ("cgamesh.inputs.streamlines", "read_streamlines", "mm"),
    ".trx": ("cgamesh.inputs.streamlines", "read_streamlines", "mm"),
    ".npz": ("cgamesh.inputs.arrays", "read_npz", "m"),
}


def is_centerline_file(path) -> bool:
    """Whether ``path``'s extension (case-insensitive) names a centreline format."""
    import os

    return os.path.splitext(os.fspath(path))[1].lower() in CENTERLINE_FORMATS


def read_centerlines(path, units: str | None = None) -> Centerlines:
    """Any centreline file by its extension; ``units`` overrides the format's own unit."""
    import importlib
    import os

    from cgamesh.errors import InvalidInputError

    suffix = os.path.splitext(os.fspath(path))[1].lower()
    if suffix not in CENTERLINE_FORMATS:
        raise InvalidInputError(f"{os.fspath(path)}: unknown input format {suffix or '(no extension)'!r}; expected "
                                f"a scene file (.yaml, .yml) or one of {', '.join(CENTERLINE_FORMATS)}")
    if units is not None and units not in METERS_PER_UNIT:
        raise InvalidInputError(f"units must be one of {', '.join(METERS_PER_UNIT)}, got {units!r}")
    module, function, default = CENTERLINE_FORMATS[suffix]
    return getattr(importlib.import_module(module), function)(path, units=units or default)
