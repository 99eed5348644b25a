"""Many meshes into one: a whole neuron or tractogram as one mesh, one draw call.

Positions, normals, UVs, colours and attributes are stacked, faces shifted by each piece's
vertex offset (32-bit indices unless 2^31 vertices are exceeded).

Two channels of the pieces are not carried over, since nothing downstream of a merge reads
them and on a tractogram they were a sixth of the merged mesh:

- the weld: a merged mesh leaves ``weld`` None, and what needs one derives it from the
  positions (``weld_by_position``: the USD writer, the quality report), exactly the map a merge
  would store. The glTF writer never needs it, and weld scratch (five arrays of V integers)
  would come on top of the whole merged mesh, the largest moment of a run.
- ``uv_lengths``: they scale natural UVs, applied to each surface before any merge; one merged
  UV set of many tubes has no one length scale.

``MergedMesh(..., as_written=True)`` holds the normals, colours and attributes the way the glTF
writer stores them, float32, for a run whose every output is a plain (unquantized) glTF file:
the normals as the writer's single rounding of each float64 normal over its length (so the
writer copies them as they are), colours and attributes rounded once to float32 (the writer's
own cast, and clipping to [0, 1] commutes with it). Files are byte for byte those written from
the float64 mesh; on a tractogram the merged mesh holds 81 bytes a vertex instead of 101 (its
GLB stores 61). Attributes that colours are computed from after the merge stay float64 (``exact_attributes``).

``MergedMesh`` takes the pieces one at a time into arrays allocated once, so a producer that
hands over each piece as it is made (the batched pass, chunk by chunk) never holds the pieces
and the merged mesh at once: peak memory is the merged mesh and one piece.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from cgamesh.meshing.mesh import SurfaceMesh

# Per-vertex channels (name, columns); a channel is kept when every piece has it.
_CHANNELS = (("positions", 3), ("normals", 3), ("uvs", 2), ("tangents", 4), ("colors", 3))


def merge(pieces: Sequence[SurfaceMesh], name: str) -> SurfaceMesh:
    """One mesh of every piece, in order.

    Colours are kept when every piece has them, and an attribute when every piece has it;
    tangents when every piece has them. ``double_sided`` if any piece is. No weld and no
    ``uv_lengths`` (see the module).
    """
    if not pieces:
        raise ValueError("merge needs at least one mesh")
    merged = MergedMesh(sum(p.vertex_count for p in pieces), sum(p.triangle_count for p in pieces))
    for piece in pieces:
        merged.append(piece)
    return merged.finish(name)


class MergedMesh:
    """Pieces appended one by one into one mesh (``merge``'s result, piece for piece).

    ``vertices`` and ``triangles`` are the expected totals; more is accepted (the arrays grow),
    fewer costs nothing (untouched pages of the allocation are never made resident).
    ``as_written``, ``exact_attributes``: see the module.
    """

    def __init__(self, vertices: int, triangles: int, *, as_written: bool = False,
                 exact_attributes: tuple[str, ...] = ()) -> None:
        self._as_written = as_written
        self._exact = frozenset(exact_attributes)
        self._capacity = max(int(vertices), 1)
        self._face_capacity = max(int(triangles), 1)
        self._vertices = self._triangles = self._pieces = 0
        self._channels: dict[str, np.ndarray | None] = {}
        self._attributes: dict[str, np.ndarray] | None = None
        self._faces = np.empty((self._face_capacity, 3), dtype=_index_type(self._capacity))
        self._double_sided = False

    def append(self, piece: SurfaceMesh) -> None:
        v, f = piece.vertex_count, piece.triangle_count
        self._reserve(self._vertices + v, self._triangles + f)
        rows = slice(self._vertices, self._vertices + v)
        first = self._pieces == 0
        for channel, columns in _CHANNELS:
            values = getattr(piece, channel)
            if first and values is not None:
                self._channels[channel] = np.empty((self._capacity, columns), dtype=self._dtype(channel))
            if values is None:
                self._channels[channel] = None  # a piece without it: the merged mesh has none
            elif channel == "normals" and self._as_written:
                _unit_float32(values, self._channels[channel][rows])
            elif self._channels.get(channel) is not None:
                self._channels[channel][rows] = values
        if first:
            self._attributes = None if not piece.attributes else {
                key: np.empty(self._capacity, dtype=self._dtype(key, attribute=True)) for key in piece.attributes}
        elif self._attributes is not None:
            if not piece.attributes:
                self._attributes = None
            else:
                self._attributes = {k: a for k, a in self._attributes.items() if k in piece.attributes}
        for key, array in (self._attributes or {}).items():
            array[rows] = piece.attributes[key]
        np.add(piece.faces, self._vertices, out=self._faces[self._triangles:self._triangles + f], casting="unsafe")
        self._double_sided |= bool(piece.double_sided)
        self._vertices += v
        self._triangles += f
        self._pieces += 1

    def _dtype(self, name: str, attribute: bool = False) -> type:
        """float32 for what the glTF writer stores as float32 when ``as_written``, else float64."""
        written = ((attribute and name not in self._exact) or name in ("normals", "colors"))
        return np.float32 if self._as_written and written else np.float64

    @property
    def empty(self) -> bool:
        return self._pieces == 0

    def finish(self, name: str) -> SurfaceMesh:
        """The merged mesh (no weld, see the module); 32-bit indices below 2^31 vertices."""
        if not self._pieces:
            raise ValueError("merge needs at least one mesh")
        v = self._vertices
        index = _index_type(v)
        channels = {k: (None if a is None else a[:v]) for k, a in self._channels.items()}
        faces = self._faces[:self._triangles].astype(index, copy=False)
        return SurfaceMesh(
            name=name, positions=channels["positions"], normals=channels["normals"], uvs=channels["uvs"],
            faces=faces, double_sided=self._double_sided,
            tangents=channels.get("tangents"), colors=channels.get("colors"),
            attributes=None if self._attributes is None else {k: a[:v] for k, a in sorted(self._attributes.items())})

    def _reserve(self, vertices: int, triangles: int) -> None:
        if vertices > self._capacity:
            self._capacity = max(vertices, 2 * self._capacity)
            for channel, array in self._channels.items():
                if array is not None:
                    self._channels[channel] = _grown(array, self._capacity, self._vertices)
            if self._attributes is not None:
                self._attributes = {k: _grown(a, self._capacity, self._vertices) for k, a in self._attributes.items()}
        if triangles > self._face_capacity or _index_type(vertices) != self._faces.dtype:
            self._face_capacity = max(triangles, 2 * self._face_capacity)
            self._faces = _grown(self._faces.astype(_index_type(vertices), copy=False), self._face_capacity,
                                 self._triangles)


def _unit_float32(normals: np.ndarray, out: np.ndarray) -> None:
    """out (n, 3) float32 = normals / |normals| (n, 3) float64, each rounded once: what the glTF
    writer stores for a float64 normal (its lengths as the writer's checks measure them)."""
    from cgamesh.export.checks import vector_lengths

    length = vector_lengths(np.asarray(normals, dtype=np.float64))
    for j in range(3):
        np.divide(normals[:, j], length, out=out[:, j], casting="same_kind")


def _index_type(vertices: int) -> type:
    return np.int32 if vertices < 2**31 else np.int64


def _grown(array: np.ndarray, rows: int, used: int) -> np.ndarray:
    bigger = np.empty((rows,) + array.shape[1:], dtype=array.dtype)
    bigger[:used] = array[:used]
    return bigger
