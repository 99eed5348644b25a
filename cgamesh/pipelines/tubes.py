"""One chain's tube: its motor surface and request, and its mesh's attributes.

``tube_spec`` makes the circle surface of a chain (centre = the node, normal = the path's
bisector turned to stay in the radius envelope, radius = the node's; the splined motion of a
Catmull-Rom curve through them, as a scene file's ``interpolation: motor`` surface of those
circles is built) straight from the chain's arrays, and what meshing it asks for (a
``TubeRequest``), which the scene pipeline plans and meshes like a scene file's surface;
``finish_tube`` checks the mesh and gives it the chain's per-vertex ``radius``, ``segment`` and
``scalar`` and its direction colours, or, watertight and folding over itself, replaces it by
frusta and node spheres (cgamesh.meshing.frusta).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, replace

import numpy as np

from cgamesh.errors import DegenerateGeometryError
from cgamesh.geometry.frame import LocalFrame
from cgamesh.geometry.motor_surface import MotorSurface
from cgamesh.geometry.motors import MotionSpline
from cgamesh.inputs.centerlines import Centerlines
from cgamesh.inputs.scene_specs import Location
from cgamesh.meshing.batch_pass.chains import chain_motions
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.meshing.node_normals import envelope_normals
from cgamesh.pipelines.chains import Chain
from cgamesh.pipelines.spheres import SOMA_SEGMENT, split_spheres
from cgamesh.pipelines.tube_options import TubeOptions


@dataclass(frozen=True)
class TubeRequest:
    """What meshing a chain's tube asks for, as the scene pipeline reads a surface spec's: its
    name, kind, resolution (or tolerance), caps, and its place for messages (``location``)."""

    name: str
    location: Location
    around: int | None
    along: int | None
    tolerance: float | None
    caps: bool
    type: str = "circles"
    closed: bool = False


@dataclass(frozen=True)
class TubeSpec:
    """One chain's tube: its motor surface and request, with the nodes and ring normals its
    attributes need."""

    request: TubeRequest
    surface: MotorSurface
    nodes: np.ndarray
    p: np.ndarray
    tube_radii: np.ndarray
    t: np.ndarray


def tube_spec(chain: Chain, index: int, points, radii, soma, tangents, segment_of, lines: Centerlines,
              options: TubeOptions, stem: str) -> TubeSpec | None:
    """One chain's tube (its junction tangents and segments noted in ``tangents`` and
    ``segment_of``); None for a chain inside the soma alone."""
    nodes = chain.nodes
    tube_radii = radii[nodes]
    inside = soma[nodes]
    if inside.all():
        return None  # the soma's spheres stand for it
    if inside.any():  # a neurite leaving the soma starts with its own radius, not the soma's
        outside = np.flatnonzero(~inside)
        nearest = outside[np.abs(np.arange(len(nodes))[:, None] - outside[None, :]).argmin(axis=1)]
        tube_radii = tube_radii[nearest]
    where = Location(lines.source, chain.line, chain.label)
    p = points[nodes]
    distinct = np.concatenate([[True], np.any(p[1:] != p[:-1], axis=1)])  # exact duplicates merged
    nodes, p, tube_radii = nodes[distinct], p[distinct], tube_radii[distinct]
    if len(nodes) < 2:
        raise DegenerateGeometryError(f"{where}: expected at least two distinct points, got {len(nodes)}")
    # ring normals: the path's bisectors, turned where a node ring would leave the radius envelope
    t = envelope_normals(p, tube_radii, node_tangents(p), np.array([0]), np.array([len(p)]))
    tangents[nodes[-1]] = t[-1]
    tangents[nodes[0]] = np.where(segment_of[nodes[0]] == SOMA_SEGMENT, t[0], tangents[nodes[0]])
    segment_of[nodes[-1]] = index
    segment_of[nodes[0]] = np.where(segment_of[nodes[0]] == SOMA_SEGMENT, index, segment_of[nodes[0]])
    along = (len(nodes) - 1) * (options.subdivide + 1) + 1
    fixed = options.tolerance is None
    request = TubeRequest(f"{stem}_{index}", where, options.around if fixed else None, along if fixed else None,
                          options.tolerance, options.watertight or options.caps)
    return TubeSpec(request, tube_surface(request.name, p, t, tube_radii), nodes, p, tube_radii, t)


def tube_surface(name: str, centre: np.ndarray, normal: np.ndarray, radius: np.ndarray) -> MotorSurface:
    """The motor surface through the circles of centres (n, 3), normals (n, 3, any length) and radii
    (n,) in file units: a chain's motion as the chunks of chains spline it
    (``batch_pass.chains.chain_motions``), as a surface of its own."""
    motions, origin, scale = chain_motions(centre, normal, radius, np.array([0]), np.array([len(centre)]))
    return MotorSurface(name, MotionSpline(motions), LocalFrame(origin=origin[0], scale=float(scale[0])))


def finish_tube(tube: TubeSpec, mesh: SurfaceMesh, chain: Chain, index: int, scalar, options: TubeOptions,
                stem: str) -> SurfaceMesh | list[SurfaceMesh]:
    """The chain's mesh checked and given its attributes and colours (or, watertight and
    folding, its frusta)."""
    nodes, p, tube_radii, t, where = tube.nodes, tube.p, tube.tube_radii, tube.t, tube.request.location
    if not (np.isfinite(mesh.positions).all() and np.isfinite(mesh.normals).all()):
        raise DegenerateGeometryError(f"{where}: expected a finite mesh, got non-finite vertices or normals")
    if options.watertight and not (closed_and_oriented(mesh) and rings_in_order(mesh)):
        # The tube folds over itself (a radius large against its bend): frusta between the nodes
        # and spheres at the inner nodes stand for it, closed whatever the bend.
        return _frusta_chain(p, tube_radii, nodes, index, scalar, t, options, f"{stem}_{label_name(chain.label)}")
    s = _node_parameter(mesh, len(nodes), options, p)
    grid = np.arange(len(nodes))
    attributes = {"radius": np.interp(s, grid, tube_radii), "segment": np.full(mesh.vertex_count, float(index))}
    if scalar is not None:
        attributes["scalar"] = np.interp(s, grid, scalar[nodes])
    colors = None
    if options.color_by == "direction":
        from cgamesh.meshing.colors import direction_colors

        along_t = np.stack([np.interp(s, grid, t[:, k]) for k in range(3)], axis=1)
        colors = direction_colors(along_t)  # any length; a zero one (a turn back) gets NAN_COLOR
    return replace(mesh, name=f"{stem}_{label_name(chain.label)}", attributes=attributes, colors=colors)


def _frusta_chain(p, tube_radii, nodes, index, scalar, t, options: TubeOptions, name: str) -> list[SurfaceMesh]:
    """A folding chain as closed pieces: a capped frustum per consecutive node pair and an
    enclosing sphere at each inner node, with the tube's attributes and colours."""
    from cgamesh.meshing.frusta import frusta, node_spheres

    pieces = []
    for k, piece in enumerate(frusta(p, tube_radii, options.around, f"{name}_frustum")):
        s = np.where(piece.uvs[:, 1] > 0.5, k + 1.0, float(k))  # each end takes its node's values
        pieces.append((piece, s, np.broadcast_to(p[k + 1] - p[k], (piece.vertex_count, 3))))
    if len(p) > 2:
        spheres = node_spheres(p[1:-1], tube_radii[1:-1], options.around, f"{name}_nodes")
        for k, sphere in enumerate(split_spheres(spheres, len(p) - 2)):
            pieces.append((sphere, np.full(sphere.vertex_count, k + 1.0), np.broadcast_to(t[k + 1], (sphere.vertex_count, 3))))
    grid = np.arange(len(nodes))
    result = []
    for piece, s, direction in pieces:
        attributes = {"radius": np.interp(s, grid, tube_radii), "segment": np.full(piece.vertex_count, float(index))}
        if scalar is not None:
            attributes["scalar"] = np.interp(s, grid, scalar[nodes])
        colors = None
        if options.color_by == "direction":
            from cgamesh.meshing.colors import direction_colors

            colors = direction_colors(direction / np.linalg.norm(direction, axis=1, keepdims=True))
        result.append(replace(piece, attributes=attributes, colors=colors))
    return result


