"""How faithfully a tube follows sparse samples (centres and radii): bulge, neck and folds.

Shared by benchmarks/bench_fidelity.py and tests/test_fidelity.py.

The reference is a smooth centreline through each unbranched chain of samples: a cubic spline
(scipy's CubicSpline, natural ends) through the centres, parametrised by chord length, sampled
densely, with the node radius interpolated linearly in arc length along it. Then

- bulge, per mesh vertex: its distance to the nearest point of any chain's centreline divided
  by the radius there (1 on a perfect tube; a balloon between samples gives > 1);
- neck, per centreline sample: its distance to the nearest mesh vertex divided by its radius
  (a pinch gives < 1; junctions and bends tighter than the radius bring other parts of the
  tube near the centreline too, so necks are compared, not bounded);
- folded segments: spans between two samples where the tube's wall turns inside out (a quad
  of the ring grid whose geometric normal points towards its ring's centre while the
  surface's majority points away): a local self-intersection of the swept surface.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicHermiteSpline, CubicSpline
from scipy.spatial import cKDTree

from cgamesh.inputs.scene import CircleControl, Location, SurfaceSpec
from cgamesh.material import Material
from cgamesh.meshing.node_normals import envelope_normals
from cgamesh.pipelines.scene import Resolution, mesh_surface

# Centreline samples per radius of arc length.
CENTRELINE_DENSITY = 5.0
# Rings per segment and vertices around each ring of the benchmark's meshes.
RINGS_PER_SEGMENT = 8
AROUND = 16


@dataclass(frozen=True)
class Chain:
    """An unbranched run of samples: centres (n, 3), radii (n,)."""

    centres: np.ndarray
    radii: np.ndarray


def dedupe(chain: Chain) -> Chain | None:
    """The chain without consecutive repeated centres; None when fewer than 2 remain."""
    keep = np.concatenate([[True], np.linalg.norm(np.diff(chain.centres, axis=0), axis=1) > 0.0])
    if keep.sum() < 2:
        return None
    return Chain(chain.centres[keep], chain.radii[keep])


def swc_chains(path) -> list[Chain]:
    """The unbranched chains of an SWC skeleton (columns: id, type, x, y, z, radius, parent).

    A chain runs from a root or branch node to the next branch node or leaf; a branch node
    starts every chain leaving it (so chains join at their shared node).
    """
    rows = np.loadtxt(path, comments="#", ndmin=2)
    ids = rows[:, 0].astype(np.int64)
    index = {node: k for k, node in enumerate(ids)}
    parent = np.array([index.get(int(p), -1) for p in rows[:, 6]])
    children: list[list[int]] = [[] for _ in ids]
    for k, p in enumerate(parent):
        if p >= 0:
            children[p].append(k)
    points, radii = rows[:, 2:5], rows[:, 5]
    chains = []
    starts = [k for k in range(len(ids)) if parent[k] < 0 or len(children[parent[k]]) != 1]
    for start in starts:
        run = [parent[start], start] if parent[start] >= 0 else [start]
        while len(children[run[-1]]) == 1:
            run.append(children[run[-1]][0])
        chain = dedupe(Chain(points[run], np.maximum(radii[run], 1e-9)))
        if chain is not None:
            chains.append(chain)
    return chains


def path_tangents(centres: np.ndarray) -> np.ndarray:
    """Unit tangents (n, 3) at the samples: the bisector of the unit chords on either side."""
    chord = np.diff(centres, axis=0)
    unit = chord / np.linalg.norm(chord, axis=1, keepdims=True)
    tangent = np.vstack([unit[:1], unit[:-1] + unit[1:], unit[-1:]])
    length = np.linalg.norm(tangent, axis=1, keepdims=True)
    # a full reversal (bisector 0): the incoming chord
    tangent = np.where(length > 1e-9, tangent / np.where(length > 1e-9, length, 1.0),
                       np.vstack([unit[:1], unit])[: len(centres)])
    return tangent


def node_normals(chain: Chain) -> np.ndarray:
    """The ring normals cgamesh gives a centreline input's nodes (``centerline_pipeline``): the
    bisectors of the path, turned where a node's rings would leave the radius envelope
    (``cgamesh.meshing.node_normals``)."""
    return envelope_normals(chain.centres, chain.radii, path_tangents(chain.centres), np.array([0]),
                            np.array([len(chain.centres)]))


def chain_spec(chain: Chain, interpolation: str, name: str = "chain") -> SurfaceSpec:
    """A circles surface through the chain's samples, normals as for centreline inputs, Catmull-Rom."""
    here = Location(name, 1, name)
    normals = node_normals(chain)
    controls = tuple(CircleControl(tuple(map(float, c)), tuple(map(float, n)), float(r), None, 1.0, here)
                     for c, n, r in zip(chain.centres, normals, chain.radii))
    along = RINGS_PER_SEGMENT * (len(controls) - 1) + 1
    return SurfaceSpec(name, "circles", "catmull_rom", 0.0, 0.0, 0.0, False, True, controls, AROUND, along, None,
                       False, Material(), here, interpolation=interpolation)


