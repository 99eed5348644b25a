"""Plain arrays (.npz, or arrays in memory) read into Centerlines.

An .npz holds ``points`` (N, 3) and either ``offsets`` (the start of each polyline, (M,) or
with N appended, (M + 1,)) or ``parents`` ((N,) parent index, -1 for a root: a tree), and
optionally ``radii`` (N,). Any other (N,) float array is a per-point scalar by its name.
"""

from __future__ import annotations

import os
import zipfile

import numpy as np

from cgamesh.errors import InvalidInputError, NonFiniteInputError
from cgamesh.inputs.centerlines import Centerlines
from cgamesh.inputs.trees import unrooted

KNOWN = ("points", "offsets", "radii", "parents")


def read_npz(path: str | os.PathLike[str], units: str = "m") -> Centerlines:
    """The centrelines of an .npz file (see the module's docstring)."""
    name = os.fspath(path)
    try:
        with np.load(name, allow_pickle=False) as data:
            arrays = {key: np.array(data[key]) for key in data.files}
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as error:
        raise InvalidInputError(f"{name}: expected an .npz file of arrays: {error}") from None
    return centerlines_from_arrays(arrays, name, units)


def centerlines_from_arrays(arrays: dict[str, np.ndarray], name: str = "<arrays>", units: str = "m") -> Centerlines:
    """Centrelines from a mapping of arrays named as in an .npz; every mistake names ``name`` and the array."""
    if "points" not in arrays:
        raise InvalidInputError(f"{name}: expected an array 'points' (N, 3), found {sorted(arrays) or 'none'}")
    points = _numeric(arrays["points"], name, "points")
    if points.ndim != 2 or points.shape[1] != 3 or len(points) == 0:
        raise InvalidInputError(f"{name}: points: expected shape (N, 3) with N >= 1, got {points.shape}")
    n = len(points)
    bad = np.flatnonzero(~np.isfinite(points).all(axis=1))
    if bad.size:
        raise NonFiniteInputError(f"{name}: points[{bad[0]}]: expected finite coordinates, got {points[bad[0]].tolist()}")
    radii = None
    if "radii" in arrays:
        radii = _numeric(arrays["radii"], name, "radii").reshape(-1) if np.ndim(arrays["radii"]) else None
        if radii is None or len(radii) != n:
            raise InvalidInputError(f"{name}: radii: expected shape ({n},), got {np.shape(arrays['radii'])}")
        bad = np.flatnonzero(~np.isfinite(radii) | (radii < 0.0))
        if bad.size:
            raise InvalidInputError(f"{name}: radii[{bad[0]}]: expected a finite radius >= 0, got {radii[bad[0]]}")
    if ("offsets" in arrays) == ("parents" in arrays):
        raise InvalidInputError(f"{name}: expected exactly one of 'offsets' (polylines) and 'parents' (a tree), "
                                f"found {'both' if 'offsets' in arrays else 'neither'}")
    parents = offsets = None
    if "parents" in arrays:
        parents = _indices(arrays["parents"], name, "parents")
        if parents.shape != (n,):
            raise InvalidInputError(f"{name}: parents: expected shape ({n},), got {parents.shape}")
        bad = np.flatnonzero(parents >= n)
        if bad.size:
            raise InvalidInputError(f"{name}: parents[{bad[0]}]: expected a point index below {n} or -1, "
                                    f"got {parents[bad[0]]}")
        parents = np.where(parents < 0, -1, parents)
        _refuse_cycles(parents, name)
    else:
        offsets = _indices(arrays["offsets"], name, "offsets").reshape(-1)
        if len(offsets) == 0 or offsets[-1] != n:
            offsets = np.append(offsets, n)
        if offsets[0] != 0 or np.any(np.diff(offsets) < 0):
            raise InvalidInputError(f"{name}: offsets: expected polyline starts increasing from 0 up to {n}, "
                                    f"got {offsets[:-1].tolist()[:8]}")
    scalars = {}
    for key, value in arrays.items():
        if key not in KNOWN and np.ndim(value) == 1 and len(value) == n and np.issubdtype(np.asarray(value).dtype, np.number):
            values = np.asarray(value, dtype=np.float64)
            bad = np.flatnonzero(~np.isfinite(values))
            if bad.size:
                raise NonFiniteInputError(f"{name}: {key}[{bad[0]}]: expected a finite value, got {values[bad[0]]}")
            scalars[key] = values
    return Centerlines(points=points, radii=radii, parents=parents, offsets=offsets, scalars=scalars,
                       units=units, source=name)


def _numeric(value, name: str, key: str) -> np.ndarray:
    array = np.asarray(value)
    if not np.issubdtype(array.dtype, np.number) or np.issubdtype(array.dtype, np.complexfloating):
        raise InvalidInputError(f"{name}: {key}: expected real numbers, got dtype {array.dtype}")
    return np.ascontiguousarray(array, dtype=np.float64)


def _indices(value, name: str, key: str) -> np.ndarray:
    array = np.asarray(value)
    if not np.issubdtype(array.dtype, np.integer):
        raise InvalidInputError(f"{name}: {key}: expected whole numbers, got dtype {array.dtype}")
    return np.ascontiguousarray(array, dtype=np.int64)


def _refuse_cycles(parents: np.ndarray, name: str) -> None:
    stuck = unrooted(parents)
    if stuck.size:
        raise InvalidInputError(f"{name}: parents[{stuck[0]}]: expected a tree, but following parents from "
                                f"point {stuck[0]} never reaches a root (a cycle)")