def closed_and_oriented(mesh: SurfaceMesh) -> bool:
    """Whether the welded mesh is closed with every edge used once each way (what a boolean
    union needs); a tube that folds over itself has triangles wound against their neighbours."""
    weld = mesh.weld if mesh.weld is not None else np.arange(mesh.vertex_count)
    faces = weld[mesh.faces].astype(np.int64)
    faces = faces[(faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 2] != faces[:, 0])]
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    forward = edges[:, 0] * mesh.vertex_count + edges[:, 1]
    backward = edges[:, 1] * mesh.vertex_count + edges[:, 0]
    unique, counts = np.unique(forward, return_counts=True)
    return bool(np.all(counts == 1) and np.isin(backward, unique).all())


def rings_in_order(mesh: SurfaceMesh) -> bool:
    """Whether each ring of a capped tube's grid (rings of equal size with a repeated seam
    vertex, then two caps of one ring size each: ``circles._add_cap``) lies wholly ahead of the plane of the ring before it and the
    one before wholly behind its plane. Where the centreline bends tighter than the radius the
    inner wall of consecutive rings crosses: the tube is closed and consistently wound, yet
    its surface passes through itself, and a union of it keeps that self-intersection."""
    v = mesh.uvs[:, 1]
    columns = int(np.argmax(v != v[0])) if (v != v[0]).any() else 0
    grid = mesh.vertex_count - 2 * columns
    if columns < 4 or grid <= 0 or grid % columns:
        return False
    rings = mesh.positions[:grid].reshape(-1, columns, 3)[:, :-1]
    centre = rings.mean(axis=1)
    normal = np.cross(rings - centre[:, None], np.roll(rings, -1, axis=1) - centre[:, None]).sum(axis=1)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    ahead = np.einsum("kij,kj->ki", rings[1:] - centre[:-1, None], normal[:-1]).min(axis=1)
    behind = np.einsum("kij,kj->ki", rings[:-1] - centre[1:, None], normal[1:]).max(axis=1)
    return bool((ahead > 0.0).all() and (behind < 0.0).all())


