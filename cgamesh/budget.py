"""The resource budget: what a request will allocate, estimated before it allocates, against a limit.

Every command that can be asked for more memory than the machine has (a mesh at a huge
resolution, a tolerance far below the surface's size, a huge render, the ray tracer's
polynomials of a high-order curve) prices the request first with the estimates below and
refuses what exceeds the limit with one line naming the knob::

    cgamesh: error: kb_tube.yaml:5: surfaces[0].resolution asks for 224 GiB of mesh
    (100000 x 100000); the limit is 9.6 GiB (--max-memory)

Work that can stream does instead: the renderer traces and writes the image in bands of rows,
``verify`` traces the vertices in chunks, each sized to fit the limit.

The limit is ``--max-memory`` (a size such as ``2G``, ``512MiB`` or plain bytes); by default
DEFAULT_FRACTION of the memory available when the command starts (``MemAvailable`` of
/proc/meminfo, capped by a cgroup's memory.max; else os.sysconf's available pages; else
FALLBACK_AVAILABLE).

The per-vertex figures are peaks measured with tracemalloc (numpy reports its buffers to it) on
circle and point-pair surfaces, rounded up; tests/test_budget.py checks that every estimate is
at least the measured peak of the work it prices.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass

from cgamesh.errors import CgameshError

DEFAULT_FRACTION = 0.5
FALLBACK_AVAILABLE = 4 * 2**30
# Always allowed, whatever the limit says: the interpreter, the libraries, a small mesh.
FIXED_OVERHEAD = 32 * 2**20

# Bytes per vertex of the arrays a mesh keeps (positions, normals, uvs, faces, weld, ...), and
# the transient peak of meshing one surface on top of them; per ring (or ruling) for the
# per-ring algebra.
HELD_PER_VERTEX = 200
MESHING_PER_VERTEX = {"circles": 500, "point_pairs": 900}
MESHING_PER_RING = {"circles": 4096, "point_pairs": 8192}
# Bytes per vertex each output format allocates while it is written (its own arrays and the
# file's bytes), beyond the meshes; measured per format as above.
# glTF streams its binary chunk in blocks: the normals' lengths (8 bytes) and slack.
EXPORT_PER_VERTEX = {".glb": 64, ".gltf": 64, ".usda": 400, ".usdc": 250, ".usd": 250, ".usdz": 250,
                     ".obj": 1600, ".ply": 700, ".stl": 1200}
TANGENTS_PER_VERTEX = 200  # analytic tangents while meshing, TANGENT while writing

_UNITS = {"": 1, "b": 1, "k": 2**10, "kb": 10**3, "kib": 2**10, "m": 2**20, "mb": 10**6, "mib": 2**20,
          "g": 2**30, "gb": 10**9, "gib": 2**30, "t": 2**40, "tb": 10**12, "tib": 2**40}


class ResourceLimitError(CgameshError):
    """A request that needs more memory than the budget allows (--max-memory)."""


def available_memory() -> int | None:
    """Bytes of memory available to this process now, or None when the system does not say."""
    available = None
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    available = int(line.split()[1]) * 1024
                    break
    except (OSError, ValueError, IndexError):
        available = None
    if available is None:
        try:
            available = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
        except (AttributeError, OSError, ValueError):
            available = None
    cgroup = _cgroup_room()
    if cgroup is not None:
        available = cgroup if available is None else min(available, cgroup)
    return available if available is None or available > 0 else None


def _cgroup_room() -> int | None:
    """memory.max - memory.current of this process's cgroup (v2), when it has a limit."""
    try:
        with open("/sys/fs/cgroup/memory.max", encoding="ascii") as f:
            text = f.read().strip()
        if text == "max":
            return None
        with open("/sys/fs/cgroup/memory.current", encoding="ascii") as f:
            return max(0, int(text) - int(f.read().strip()))
    except (OSError, ValueError):
        return None


def default_limit() -> int:
    """DEFAULT_FRACTION of the available memory (FALLBACK_AVAILABLE when unknown)."""
    available = available_memory()
    return int(DEFAULT_FRACTION * (available if available is not None else FALLBACK_AVAILABLE))


def parse_size(text: str) -> int:
    """Bytes from ``2G``, ``1.5GiB``, ``512M``, ``500MB``, ``1e9``: K/M/G/T and KiB/MiB/... are
    powers of 1024, kB/MB/GB/TB powers of 1000. ValueError for anything else."""
    match = re.fullmatch(r"\s*([0-9]*\.?[0-9]+(?:[eE][+-]?[0-9]+)?)\s*([A-Za-z]*)\s*", text)
    if not match or match.group(2).lower() not in _UNITS:
        raise ValueError(f"expected a size such as 2G, 512MiB or 1e9 (bytes), got {text!r}")
    value = float(match.group(1)) * _UNITS[match.group(2).lower()]
    if not (value >= 1 and math.isfinite(value)):
        raise ValueError(f"expected a size of at least 1 byte, got {text!r}")
    return int(value)


