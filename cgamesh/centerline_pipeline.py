"""From centrelines (SWC skeletons, tractograms, arrays) to tube meshes: chains -> specs -> meshes.

Each unbranched chain of a tree (cgamesh.inputs.trees), or each polyline, becomes one circle
surface spec: a circle control per node (centre = the node, normal = the chain's tangent there
by central differences, one-sided at the ends, radius = the node's radius clamped to the minimum
radius), a Catmull-Rom curve through them, ``interpolation = "motor"``, and (nodes - 1) * (K + 1)
+ 1 rings along, so K rings fall between consecutive nodes and one on every node. The specs go
through the same pipeline as a scene file's surfaces (cgamesh.pipeline.mesh_surface). Branch
nodes are closed by spheres of their radius (cgamesh.meshing.junctions), a neuron's soma (SWC
type 1 nodes) by spheres of its radius; then everything is merged into one mesh
(cgamesh.meshing.merge), kept apart (``split``), or united into one closed surface
(``watertight``, cgamesh.meshing.watertight). Per-vertex attributes ``radius`` and ``segment``
(and ``scalar`` when colouring by a per-point field) are interpolated from the nodes along each
tube, and colours computed from them (cgamesh.meshing.colors).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from cgamesh.errors import CgameshError, DegenerateGeometryError, InvalidInputError
from cgamesh.inputs.centerlines import Centerlines
from cgamesh.inputs.formats import InputKind
from cgamesh.material import Material
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.meshing.node_normals import envelope_normals
from cgamesh.options import BY_NAME as OPTION_TABLE, COLOR_MODES, for_input  # the table the options come from

SOMA = 1  # SWC structure type
SOMA_SEGMENT = -1.0  # the ``segment`` attribute of soma spheres
# Sphere vertices meshed at a time when they are merged (182 spheres of 45 vertices at 8 around:
# about 1.2 MB with their attributes, where a neuron's 600 junctions at once took 4 MB on top of
# the merged mesh; under a tolerance a sphere can have tens of thousands).
SPHERE_BLOCK_VERTICES = 1 << 13


@dataclass(frozen=True)
class TubeOptions:
    """How centrelines become tubes (the command line's real-data options), as the centreline
    pipeline receives them; ``from_options`` builds one from the table of options (cgamesh.options),
    whose defaults are these.

    radius:     a constant radius for every node (required when the input has no radii; it
                replaces the file's radii when given).
    min_radius: radii below it are raised to it (a radius of 0 is an error without it).
    up:         which axis of the input points up: x, y or z.
    around:     vertices around every tube and sphere (>= 3).
    subdivide:  rings between consecutive nodes (>= 0); or ``tolerance``, a largest distance
                from the true surface in the input's units, instead.
    color_by:   none | radius | direction | segment | the name of a per-point scalar.
    split:      one mesh per chain or streamline (and one for the spheres) instead of one mesh.
    watertight: one closed 2-manifold mesh (capped tubes, spheres and soma united).
    caps:       close every tube's ends with flat discs (implied by ``watertight``).
    strict:     a chain that cannot be meshed is an error instead of being skipped.
    """

    radius: float | None = None
    min_radius: float | None = None
    up: str = "z"
    around: int = 8
    subdivide: int = 3
    tolerance: float | None = None
    color_by: str = "none"
    split: bool = False
    watertight: bool = False
    strict: bool = False
    caps: bool = False

    @classmethod
    def from_options(cls, values) -> TubeOptions:
        """The options of ``values`` (a mapping by the table's names) that a centreline input
        takes and were given; the defaults for the others. ``units`` is the reader's, not ours."""
        return cls(**{name: value for name, value in for_input(values, InputKind.CENTERLINES).items()
                      if name != "units"})


@dataclass(frozen=True)
class TubeMeshes:
    """The meshes of one input, ready for the writers, and what was skipped.

    meshes:   one mesh (merged or watertight) or, with ``split``, one per chain plus the spheres.
    skipped:  one line per chain that could not be meshed, naming its nodes or streamline.
    up:       the writers' up axis ("z" or "y"; an x-up input was turned to z-up).
    units, meters_per_unit: the input's length unit.
    chains:   how many chains or streamlines the input has.
    """

    meshes: tuple[SurfaceMesh, ...]
    skipped: tuple[str, ...]
    up: str
    units: str
    meters_per_unit: float
    chains: int
    material: Material = field(default_factory=Material)


@dataclass(frozen=True)
class _Chain:
    label: str
    line: int | None
    nodes: np.ndarray


@dataclass(frozen=True)
class _ChainList:
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

    def __getitem__(self, i: int) -> _Chain:
        i = int(i)
        if not 0 <= i < len(self):
            raise IndexError(i)
        nodes = self.nodes[self.offsets[i]: self.offsets[i + 1]]
        lines = self.lines
        if not lines.is_tree:
            return _Chain(f"streamline {i}", None, nodes)
        ids = nodes if lines.ids is None else lines.ids[nodes]
        word = "nodes" if lines.ids is not None else "points"
        label = (f"{word} {', '.join(str(int(k)) for k in ids)}" if len(ids) <= 4 else
                 f"{word} {int(ids[0])}, {int(ids[1])}, ..., {int(ids[-1])} ({len(ids)} {word})")
        line = int(lines.lines[nodes[1]]) if lines.lines is not None else None
        return _Chain(label, line, nodes)

    def __iter__(self):
        return (self[i] for i in range(len(self)))


def mesh_centerlines(lines: Centerlines, options: TubeOptions = TubeOptions(),
                     progress: Callable[..., None] = lambda label, count=1: None,
                     batched: bool = True, as_written: bool = False, max_memory=None,
                     outputs: Sequence[str] = ()) -> TubeMeshes:
    """Tubes along every chain of ``lines`` with their junction and soma spheres (see the module).

    ``progress(label, count)`` after every ``count`` chains (under a tolerance twice per chain:
    planned, then meshed). Under a tolerance every chain is planned first and the whole run
    priced against ``max_memory`` (bytes, a size such as "2G", a cgamesh.budget.Budget, or None
    for the default) with the largest export of ``outputs`` (file names or extensions):
    ResourceLimitError, naming about the tolerance that would fit, before any mesh is made.
    ``batched``: mesh the chains in
    one vectorised pass (cgamesh.meshing.batch_pass; same meshes within 1e-12 relative) where
    the options allow it (a fixed resolution, no caps, not watertight); else, or when False,
    one chain at a time. ``as_written``: a merged mesh holds its normals, colours and the
    attributes no colour is made from as the glTF writer stores them, float32
    (cgamesh.meshing.merge; for runs that write only unquantized glTF files, byte for byte the same).
    """
    _check_options(lines, options)
    radii = _radii(lines, options)
    points = lines.points[:, [1, 2, 0]] if options.up == "x" else lines.points  # x up -> z up, a rotation
    up = "y" if options.up == "y" else "z"
    scalar = lines.scalars.get(options.color_by)
    chains, junctions = _chains(lines)
    _check_scale(lines, points, chains)
    soma = lines.kinds == SOMA if lines.kinds is not None else np.zeros(len(points), dtype=bool)
    tangents = np.zeros_like(points)
    tangents[:, 2] = 1.0
    segment_of = np.full(len(points), SOMA_SEGMENT)
    skipped: list[str] = []
    stem = _mesh_name(lines.source)
    planned = None
    if options.tolerance is not None:  # every chain planned, the whole run priced, then meshed
        from cgamesh import centerline_tolerance as to_tolerance

        # the spheres first: one that cannot meet the tolerance is refused before any tube is planned
        sphere_vertices, sphere_triangles = to_tolerance.sphere_size(lines, radii, junctions, soma, options)
        price = to_tolerance.TolerancePrice(lines, options.tolerance, max_memory, outputs, sphere_vertices)
        planned = to_tolerance.plan_tubes(chains, points, radii, soma, tangents, segment_of, lines, options, stem,
                                          skipped, progress, price)
        price.finish()
    merging = not options.split and not options.watertight
    pieces: list[SurfaceMesh] = []
    if merging:  # each piece goes into the merged arrays as it is made (cgamesh.meshing.merge)
        from cgamesh.meshing.merge import MergedMesh

        if planned is None:
            vertices, triangles = _expected_size(chains, junctions, soma, options)
        else:  # an upper estimate: the pages of the arrays never filled are never made resident
            vertices, triangles = to_tolerance.planned_size(planned, options)
            vertices, triangles = vertices + sphere_vertices, triangles + sphere_triangles
        exact = () if options.color_by in ("none", "direction") else ("radius", "segment", "scalar")
        merged = MergedMesh(vertices, triangles, as_written=as_written, exact_attributes=exact)
        sink = merged.append
    else:
        sink = pieces.append
    if batched and uses_batched_pass(options):
        from cgamesh.meshing.batch_pass.chains import tube_pieces

        def single(chain, index, tangents_, segment_of_):
            return _tube(chain, index, points, radii, soma, scalar, tangents_, segment_of_, lines, options, stem)

        skipped = tube_pieces(chains, points, radii, soma, scalar, tangents, segment_of, options, stem,
                              _label_name, single, progress, sink)
        chains_loop = []
    elif planned is not None:
        to_tolerance.mesh_planned_tubes(planned, scalar, options, stem, skipped, progress, sink)
        chains_loop = []
    else:
        chains_loop = chains
    for index, chain in enumerate(chains_loop):
        _take(lambda: _tube(chain, index, points, radii, soma, scalar, tangents, segment_of, lines, options, stem),
              options, skipped, sink)
        progress(chain.label)
    # merged, the spheres go in blocks of SPHERE_BLOCK_VERTICES: consecutive pieces of one group merge to its mesh
    for sphere in _spheres(junctions, points, radii, soma, scalar, tangents, segment_of, options, stem,
                           block=SPHERE_BLOCK_VERTICES if merging else None):
        sink(sphere)
    if (merged.empty if merging else not pieces):
        raise DegenerateGeometryError(f"{lines.source}: nothing to mesh: "
                                      f"{'; '.join(skipped[:3]) if skipped else 'no chain has two distinct points'}")
    meshes = _colored([merged.finish(stem)] if merging else _assemble(pieces, options, stem), options)
    return TubeMeshes(meshes=tuple(meshes), skipped=tuple(skipped), up=up, units=lines.units,
                      meters_per_unit=lines.meters_per_unit, chains=len(chains),
                      material=Material(color=(1.0, 1.0, 1.0)) if options.color_by != "none" else Material())


def _take(make: Callable[[], "SurfaceMesh | list[SurfaceMesh] | None"], options: TubeOptions, skipped: list[str],
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


def uses_batched_pass(options: TubeOptions) -> bool:
    """Whether the batched pass covers these options (tolerance-driven rings, caps and the
    watertight union are meshed one chain at a time)."""
    return options.tolerance is None and not options.watertight and not options.caps


def chain_count(lines: Centerlines) -> int:
    """How many chains (tree) or polylines the input has, without splitting it."""
    if not lines.is_tree:
        return len(lines.offsets) - 1
    parents = lines.parents
    below = np.flatnonzero(parents >= 0)
    children = np.bincount(parents[below], minlength=len(parents))
    head = parents[below]
    return int(np.count_nonzero((parents[head] < 0) | (children[head] != 1)))


def _check_options(lines: Centerlines, options: TubeOptions) -> None:
    """The checks of the option table (cgamesh.options) on every value (a TubeOptions may be
    made without the table), and a colouring that names a field of this file."""
    where = lines.source
    for key in ("up", "around", "subdivide", "radius", "min_radius", "tolerance"):
        value = getattr(options, key)
        if value is not None:
            OPTION_TABLE[key].value_for(InputKind.CENTERLINES).check(key, value)
    if options.color_by not in COLOR_MODES and options.color_by not in lines.scalars:
        fields = ", ".join(lines.scalars) or "none"
        raise InvalidInputError(f"{where}: color-by must be one of {', '.join(COLOR_MODES)} or a per-point "
                                f"field of the file ({fields}), got {options.color_by!r}")


# Lengths the meshing squares and multiplies (steps between points, radii, coordinates) stay
# within these, so their squares and products are normal float64 numbers: a step of 1e-310 or
# a coordinate of 1e300 would underflow or overflow to zero or infinity mid-way and surface as
# an unrelated error (a lost circle plane) after a page of numpy warnings.
SMALLEST_LENGTH, LARGEST_LENGTH = 1e-150, 1e150


def _radii(lines: Centerlines, options: TubeOptions) -> np.ndarray:
    """Each node's radius: the constant one or the file's, raised to the minimum radius."""
    if options.radius is not None:
        radii = np.full(len(lines.points), float(options.radius))
    elif lines.radii is None:
        raise InvalidInputError(f"{lines.source}: the file has no radii; give a radius (--radius R)")
    else:
        radii = np.array(lines.radii, dtype=np.float64)
    if options.min_radius is not None:
        radii = np.maximum(radii, options.min_radius)
    zero = np.flatnonzero(radii <= 0.0)
    if zero.size:
        raise InvalidInputError(f"{lines.source}: {lines.node_name(int(zero[0]))}: expected a radius > 0, got "
                                f"{radii[zero[0]]:g} ({zero.size} such); give a minimum radius (--min-radius R)")
    odd = np.flatnonzero((radii < SMALLEST_LENGTH) | (radii > LARGEST_LENGTH))
    if odd.size:
        raise InvalidInputError(f"{lines.source}: {lines.node_name(int(odd[0]))}: expected lengths between "
                                f"{SMALLEST_LENGTH:g} and {LARGEST_LENGTH:g} {lines.units}, got a radius of "
                                f"{radii[odd[0]]:g}")
    return radii


def _check_scale(lines: Centerlines, points: np.ndarray, chains: _ChainList) -> None:
    """A located InvalidInputError for the first point whose coordinate or step to the next
    point of its chain (exact duplicates apart: they are merged) is outside [SMALLEST_LENGTH,
    LARGEST_LENGTH] (radii: ``_radii``)."""
    units = lines.units
    expected = f"expected lengths between {SMALLEST_LENGTH:g} and {LARGEST_LENGTH:g} {units}"
    big = np.flatnonzero(np.abs(points).max(axis=1, initial=0.0) > LARGEST_LENGTH)
    if big.size:
        raise InvalidInputError(f"{lines.source}: {lines.node_name(int(big[0]))}: {expected}, got a coordinate of "
                                f"{np.abs(points[big[0]]).max():g}")
    nodes = chains.nodes[chains.offsets[0]:chains.offsets[-1]]
    within = np.ones(max(len(nodes) - 1, 0), dtype=bool)
    within[chains.offsets[1:-1] - chains.offsets[0] - 1] = False  # the last node of a chain has no next
    step = np.abs(points[nodes[1:]] - points[nodes[:-1]]).max(axis=1, initial=0.0)
    tiny = np.flatnonzero(within & (step > 0.0) & (step < SMALLEST_LENGTH))
    if tiny.size:
        k = int(nodes[tiny[0]])
        raise InvalidInputError(f"{lines.source}: {lines.node_name(k)}: {expected}, got a step of "
                                f"{step[tiny[0]]:g} to the next point")


def _chains(lines: Centerlines) -> tuple[_ChainList, np.ndarray]:
    """The chains (or streamlines) to mesh, and the junction nodes (none for polylines)."""
    if lines.is_tree:
        from cgamesh.inputs.trees import split_tree

        split = split_tree(lines.parents)
        return _ChainList(lines, split.nodes, split.offsets), split.junctions
    return (_ChainList(lines, np.arange(len(lines.points), dtype=np.int64), np.asarray(lines.offsets, dtype=np.int64)),
            np.zeros(0, dtype=np.int64))


@dataclass(frozen=True)
class _TubeSpec:
    """One chain's tube as a surface spec, with the nodes and ring normals its attributes need."""

    spec: object  # cgamesh.inputs.scene.SurfaceSpec
    nodes: np.ndarray
    p: np.ndarray
    tube_radii: np.ndarray
    t: np.ndarray


def _tube(chain: _Chain, index: int, points, radii, soma, scalar, tangents, segment_of, lines: Centerlines,
          options: TubeOptions, stem: str) -> SurfaceMesh | list[SurfaceMesh] | None:
    """The tube of one chain with its attributes; None for a chain inside the soma alone."""
    from cgamesh.pipeline import Resolution, mesh_surface

    tube = _tube_spec(chain, index, points, radii, soma, tangents, segment_of, lines, options, stem)
    if tube is None:
        return None
    return _tube_finish(tube, mesh_surface(tube.spec, Resolution()), chain, index, scalar, options, stem)


def _tube_spec(chain: _Chain, index: int, points, radii, soma, tangents, segment_of, lines: Centerlines,
               options: TubeOptions, stem: str) -> _TubeSpec | None:
    """The surface spec of one chain's tube (its junction tangents and segments noted in
    ``tangents`` and ``segment_of``); None for a chain inside the soma alone."""
    from cgamesh.inputs.scene import CircleControl, Location, SurfaceSpec

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
    controls = tuple(
        CircleControl(center=tuple(c), normal=tuple(n), radius=float(r), through=None, weight=1.0,
                      location=Location(lines.source, None if lines.lines is None else int(lines.lines[k]),
                                        f"{chain.label}: {lines.node_name(int(k))}"))
        for c, n, r, k in zip(p.tolist(), t.tolist(), tube_radii, nodes))
    along = (len(nodes) - 1) * (options.subdivide + 1) + 1
    fixed = options.tolerance is None
    spec = SurfaceSpec(
        name=f"{stem}_{index}", type="circles", curve="catmull_rom", tension=0.0, bias=0.0, continuity=0.0,
        closed=False, align=True, controls=controls, around=options.around if fixed else None,
        along=along if fixed else None, tolerance=options.tolerance, caps=options.watertight or options.caps,
        material=Material(), location=where, interpolation="motor")
    return _TubeSpec(spec, nodes, p, tube_radii, t)


def _tube_finish(tube: _TubeSpec, mesh: SurfaceMesh, chain: _Chain, index: int, scalar, options: TubeOptions,
                 stem: str) -> SurfaceMesh | list[SurfaceMesh]:
    """The chain's mesh checked and given its attributes and colours (or, watertight and
    folding, its frusta)."""
    nodes, p, tube_radii, t, where = tube.nodes, tube.p, tube.tube_radii, tube.t, tube.spec.location
    if not (np.isfinite(mesh.positions).all() and np.isfinite(mesh.normals).all()):
        raise DegenerateGeometryError(f"{where}: expected a finite mesh, got non-finite vertices or normals")
    if options.watertight and not (closed_and_oriented(mesh) and rings_in_order(mesh)):
        # The tube folds over itself (a radius large against its bend): frusta between the nodes
        # and spheres at the inner nodes stand for it, closed whatever the bend.
        return _frusta_chain(p, tube_radii, nodes, index, scalar, t, options, f"{stem}_{_label_name(chain.label)}")
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
    return _with(mesh, name=f"{stem}_{_label_name(chain.label)}", attributes=attributes, colors=colors)


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
        for k, sphere in enumerate(_split_spheres(spheres, len(p) - 2)):
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
        result.append(_with(piece, attributes=attributes, colors=colors))
    return result


def _split_spheres(mesh: SurfaceMesh, count: int) -> list[SurfaceMesh]:
    """A mesh of ``count`` equal spheres (``uv_spheres``) as one mesh per sphere: overlapping
    spheres must enter a union as separate solids, not as one self-overlapping mesh."""
    per_vertex, per_face = mesh.vertex_count // count, mesh.triangle_count // count
    out = []
    for k in range(count):
        rows = slice(k * per_vertex, (k + 1) * per_vertex)
        base = k * per_vertex
        out.append(SurfaceMesh(
            name=f"{mesh.name}_{k}", positions=mesh.positions[rows], normals=mesh.normals[rows], uvs=mesh.uvs[rows],
            faces=np.asarray(mesh.faces[k * per_face:(k + 1) * per_face]) - base,
            weld=None if mesh.weld is None else np.asarray(mesh.weld[rows]) - base,
            colors=None if mesh.colors is None else mesh.colors[rows],
            attributes=None if mesh.attributes is None else {n: a[rows] for n, a in mesh.attributes.items()}))
    return out


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


def _spheres(junctions, points, radii, soma, scalar, tangents, segment_of, options, stem,
             block: int | None = None) -> Iterator[SurfaceMesh]:
    """The junction spheres and the soma spheres, those that exist: one mesh per group and count
    around (one count at a fixed resolution; per sphere under a tolerance, ``spheres_around``),
    its spheres in node order.

    ``block``: the meshes of at most that many vertices (at least one sphere), made one at a time
    as they are asked for, so a run that merges them never holds more than one block beside the
    merged mesh (what a merge makes of consecutive blocks is the group's mesh: every sphere's
    vertices and values are its own)."""
    from cgamesh.meshing.junctions import sphere_bands

    for name, nodes, sphere_radii, around in sphere_groups(junctions, soma, radii, options):
        for count in np.flatnonzero(np.bincount(around)):  # the counts present (np.unique imports numpy.ma)
            chosen = np.flatnonzero(around == count)
            per_sphere = (count + 1) * (sphere_bands(int(count)) + 1)
            step = len(chosen) if block is None else max(1, block // per_sphere)
            for start in range(0, len(chosen), step):
                part = chosen[start:start + step]
                mesh = _sphere_mesh(name, nodes[part], sphere_radii[part], int(count), points, radii, scalar,
                                    tangents, segment_of, options, stem)
                yield from _split_spheres(mesh, len(part)) if options.watertight else [mesh]


def sphere_groups(junctions, soma, radii, options: TubeOptions) -> Iterator[tuple]:
    """(name, nodes, radii, counts around) of the junction and of the soma spheres, those that
    exist: the radii enclosing the tubes' rings when watertight, the counts ``options.around``
    or, under a tolerance, each sphere's own (cgamesh.centerline_tolerance.spheres_around)."""
    for name, nodes in (("junctions", junctions[~soma[junctions]]), ("soma", np.flatnonzero(soma))):
        if not len(nodes):
            continue
        sphere_radii = radii[nodes] * (_junction_scale(options) if name == "junctions" else 1.0)
        if options.tolerance is None:
            around = np.full(len(nodes), options.around)
        else:
            from cgamesh.centerline_tolerance import spheres_around

            around = spheres_around(sphere_radii, options.tolerance)
        yield name, nodes, sphere_radii, around


def _sphere_mesh(name, group, sphere_radii, around, points, radii, scalar, tangents, segment_of, options,
                 stem) -> SurfaceMesh:
    """UV spheres of ``around`` at the nodes ``group`` with their attributes and colours."""
    from cgamesh.meshing.junctions import uv_spheres

    mesh = uv_spheres(points[group], sphere_radii, around, name=f"{stem}_{name}")
    per = mesh.vertex_count // len(group)
    attributes = {"radius": np.repeat(radii[group], per), "segment": np.repeat(segment_of[group], per)}
    if name == "soma":
        attributes["segment"][:] = SOMA_SEGMENT
    if scalar is not None:
        attributes["scalar"] = np.repeat(scalar[group], per)
    colors = None
    if options.color_by == "direction":
        from cgamesh.meshing.colors import direction_colors

        colors = direction_colors(np.repeat(tangents[group], per, axis=0))
    return _with(mesh, attributes=attributes, colors=colors)


def _junction_scale(options: TubeOptions) -> float:
    """The junction spheres' radius over their node's: watertight, they enclose the tubes' rings."""
    if not options.watertight:
        return 1.0
    from cgamesh.meshing.frusta import enclosing_sphere_scale

    return enclosing_sphere_scale(options.around)  # the tubes' rings there lie strictly inside


def _assemble(pieces: list[SurfaceMesh], options: TubeOptions, stem: str) -> list[SurfaceMesh]:
    """Split (one mesh per piece) or watertight (one union); merged outputs are built as the
    pieces come (mesh_centerlines)."""
    if options.watertight:
        from cgamesh.meshing.watertight import union

        return [union(pieces, stem)]
    return pieces


def _expected_size(chains: _ChainList, junctions: np.ndarray, soma: np.ndarray,
                   options: TubeOptions) -> tuple[int, int]:
    """Vertices and triangles of the merged tubes and spheres at a fixed resolution (an upper
    bound: duplicate points merged, chains skipped or inside the soma have fewer); with a
    tolerance, a first guess the merged arrays grow from."""
    from cgamesh.meshing.junctions import uv_spheres

    nodes = chains.counts
    along = (np.maximum(nodes, 2) - 1) * (options.subdivide + 1) + 1
    vertices = int(along.sum()) * (options.around + 1)
    triangles = int((along - 1).sum()) * 2 * options.around
    if options.caps:
        vertices += 2 * len(chains) * (options.around + 1)
        triangles += 2 * len(chains) * options.around
    spheres = int(np.count_nonzero(~soma[junctions]) + np.count_nonzero(soma))
    if spheres:
        one = uv_spheres(np.zeros((1, 3)), np.ones(1), options.around)
        vertices += spheres * one.vertex_count
        triangles += spheres * one.triangle_count
    return vertices, triangles


def _colored(meshes: list[SurfaceMesh], options: TubeOptions) -> list[SurfaceMesh]:
    """Colours from the attributes over all meshes at once (one colour scale for a split output)."""
    mode = options.color_by
    if mode in ("none", "direction") or not all(m.attributes for m in meshes):
        return meshes
    from cgamesh.meshing import colors

    key = mode if mode in ("radius", "segment") else "scalar"
    if mode == "segment":
        return [_with(m, colors=colors.segment_colors(m.attributes["segment"])) for m in meshes]
    lo = min(float(m.attributes[key].min()) for m in meshes)
    hi = max(float(m.attributes[key].max()) for m in meshes)
    return [_with(m, colors=colors.colormap(m.attributes[key], "viridis", lo, hi)) for m in meshes]


def _with(mesh: SurfaceMesh, **changes) -> SurfaceMesh:
    from dataclasses import replace

    return replace(mesh, **changes)


def _mesh_name(source: str) -> str:
    """A mesh name from the file's stem, valid in every output format ([A-Za-z_][A-Za-z0-9_]*)."""
    stem = re.sub(r"[^A-Za-z0-9_]", "_", Path(source).stem) or "tubes"
    return stem if re.match(r"[A-Za-z_]", stem) else f"_{stem}"


def _label_name(label: str) -> str:
    return re.sub(r"_+", "_", re.sub(r"[^A-Za-z0-9]", "_", label.split(" (")[0])).strip("_")
