"""A tiny input format for the tests of the input table: text polylines (``.polyl``).

One polyline a line, its points' coordinates in a row: ``x0 y0 z0 x1 y1 z1 ...``; blank lines
and lines starting with ``#`` are skipped. The tests register it with
``cgamesh.inputs.formats.register`` and nothing else, to show that a new format needs no other
change: in this process directly, in a child process through a plugin module named in
CGAMESH_PLUGINS (``PLUGIN_SOURCE``).
"""

from __future__ import annotations

import os

import numpy as np

from cgamesh.errors import InvalidInputError
from cgamesh.inputs.arrays import centerlines_from_arrays

NAME = "text polylines"
SUFFIXES = (".polyl",)
UNITS = "mm"
HEADER = b"# polylines"  # what the probe looks for in a file of another suffix

# The whole plugin module a child process imports: the registration, and nothing more.
PLUGIN_SOURCE = """\
from cgamesh.inputs.formats import register
from polyline_format import NAME, SUFFIXES, UNITS, probe, read_polylines

register(NAME, SUFFIXES, read_polylines, units=UNITS, probe=probe)
"""


def probe(head: bytes) -> bool:
    return head.startswith(HEADER)


def read_polylines(path: str | os.PathLike[str], units: str = UNITS):
    """The polylines of a .polyl file as Centerlines in ``units``; a bad line is one error
    naming the file, the line and what was expected."""
    name = os.fspath(path)
    rows = []
    with open(name, encoding="utf-8") as stream:
        for number, line in enumerate(stream, start=1):
            if not line.strip() or line.lstrip().startswith("#"):
                continue
            try:
                values = np.array(line.split(), dtype=np.float64)
            except ValueError:
                raise InvalidInputError(f"{name}:{number}: expected numbers, got {line.strip()!r}") from None
            if len(values) < 6 or len(values) % 3:
                raise InvalidInputError(f"{name}:{number}: expected x y z for two points or more, "
                                        f"got {len(values)} numbers")
            rows.append(values.reshape(-1, 3))
    if not rows:
        raise InvalidInputError(f"{name}: expected at least one polyline, got none")
    offsets = np.concatenate([[0], np.cumsum([len(row) for row in rows])])
    return centerlines_from_arrays({"points": np.concatenate(rows), "offsets": offsets}, name, units)


def write_polylines(path, polylines, header: bool = False) -> None:
    """``polylines`` ((n_i, 3) arrays) as a .polyl file at ``path``."""
    lines = [HEADER.decode()] if header else []
    lines += [" ".join(repr(float(v)) for v in np.ravel(polyline)) for polyline in polylines]
    with open(path, "w", encoding="utf-8") as stream:
        stream.write("\n".join(lines) + "\n")