def format_size(size: float) -> str:
    """``224 GiB``, ``9.6 GiB``, ``512 MiB``, ``3.1e+12 TiB``: three significant figures at most."""
    size = float(min(size, 10**300))  # a count like 10**30 squared still prints
    for unit, scale in (("TiB", 2**40), ("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if size >= scale:
            value = size / scale
            return f"{value:.3g} {unit}" if value < 1e6 else f"{value:.2g} {unit}"
    return f"{int(size)} bytes"


@dataclass(frozen=True)
class Budget:
    """A memory limit in bytes; ``knob`` is how a user changes it (named in every refusal)."""

    limit: int
    knob: str = "--max-memory"

    @classmethod
    def of(cls, max_memory: "int | str | Budget | None") -> "Budget":
        """The budget for an API argument: a Budget, bytes, a size string, or None (the default)."""
        if isinstance(max_memory, Budget):
            return max_memory
        if max_memory is None:
            return cls(default_limit())
        if isinstance(max_memory, str):
            return cls(parse_size(max_memory))
        return cls(int(max_memory))

    def allows(self, size: float) -> bool:
        return size <= max(self.limit, FIXED_OVERHEAD)

    def require(self, size: float, where: str, what: str, advice=None) -> None:
        """Refuse (ResourceLimitError) when ``size`` bytes exceed the limit. The message reads
        ``{where} asks for {size} of {what}; the limit is {limit} ({knob})``, then
        ``; {advice(limit)}`` when ``advice`` (what would fit, from the limit) gives one."""
        if not self.allows(size):
            hint = advice(max(self.limit, FIXED_OVERHEAD)) if advice is not None else None
            raise ResourceLimitError(f"{where} asks for {format_size(size)} of {what}; "
                                     f"the limit is {format_size(self.limit)} ({self.knob})"
                                     + (f"; {hint}" if hint else ""))

    def items(self, size_each: float, where: str, what: str, most: int) -> int:
        """How many items of ``size_each`` bytes fit at once (at most ``most``, at least 1): the
        chunk of a streamed job. Refuses when not even one fits."""
        self.require(size_each, where, what)
        room = max(self.limit, FIXED_OVERHEAD)
        return int(max(1, min(most, room // max(size_each, 1.0))))


def grid_vertices(kind: str, around: int, along: int, caps: bool = False) -> int:
    """Vertices of a fixed-resolution mesh: rings of around + 1 (the seam column) for circles,
    around per ruling for ribbons, plus the caps' discs."""
    if kind == "circles":
        return (around + 1) * along + (2 * (around + 2) if caps else 0)
    return around * along


def surface_bytes(kind: str, around: int, along: int, caps: bool = False, tangents: bool = False) -> tuple[int, int]:
    """(held, peak) bytes of one surface's mesh: what it keeps, and the most it allocates while
    it is made (the kept arrays included)."""
    vertices = grid_vertices(kind, around, along, caps)
    held = (HELD_PER_VERTEX + (TANGENTS_PER_VERTEX if tangents else 0)) * vertices
    peak = held + MESHING_PER_VERTEX[kind] * vertices + MESHING_PER_RING[kind] * along
    return held, peak


def output_suffixes(outputs) -> list[str]:
    """The extensions of ``outputs`` (file names, or extensions already), as export_bytes takes them."""
    return [("." + str(o).rsplit(".", 1)[-1]) if "." in str(o) else str(o) for o in outputs]


def export_bytes(suffixes, vertices: int, tangents: bool = False) -> int:
    """The most any one of the outputs (written one after another) allocates for ``vertices``."""
    per_vertex = max((EXPORT_PER_VERTEX.get(s.lower(), max(EXPORT_PER_VERTEX.values())) for s in suffixes),
                     default=0)
    return (per_vertex + (TANGENTS_PER_VERTEX if tangents else 0)) * vertices


# The batched pass of centreline inputs meshes chunks of at most this many rings (its
# CHUNK_RINGS, and one chain longer than that) into the merged mesh (which is not welded:
# cgamesh.meshing.merge).
BATCHED_CHUNK_RINGS = 2048


def centerline_bytes(points: int, chains: int, around: int, subdivide: int, suffixes=(),
                     tangents: bool = False, batched: bool = False,
                     longest_chain: int | None = None) -> tuple[int, int]:
    """(vertices, peak bytes) of tubes along ``chains`` centreline chains of ``points`` nodes in
    all, ``subdivide`` rings between nodes, with a junction sphere per chain at most: an upper
    estimate made before anything is read into meshes, written to ``suffixes``.

    ``batched``: the batched pass (cgamesh.meshing.batch_pass) makes the meshes, a chunk at a
    time into the merged mesh: the merged mesh and one chunk's meshing (of at most
    ``longest_chain`` nodes' rings beyond a chunk), not a whole mesh's meshing peak."""
    rings = points * (subdivide + 1) + chains
    sphere = (around + 1) * (around // 2 + 1)
    vertices = rings * (around + 1) + chains * sphere
    if batched:
        chunk_rings = min(rings, BATCHED_CHUNK_RINGS + (points if longest_chain is None else longest_chain)
                          * (subdivide + 1))
        _, chunk = surface_bytes("circles", around, chunk_rings, tangents=tangents)
        peak = HELD_PER_VERTEX * vertices + chunk
    else:
        _, peak = surface_bytes("circles", around, rings + chains * (around // 2 + 1), tangents=tangents)
    return vertices, peak + export_bytes(suffixes, vertices, tangents)
