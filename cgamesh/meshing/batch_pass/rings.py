"""Rings, normals, UVs and faces of many motor tubes at once: every chain's rings as rows of the
one circle mesher (cgamesh.meshing.circles.mesh_rings).

For every chain of ``Motions`` the rings sit where a chain meshed alone puts them
(``np.linspace(0, spans, along)``, reproduced with linspace's own arithmetic) and are read out
of the same circle blades (``circle_rows``, blade-major) in the chain's local frame. A chain
whose normal spline is not certified away from zero by its bound is scanned as a motor
surface's ``check_projection_exists`` scans it; one that loses its plane there, or whose
rings all coincide, gets its error. Rings that would coincide in an output file are left out
(``dropped``: such a chain's attributes follow its arc length, not its rings).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cgamesh.geometry.motors import Motions
from cgamesh.geometry.surface import SCAN_SAMPLES_PER_SEGMENT
from cgamesh.meshing.batch_pass.circle_rows import CircleRows
from cgamesh.meshing.circles import CircleSurfaces, mesh_rings
from cgamesh.meshing.ring_rows import RingRows, SurfaceRows


@dataclass(frozen=True)
class TubeArrays:
    """The tubes of every chain, chain after chain (those with an error are not to be used).

    positions, normals (V, 3); uvs (V, 2); faces (F, 3) int32, indices local to each chain, in
    rows of 2 around triangles, one row per pair of consecutive rings (fewer where a triangle
    of no area was dropped); ring_chain (R,), ring_local (R,) the chain of each kept ring and
    its index within its chain (a ring's around + 1 vertices are consecutive); face_counts (C,)
    triangles per chain; uv_lengths (C, 2) per chain (circumference, length); errors {chain:
    error} of the chains that cannot be meshed (their vertices are not to be used); dropped
    (C,) chains with rings left out as coincident.
    """

    positions: np.ndarray
    normals: np.ndarray
    uvs: np.ndarray
    faces: np.ndarray
    ring_chain: np.ndarray
    ring_local: np.ndarray
    face_counts: np.ndarray
    uv_lengths: np.ndarray
    errors: dict
    dropped: np.ndarray


def _linspace_parameters(spans: np.ndarray, along: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """t of every ring (``np.linspace(0, spans, along)`` per chain, bit for bit) and its chain."""
    chain = np.repeat(np.arange(len(along)), along)
    first = np.concatenate([[0], np.cumsum(along)[:-1]])
    k = (np.arange(int(along.sum())) - first[chain]).astype(np.float64)
    step = spans.astype(np.float64) / (along - 1)
    t = k * step[chain]
    t[first + along - 1] = spans
    return t, chain


def _rows(motions: Motions, origin: np.ndarray, scale: np.ndarray, chain: np.ndarray,
          t: np.ndarray) -> RingRows:
    """The circles of chains ``chain`` (R,) at parameters t (R,), in world units and each chain's frame."""
    nodes = motions.nodes
    segment = np.clip(np.floor(t), 0, nodes.count[chain] - 2).astype(np.int64)
    state = motions.span_state(nodes.span_first[chain] + segment, t - segment)
    circles = CircleRows.of(state)
    centre, normal, radius = circles.euclidean()
    row_origin, row_scale = origin[chain], scale[chain]
    return RingRows(row_origin + row_scale[:, None] * centre, normal, row_scale * radius, circles.omega(),
                    row_origin, row_scale, t)


def mesh_chains(motions: Motions, origin: np.ndarray, scale: np.ndarray, around: int,
                subdivide: int, names) -> TubeArrays:
    """Tubes of ``around`` vertices per ring and ``subdivide`` rings between nodes for every chain
    (frames: origin (C, 3), scale (C,); ``names`` (C,) their surfaces' names, for messages)."""
    nodes = motions.nodes
    chains = len(nodes.count)
    segments = nodes.count - 1
    along = segments * (subdivide + 1) + 1
    t, ring_chain = _linspace_parameters(segments, along)
    rings = _rows(motions, origin, scale, ring_chain, t)

    def resample(chain: np.ndarray, at: np.ndarray) -> tuple[RingRows, np.ndarray]:
        return _rows(motions, origin, scale, chain, at), np.ones(len(at), dtype=bool)

    surfaces = CircleSurfaces(tuple(names), segments.astype(np.float64), np.zeros(chains, dtype=bool),
                              np.zeros(chains, dtype=bool), resample)
    meshes = mesh_rings(rings, SurfaceRows.of_counts(along), surfaces, around, distinct=True)
    del rings
    # a normal spline its bound does not certify is scanned as a motor surface's check scans it
    errors = motions.lost_planes(names, SCAN_SAMPLES_PER_SEGMENT) if not motions.certified.all() else {}
    for c, error in meshes.errors.items():  # a motor circle is never a line: rings that all coincide
        errors.setdefault(c, error)
    dropped = np.bincount(meshes.ring_surface, minlength=chains) != along
    face_counts = np.diff(meshes.face_first)
    faces = meshes.faces
    faces -= np.repeat(meshes.vertex_first[:-1], face_counts).astype(np.int32)[:, None]
    return TubeArrays(meshes.positions, meshes.normals, meshes.uvs, faces, meshes.ring_surface, meshes.ring_local,
                      face_counts, meshes.uv_lengths, errors, dropped)