@dataclass
class TubeMesh:
    """A tube's vertices (V, 3) and its ring grid (K, M, 3) with each ring's segment (K,) and centre (K, 3)."""

    vertices: np.ndarray
    grid: np.ndarray
    segment: np.ndarray
    centre: np.ndarray


def cgamesh_tube(chain: Chain, interpolation: str) -> TubeMesh:
    spec = chain_spec(chain, interpolation)
    mesh = mesh_surface(spec, Resolution())
    along = spec.along
    grid = mesh.positions[: along * (AROUND + 1)].reshape(along, AROUND + 1, 3)[:, :-1]
    t = np.linspace(0.0, len(chain.centres) - 1, along)
    segment = np.minimum(np.floor(t).astype(int), len(chain.centres) - 2)
    return TubeMesh(grid.reshape(-1, 3), grid, segment, grid.mean(axis=1))


def pyvista_tube(chain: Chain) -> TubeMesh:
    """pyvista's Spline (chord-length Kochanek spline through the centres) swept by its tube
    filter, the radius interpolated in arc length between the samples."""
    import pyvista

    count = len(chain.centres)
    rings = RINGS_PER_SEGMENT * (count - 1) + 1
    spline = pyvista.Spline(chain.centres, rings)
    node_arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(chain.centres, axis=0), axis=1))])
    fraction = node_arc / node_arc[-1]
    along = np.linspace(0.0, 1.0, spline.n_points)
    spline["radius"] = np.interp(along, fraction, chain.radii)
    tube = spline.tube(scalars="radius", absolute=True, n_sides=AROUND, capping=False)
    points = np.asarray(tube.points)
    grid = points.reshape(spline.n_points, AROUND, 3) if len(points) == spline.n_points * AROUND else \
        points.reshape(AROUND, spline.n_points, 3).transpose(1, 0, 2)
    segment = np.minimum(np.searchsorted(fraction, along, side="right") - 1, count - 2)
    return TubeMesh(points, grid, segment, np.asarray(spline.points))


@dataclass(frozen=True)
class Centreline:
    points: np.ndarray  # (S, 3)
    radius: np.ndarray  # (S,)


REFERENCES = ("natural", "catmull_rom")


def reference_spline(arc: np.ndarray, centres: np.ndarray, kind: str):
    """The centreline through centres at chord-length knots ``arc``: "natural" (a C2 cubic
    spline, natural ends) or "catmull_rom" (C1 cubic Hermite, tangent at each sample the mean of
    the unit chords on either side, one-sided at the ends)."""
    if kind == "natural":
        return CubicSpline(arc, centres, bc_type="natural")
    unit = np.diff(centres, axis=0) / np.diff(arc)[:, None]
    tangent = np.vstack([unit[:1], 0.5 * (unit[:-1] + unit[1:]), unit[-1:]])
    return CubicHermiteSpline(arc, centres, tangent)


