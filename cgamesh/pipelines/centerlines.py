"""From centrelines (SWC skeletons, tractograms, arrays) to tube meshes: chains -> specs -> meshes.

Each unbranched chain of a tree (cgamesh.inputs.trees), or each polyline, becomes one circle
surface spec: a circle control per node (centre = the node, normal = the chain's tangent there
by central differences, one-sided at the ends, radius = the node's radius clamped to the minimum
radius), a Catmull-Rom curve through them, ``interpolation = "motor"``, and (nodes - 1) * (K + 1)
+ 1 rings along, so K rings fall between consecutive nodes and one on every node. The specs go
through the same pipeline as a scene file's surfaces (cgamesh.pipelines.scene.mesh_surface). Branch
nodes are closed by spheres of their radius (cgamesh.meshing.junctions), a neuron's soma (SWC
type 1 nodes) by spheres of its radius; then everything is merged into one mesh
(cgamesh.meshing.merge), kept apart (``split``), or united into one closed surface
(``watertight``, cgamesh.meshing.watertight). Per-vertex attributes ``radius`` and ``segment``
(and ``scalar`` when colouring by a per-point field) are interpolated from the nodes along each
tube, and colours computed from them (cgamesh.meshing.colors).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from cgamesh.errors import DegenerateGeometryError, InvalidInputError
from cgamesh.inputs.centerlines import Centerlines
from cgamesh.inputs.formats import InputKind
from cgamesh.material import Material
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.options import BY_NAME as OPTION_TABLE, COLOR_MODES  # the table the options come from
from cgamesh.pipelines.chains import Chain, ChainList, split_chains, take_chain
from cgamesh.pipelines.spheres import SOMA_SEGMENT, sphere_meshes
from cgamesh.pipelines.tube_options import TubeOptions
from cgamesh.pipelines.tubes import finish_tube, label_name, tube_spec

SOMA = 1  # SWC structure type
# Sphere vertices meshed at a time when they are merged (182 spheres of 45 vertices at 8 around:
# about 1.2 MB with their attributes, where a neuron's 600 junctions at once took 4 MB on top of
# the merged mesh; under a tolerance a sphere can have tens of thousands).
SPHERE_BLOCK_VERTICES = 1 << 13


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


def mesh_centerlines(lines: Centerlines, options: TubeOptions = TubeOptions(),
                     progress: Callable[..., None] = lambda label, count=1: None,
                     as_written: bool = False, max_memory=None,
                     outputs: Sequence[str] = ()) -> TubeMeshes:
    """Tubes along every chain of ``lines`` with their junction and soma spheres (see the module).

    ``progress(label, count)`` after every ``count`` chains (under a tolerance twice per chain:
    planned, then meshed). Under a tolerance every chain is planned first and the whole run
    priced against ``max_memory`` (bytes, a size such as "2G", a cgamesh.budget.Budget, or None
    for the default) with the largest export of ``outputs`` (file names or extensions):
    ResourceLimitError, naming about the tolerance that would fit, before any mesh is made.
    At a fixed resolution without caps the chains are meshed in chunks, every chain of a chunk
    as rows of the one circle mesher (cgamesh.meshing.batch_pass); under a tolerance, with caps
    or watertight, one chain at a time. ``as_written``: a merged mesh holds its normals, colours and the
    attributes no colour is made from as the glTF writer stores them, float32
    (cgamesh.meshing.merge; for runs that write only unquantized glTF files, byte for byte the same).
    """
    _check_options(lines, options)
    radii = _radii(lines, options)
    points = lines.points[:, [1, 2, 0]] if options.up == "x" else lines.points  # x up -> z up, a rotation
    up = "y" if options.up == "y" else "z"
    scalar = lines.scalars.get(options.color_by)
    chains, junctions = split_chains(lines)
    _check_scale(lines, points, chains)
    soma = lines.kinds == SOMA if lines.kinds is not None else np.zeros(len(points), dtype=bool)
    tangents = np.zeros_like(points)
    tangents[:, 2] = 1.0
    segment_of = np.full(len(points), SOMA_SEGMENT)
    skipped: list[str] = []
    stem = _mesh_name(lines.source)
    planned = None
    if options.tolerance is not None:  # every chain planned, the whole run priced, then meshed
        from cgamesh.pipelines import centerline_tolerance as to_tolerance

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
    if uses_batched_pass(options):
        from cgamesh.meshing.batch_pass.chains import tube_pieces

        skipped = tube_pieces(chains, points, radii, soma, scalar, tangents, segment_of, options, stem,
                              label_name, progress, sink)
        chains_loop = []
    elif planned is not None:
        to_tolerance.mesh_planned_tubes(planned, scalar, options, stem, skipped, progress, sink)
        chains_loop = []
    else:
        chains_loop = chains
    for index, chain in enumerate(chains_loop):
        take_chain(lambda: _tube(chain, index, points, radii, soma, scalar, tangents, segment_of, lines, options, stem),
                   options, skipped, sink)
        progress(chain.label)
    # merged, the spheres go in blocks of SPHERE_BLOCK_VERTICES: consecutive pieces of one group merge to its mesh
    for sphere in sphere_meshes(junctions, points, radii, soma, scalar, tangents, segment_of, options, stem,
                           block=SPHERE_BLOCK_VERTICES if merging else None):
        sink(sphere)
    if (merged.empty if merging else not pieces):
        raise DegenerateGeometryError(f"{lines.source}: nothing to mesh: "
                                      f"{'; '.join(skipped[:3]) if skipped else 'no chain has two distinct points'}")
    meshes = _colored([merged.finish(stem)] if merging else _assemble(pieces, options, stem), options)
    return TubeMeshes(meshes=tuple(meshes), skipped=tuple(skipped), up=up, units=lines.units,
                      meters_per_unit=lines.meters_per_unit, chains=len(chains),
                      material=Material(color=(1.0, 1.0, 1.0)) if options.color_by != "none" else Material())


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


def _check_scale(lines: Centerlines, points: np.ndarray, chains: ChainList) -> None:
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


def _tube(chain: Chain, index: int, points, radii, soma, scalar, tangents, segment_of, lines: Centerlines,
          options: TubeOptions, stem: str) -> SurfaceMesh | list[SurfaceMesh] | None:
    """The tube of one chain with its attributes; None for a chain inside the soma alone."""
    from cgamesh.pipelines.scene import Resolution, mesh_surface

    tube = tube_spec(chain, index, points, radii, soma, tangents, segment_of, lines, options, stem)
    if tube is None:
        return None
    return finish_tube(tube, mesh_surface(tube.request, Resolution(), surface=tube.surface), chain, index, scalar,
                       options, stem)


def _assemble(pieces: list[SurfaceMesh], options: TubeOptions, stem: str) -> list[SurfaceMesh]:
    """Split (one mesh per piece) or watertight (one union); merged outputs are built as the
    pieces come (mesh_centerlines)."""
    if options.watertight:
        from cgamesh.meshing.watertight import union

        return [union(pieces, stem)]
    return pieces


def _expected_size(chains: ChainList, junctions: np.ndarray, soma: np.ndarray,
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


