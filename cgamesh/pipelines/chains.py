"""The chains of a centreline input: its unbranched chains (a tree's) or its polylines, as one flat index array.

A tree (an SWC skeleton) is split at its branch nodes into unbranched chains
(cgamesh.inputs.trees), each meshed as one tube, the branch nodes closed by junction spheres;
a tractogram's or an array's polylines are its chains. ``ChainList`` holds them without a
Python object per chain; ``take_chain`` hands one chain's pieces on, or skips a chain that
cannot be meshed.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from cgamesh.errors import CgameshError
from cgamesh.inputs.centerlines import Centerlines
from cgamesh.inputs.scene_specs import Location
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.pipelines.tube_options import TubeOptions


@dataclass(frozen=True)
class Chain:
    label: str
    line: int | None
    nodes: np.ndarray


@dataclass(frozen=True)
class ChainList:
    """Every chain (or polyline) of an input as one flat index array: chain i's nodes are
    ``nodes[offsets[i]:offsets[i + 1]]``. No Python object per chain is made up front (a
    tractogram has tens of thousands); ``chains[i]`` builds one, with the label and file line
    that messages, per-chain mesh names and progress use, when it is asked for."""

    lines: Centerlines
    nodes: np.ndarray
    offsets: np.ndarray

    def __len__(self) -> int:
        return len(self.offsets) - 1

    @property
    def counts(self) -> np.ndarray:
        """(M,) nodes of each chain."""
        return np.diff(self.offsets)

    def __getitem__(self, i: int) -> Chain:
        i = int(i)
        if not 0 <= i < len(self):
            raise IndexError(i)
        nodes = self.nodes[self.offsets[i]: self.offsets[i + 1]]
        lines = self.lines
        if not lines.is_tree:
            return Chain(f"streamline {i}", None, nodes)
        ids = nodes if lines.ids is None else lines.ids[nodes]
        word = "nodes" if lines.ids is not None else "points"
        label = (f"{word} {', '.join(str(int(k)) for k in ids)}" if len(ids) <= 4 else
                 f"{word} {int(ids[0])}, {int(ids[1])}, ..., {int(ids[-1])} ({len(ids)} {word})")
        line = int(lines.lines[nodes[1]]) if lines.lines is not None else None
        return Chain(label, line, nodes)

    def __iter__(self):
        return (self[i] for i in range(len(self)))

    def location(self, i: int) -> Location:
        """Chain i's place in its file, as its messages name it."""
        chain = self[i]
        return Location(self.lines.source, chain.line, chain.label)


def split_chains(lines: Centerlines) -> tuple[ChainList, np.ndarray]:
    """The chains (or streamlines) to mesh, and the junction nodes (none for polylines)."""
    if lines.is_tree:
        from cgamesh.inputs.trees import split_tree

        split = split_tree(lines.parents)
        return ChainList(lines, split.nodes, split.offsets), split.junctions
    return (ChainList(lines, np.arange(len(lines.points), dtype=np.int64), np.asarray(lines.offsets, dtype=np.int64)),
            np.zeros(0, dtype=np.int64))


def take_chain(make: Callable[[], "SurfaceMesh | list[SurfaceMesh] | None"], options: TubeOptions, skipped: list[str],
               sink: Callable[[SurfaceMesh], None]) -> None:
    """Hand the piece or pieces of one chain, ``make()``, to ``sink``; a chain that cannot be
    meshed is skipped (its reason in ``skipped``), or raises when ``options.strict``."""
    try:
        piece = make()
    except CgameshError as error:
        if options.strict:
            raise
        skipped.append(str(error))
        return
    for one in piece if isinstance(piece, list) else [] if piece is None else [piece]:
        sink(one)
