"""SWC neuron skeletons (one node a line: id, type, x, y, z, radius, parent) read into Centerlines.

Our own parser rather than MorphIO's: MorphIO refuses real files that the field's tools write
and read every day (navis' hemibrain skeletons have soma nodes whose parent is a neurite node,
and several roots), and its errors do not all name a line. Here every record is checked and a
mistake is one line naming the file, the line and what was expected:

    neuron.swc:12: expected 7 columns (id type x y z radius parent), got 6

Accepted: ``#`` comments and blank lines anywhere, ids in any order, parents before or after
their children, several roots (parent -1; any negative parent is a root), radius 0 (the
builder then needs a minimum radius). Refused: a wrong column count, ids or types or parents
that are not whole numbers, NaN or infinite numbers, a negative radius, a duplicate id, a
parent id that no node has, and cycles.
"""

from __future__ import annotations

import os

import numpy as np

from cgamesh.errors import InvalidInputError, NonFiniteInputError
from cgamesh.inputs.centerlines import Centerlines
from cgamesh.inputs.trees import unrooted

COLUMNS = "id type x y z radius parent"
SOMA = 1  # the SWC structure type of soma nodes


def read_swc(path: str | os.PathLike[str], units: str = "um") -> Centerlines:
    """The skeleton of an SWC file; coordinates and radii in ``units`` (SWC's are micrometres)."""
    name = os.fspath(path)
    try:
        with open(name, encoding="utf-8", errors="replace") as f:
            text = f.read()
    except OSError as error:
        raise InvalidInputError(f"{name}: cannot read the file: {error.strerror or error}") from None
    return parse_swc(text, name, units)


def parse_swc(text: str, name: str = "<string>", units: str = "um") -> Centerlines:
    """The skeleton of SWC text; ``name`` is used in messages."""
    rows, lines = [], []
    for number, raw in enumerate(text.splitlines(), start=1):
        content = raw.split("#", 1)[0].split()
        if not content:
            continue
        if len(content) != 7:
            raise InvalidInputError(f"{name}:{number}: expected 7 columns ({COLUMNS}), got {len(content)}")
        rows.append(content)
        lines.append(number)
    if not rows:
        raise InvalidInputError(f"{name}: expected at least one node ({COLUMNS} a line), found none")
    lines = np.array(lines, dtype=np.int64)
    table = _numbers(rows, lines, name)
    ids = _whole(table[:, 0], lines, name, "id")
    kinds = _whole(table[:, 1], lines, name, "type")
    parent_ids = _whole(table[:, 6], lines, name, "parent")
    points = np.ascontiguousarray(table[:, 2:5])
    radii = np.ascontiguousarray(table[:, 5])
    bad = np.flatnonzero(~np.isfinite(table[:, 2:6]).all(axis=1))
    if bad.size:
        i = bad[0]
        raise NonFiniteInputError(f"{name}:{lines[i]}: expected finite x y z radius, got "
                                  f"{' '.join(rows[i][2:6])}")
    bad = np.flatnonzero(radii < 0.0)
    if bad.size:
        i = bad[0]
        raise InvalidInputError(f"{name}:{lines[i]}: expected a radius >= 0, got {rows[i][5]}")
    parents = _parent_indices(ids, parent_ids, lines, name)
    _refuse_cycles(parents, ids, lines, name)
    return Centerlines(points=points, radii=radii, parents=parents, units=units, source=name, ids=ids,
                       kinds=kinds, lines=lines)


def _numbers(rows: list[list[str]], lines: np.ndarray, name: str) -> np.ndarray:
    try:
        return np.array(rows, dtype=np.float64)
    except ValueError:
        pass
    for row, line in zip(rows, lines):  # only on the error path: find the record and the column
        for column, value in zip(COLUMNS.split(), row):
            try:
                float(value)
            except ValueError:
                raise InvalidInputError(f"{name}:{line}: expected a number for {column}, got {value!r}") from None
    raise AssertionError("unreachable")


def _whole(values: np.ndarray, lines: np.ndarray, name: str, column: str) -> np.ndarray:
    bad = np.flatnonzero(~np.isfinite(values) | (values != np.round(values)) | (np.abs(values) > 2.0**53))
    if bad.size:
        i = bad[0]
        raise InvalidInputError(f"{name}:{lines[i]}: expected a whole number for {column}, got {values[i]!r}")
    return values.astype(np.int64)


def _parent_indices(ids: np.ndarray, parent_ids: np.ndarray, lines: np.ndarray, name: str) -> np.ndarray:
    """Each node's parent as an index into the nodes (-1 for roots)."""
    order = np.argsort(ids, kind="stable")
    sorted_ids = ids[order]
    repeated = np.flatnonzero(sorted_ids[1:] == sorted_ids[:-1])
    if repeated.size:
        first, second = sorted(order[repeated[0]: repeated[0] + 2])
        raise InvalidInputError(f"{name}:{lines[second]}: expected a unique node id, got {ids[second]} "
                                f"again (first on line {lines[first]})")
    is_root = parent_ids < 0
    where = np.searchsorted(sorted_ids, parent_ids)
    where = np.minimum(where, len(ids) - 1)
    found = sorted_ids[where] == parent_ids
    missing = np.flatnonzero(~is_root & ~found)
    if missing.size:
        i = missing[0]
        raise InvalidInputError(f"{name}:{lines[i]}: expected the parent id of a node in the file (or -1), "
                                f"got {parent_ids[i]}, which no node has")
    return np.where(is_root, -1, order[where]).astype(np.int64)


def _refuse_cycles(parents: np.ndarray, ids: np.ndarray, lines: np.ndarray, name: str) -> None:
    stuck = unrooted(parents)
    if stuck.size:
        i = _on_cycle(parents, stuck[0])
        raise InvalidInputError(f"{name}:{lines[i]}: expected the parents to form a tree, but node {ids[i]} "
                                f"is its own ancestor (a cycle)")


def _on_cycle(parents: np.ndarray, start: int) -> int:
    """A node on the cycle above ``start`` (a walk, only on the error path)."""
    seen = set()
    node = start
    while node not in seen:
        seen.add(node)
        node = int(parents[node])
    return node