def centreline(chains: list[Chain], kind: str = "natural") -> list[Centreline]:
    """Dense samples of the reference centreline of each chain, with their radii."""
    out = []
    for chain in chains:
        arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(chain.centres, axis=0), axis=1))])
        spline = reference_spline(arc, chain.centres, kind) if len(arc) > 2 else None
        count = max(2, int(np.ceil(CENTRELINE_DENSITY * arc[-1] / chain.radii.min())) + 1)
        s = np.linspace(0.0, arc[-1], count)
        p = spline(s) if spline is not None else chain.centres[0] + np.outer(s / arc[-1], chain.centres[1] - chain.centres[0])
        # radius linear in the arc length of the spline itself, between the nodes
        dense = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
        node_at = np.interp(arc, s, dense)
        out.append(Centreline(p, np.interp(dense, node_at, chain.radii)))
    return out


def folded_segments(tube: TubeMesh) -> set[int]:
    """Segments (indices) containing a quad whose wall faces its ring's centre against the majority."""
    grid = tube.grid
    around = np.roll(grid, -1, axis=1) - grid
    along = grid[1:] - grid[:-1]
    normal = np.cross(around[:-1], along)
    radial = grid[:-1] - tube.centre[:-1, None, :]
    facing = np.einsum("kmi,kmi->km", normal, radial)
    size = np.linalg.norm(normal, axis=-1) * np.linalg.norm(radial, axis=-1)
    significant = size > 0.0
    majority = np.sign(np.sum(np.sign(facing[significant])))
    against = significant & (facing * majority < -1e-9 * size)
    return set(np.unique(tube.segment[:-1][np.any(against, axis=1)]).tolist())


@dataclass(frozen=True)
class Fidelity:
    vertices: int
    bulge_over_125: float  # fraction of vertices
    bulge_over_160: float
    bulge_max: float
    bulge_p99: float
    neck_under_075: float  # fraction of centreline samples
    neck_min: float
    neck_p1: float
    folded: int
    segments: int
    failed_chains: int


def measure(chains: list[Chain], build, reference: str = "natural") -> Fidelity:
    """Fidelity of the tubes ``build(chain) -> TubeMesh`` of every chain against its own chain's
    reference centreline (another chain's tube or centreline, as in a bundle of streamlines or
    at a branch, does not count).

    A chain whose tube cannot be built (an error) counts in ``failed_chains``."""
    lines = centreline(chains, reference)
    bulges, necks, folded, failed, vertices = [], [], 0, 0, 0
    for chain, line in zip(chains, lines):
        try:
            tube = build(chain)
        except Exception:  # noqa: BLE001 - any failure of a candidate is a measured outcome
            failed += 1
            continue
        distance, nearest = cKDTree(line.points).query(tube.vertices)
        bulges.append(distance / line.radius[nearest])
        gap, _ = cKDTree(tube.vertices).query(line.points)
        necks.append(gap / line.radius)
        folded += len(folded_segments(tube))
        vertices += len(tube.vertices)
    bulge, neck = np.concatenate(bulges), np.concatenate(necks)
    segments = sum(len(c.centres) - 1 for c in chains)
    return Fidelity(vertices, float(np.mean(bulge > 1.25)), float(np.mean(bulge > 1.6)), float(bulge.max()),
                    float(np.percentile(bulge, 99)), float(np.mean(neck < 0.75)), float(neck.min()),
                    float(np.percentile(neck, 1)), folded, segments, failed)


def npz_streamlines(path, radius: float) -> list[Chain]:
    """Streamlines of an array file with ``points`` (N, 3) and ``offsets`` (S,) (dipy's bundles)."""
    data = np.load(path)
    points, offsets = data["points"], data["offsets"]
    bounds = list(offsets) + [len(points)] if offsets[0] == 0 else [0] + list(offsets) + [len(points)]
    chains = []
    for start, stop in zip(bounds[:-1], bounds[1:]):
        chain = dedupe(Chain(points[start:stop].astype(np.float64), np.full(stop - start, radius)))
        if chain is not None:
            chains.append(chain)
    return chains
