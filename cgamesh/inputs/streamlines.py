"""Tractograms (.trk, .tck through nibabel; .trx through trx-python) read into Centerlines.

Points are read in RAS+ millimetres (nibabel's and TRX's world space), so a .trk's voxel
order and a .tck's header need no further care. Per-point data with one value a point
(a .trk's or .trx's scalars, e.g. ``fa``) become named scalars; a file's own colours or other
multi-valued data are ignored. A file the library refuses (a .trk whose header and data
disagree, a truncated file) is one line naming the file and what the library found; a
streamline with a NaN or an infinite coordinate is one line naming its index.

nibabel's package ``__init__`` imports every image format it reads (NIfTI, CIFTI's XML,
MINC, FreeSurfer, GIFTI), scipy and OpenSSL's bindings: 13 MB of resident memory, more than a
third of what meshing the fornix holds. Its ``streamlines`` subpackage needs none of that
(two dozen of nibabel's modules, 2 MB), so ``.trk`` and ``.tck`` are read through
``nibabel.streamlines`` imported on its own (``_streamline_reader``); a process that has
imported nibabel already uses that.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
import sys
import warnings
from functools import cache
from types import ModuleType

import numpy as np

from cgamesh.errors import InvalidInputError, NonFiniteInputError
from cgamesh.inputs.centerlines import Centerlines
from cgamesh.optional import require

STREAMLINE_FORMATS = (".trk", ".tck", ".trx")


def read_streamlines(path: str | os.PathLike[str], units: str = "mm") -> Centerlines:
    """The streamlines of a .trk, .tck or .trx file, as polylines in ``units`` (the files' are mm)."""
    name = os.fspath(path)
    if not os.path.isfile(name):
        raise InvalidInputError(f"{name}: cannot read the file: no such file")
    suffix = os.path.splitext(name)[1].lower()
    if suffix == ".trx":
        points, offsets, per_point = _read_trx(name)
    elif suffix in (".trk", ".tck"):
        points, offsets, per_point = _read_nibabel(name)
    else:
        raise InvalidInputError(f"{name}: expected a tractogram ({', '.join(STREAMLINE_FORMATS)}), got {suffix!r}")
    points = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
    offsets = np.asarray(offsets, dtype=np.int64)
    scalars = {}
    for key, values in per_point.items():
        values = np.asarray(values, dtype=np.float64)
        if values.ndim == 2 and values.shape[1] == 1:
            values = values[:, 0]
        if values.ndim == 1 and len(values) == len(points):
            scalars[key] = np.ascontiguousarray(values)
    _refuse_non_finite(points, offsets, scalars, name)
    return Centerlines(points=points, offsets=offsets, scalars=scalars, units=units, source=name)


def _read_nibabel(name: str):
    reader = _streamline_reader(f"reading {os.path.basename(name)}")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # nibabel warns where the header and the data disagree
            loaded = reader.load(name)
    except Exception as error:  # nibabel's HeaderError, DataError, struct and numpy errors
        raise InvalidInputError(f"{name}: expected a valid {os.path.splitext(name)[1]} file: "
                                f"{_one_line(error)}") from None
    tractogram = loaded.tractogram
    streamlines = tractogram.streamlines
    # nibabel reads what the data holds; a header that counts otherwise is a damaged file.
    stated = _stated_count(name, loaded.header)
    if stated is not None and stated > 0 and stated != len(streamlines):
        raise InvalidInputError(f"{name}: expected {int(stated)} streamlines as the header states, "
                                f"the data holds {len(streamlines)}")
    per_point = {key: value.get_data() for key, value in tractogram.data_per_point.items()}
    return streamlines.get_data(), _boundaries(streamlines._offsets, streamlines._lengths), per_point


def _streamline_reader(purpose: str) -> ModuleType:
    """``nibabel.streamlines``, without running nibabel's package ``__init__`` (see the module)."""
    if "nibabel" in sys.modules:  # imported already (or made unimportable): as it is
        return require("nibabel", "neuro", purpose).streamlines
    return _streamlines_alone() or require("nibabel", "neuro", purpose).streamlines


@cache
def _streamlines_alone() -> ModuleType | None:
    """``nibabel.streamlines`` imported under a bare ``nibabel`` package module (its ``__path__``
    and no ``__init__``), so only the modules it imports itself are loaded; None when nibabel
    is missing or that import fails (then the whole package is imported, or its absence reported).

    Every ``nibabel`` module loaded here is taken out of ``sys.modules`` again: a later ``import
    nibabel`` in the process loads the real package and its modules afresh, consistently, and
    nothing of nibabel's leaves this module (the reader returns plain arrays).
    """
    spec = importlib.util.find_spec("nibabel")
    if spec is None or not spec.submodule_search_locations:
        return None
    before = set(sys.modules)
    sys.modules["nibabel"] = importlib.util.module_from_spec(spec)  # __path__ set, __init__ not run
    try:
        return importlib.import_module("nibabel.streamlines")
    except Exception:  # a nibabel whose streamlines need the package's own names: the whole package
        return None
    finally:
        for key in set(sys.modules) - before:
            if key == "nibabel" or key.startswith("nibabel."):
                del sys.modules[key]


def _stated_count(name: str, header: dict) -> int | None:
    """The streamline count a .trk header states (0 or None: not stated).

    nibabel overwrites the header's count with what it read, so it is read from the header's
    bytes here (offset 988, in the byte order of the header size at 996). A .tck's ``count``
    is not checked: writers that stream (MRtrix, MATLAB scripts) leave it stale in real files,
    and the format ends the data with its own marker.
    """
    if name.lower().endswith(".tck"):
        return None
    import struct

    with open(name, "rb") as f:
        raw = f.read(1000)
    if len(raw) < 1000:
        return None
    order = "<" if struct.unpack("<i", raw[996:1000])[0] == 1000 else ">"
    return struct.unpack(order + "i", raw[988:992])[0]


def _read_trx(name: str):
    require("nibabel", "neuro", f"reading {os.path.basename(name)}")
    trx = require("trx.trx_file_memmap", "neuro", f"reading {os.path.basename(name)}")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            trx_file = trx.load(name)
    except Exception as error:
        raise InvalidInputError(f"{name}: expected a valid .trx file: {_one_line(error)}") from None
    try:
        streamlines = trx_file.streamlines
        points = np.array(streamlines.get_data())
        offsets = _boundaries(streamlines._offsets, streamlines._lengths)
        per_point = {key: np.array(value.get_data()) for key, value in trx_file.data_per_vertex.items()}
    finally:
        trx_file.close()
    return points, offsets, per_point


def _boundaries(starts: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """(M + 1,) boundaries from an ArraySequence's starts and lengths (which must tile the data)."""
    starts = np.asarray(starts, dtype=np.int64)
    lengths = np.asarray(lengths, dtype=np.int64)
    if len(starts) and not np.array_equal(starts[1:], starts[:-1] + lengths[:-1]):
        order = np.argsort(starts)
        starts, lengths = starts[order], lengths[order]
    return np.concatenate([starts, [starts[-1] + lengths[-1]]]) if len(starts) else np.zeros(1, dtype=np.int64)


def _refuse_non_finite(points: np.ndarray, offsets: np.ndarray, scalars: dict, name: str) -> None:
    bad = ~np.isfinite(points).all(axis=1)
    for key, values in scalars.items():
        bad |= ~np.isfinite(values)
    first = np.flatnonzero(bad)
    if first.size:
        streamline = int(np.searchsorted(offsets, first[0], side="right") - 1)
        at = int(first[0] - offsets[streamline])
        raise NonFiniteInputError(f"{name}: streamline {streamline}: expected finite coordinates and values, "
                                  f"got {points[first[0]].tolist()} at point {at}")


def _one_line(error: BaseException) -> str:
    text = " ".join(str(error).split()) or type(error).__name__
    return text if len(text) <= 300 else text[:297] + "..."