def node_tangents(p: np.ndarray) -> np.ndarray:
    """Unit tangents (n, 3) of a polyline of distinct consecutive points: the bisector of the
    unit chords on either side (one-sided at the ends; the incoming chord where the bisector
    vanishes, a turn back). This is the direction of the motor tube's centre curve at the node
    (a chord-length Catmull-Rom spline, docs/interpolation.md section 2), so the node rings stand
    perpendicular to the path also where consecutive steps differ in length (the central
    difference p[i+1] - p[i-1] leans towards the longer step)."""
    forward = np.diff(p, axis=0)
    unit = forward / np.linalg.norm(forward, axis=1, keepdims=True)
    t = np.empty_like(p)
    t[0], t[-1] = unit[0], unit[-1]
    t[1:-1] = unit[:-1] + unit[1:]
    length = np.linalg.norm(t, axis=1)
    back = length <= 1e-12
    back[[0, -1]] = False
    t[1:-1][back[1:-1]] = unit[:-1][back[1:-1]]
    return t / np.linalg.norm(t, axis=1, keepdims=True)


def _node_parameter(mesh: SurfaceMesh, count: int, options: TubeOptions, p: np.ndarray) -> np.ndarray:
    """Each vertex's place along the chain in node units (0 at the first node, count - 1 at the last).

    On a fixed-resolution grid ring k lies at t = k / (K + 1) exactly (rings are spaced evenly
    in the curve's parameter, one on every node); caps take their end's value. Otherwise
    (tolerance-driven rings) v, which grows with arc length along the tube, is matched to the
    nodes' arc length along the polyline.
    """
    columns = options.around + 1
    along = (count - 1) * (options.subdivide + 1) + 1
    grid = along * columns
    caps = 2 * columns if options.watertight or options.caps else 0
    if options.tolerance is None and mesh.vertex_count == grid + caps:
        s = np.empty(mesh.vertex_count)
        s[:grid] = np.repeat(np.arange(along) / (options.subdivide + 1), columns)
        s[grid: grid + caps // 2] = 0.0
        s[grid + caps // 2:] = count - 1
        return s
    length = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    return np.interp(np.clip(mesh.uvs[:, 1], 0.0, 1.0) * length[-1], length, np.arange(count))


def label_name(label: str) -> str:
    return re.sub(r"_+", "_", re.sub(r"[^A-Za-z0-9]", "_", label.split(" (")[0])).strip("_")
