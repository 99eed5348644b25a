"""Mesh-quality report: our own geometry measures, and topology and self-intersections by pymeshlab.

Per surface (every measure on the mesh in its own coordinates; they are invariant under the
similarity transforms the exporters use):

- counts: stored vertices, triangles, and points (vertices welded by bit-identical position:
  UV seams and cap rims repeat vertices, and must not count as boundaries);
- triangle shape: aspect ratio (longest edge * perimeter / (4 sqrt(3) area): 1 for an
  equilateral triangle, growing without bound as it degenerates) and minimum angle in degrees,
  each as min / mean / p99 / max; degenerate triangles (area <= 1e-12 * longest edge^2);
- topology of the welded mesh (pymeshlab): non-manifold edges and vertices, boundary edges,
  holes, connected components;
- self-intersections (pymeshlab): triangles crossing a triangle they share no vertex with
  (a tube whose radius exceeds its bend radius folds through itself);
- normals that are not unit (zero, or a length off 1 by more than NORMAL_LENGTH_SLACK: int8
  quantisation stays within it), refused by default;
- normal consistency: the angle between each stored normal and the area-weighted normal of the
  triangles around it (vertices at the same point with the same normal pooled, so a UV seam
  sees its whole fan while a crease, such as a cap's rim, keeps its sides apart): max, mean,
  p99, and ``flipped`` (angle > 90 degrees);
- UV flips: triangles whose UVs wind clockwise (the exporters wind every triangle
  counter-clockwise seen from its normals, and natural and xatlas UVs keep that orientation),
  out of the triangles whose UVs have area at all.

``Thresholds`` say what ``--strict`` refuses; ``Report.failures`` lists what breaks them.
pymeshlab is imported only here, when a report is made.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from cgamesh.errors import InvalidInputError
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.meshing.weld import weld_by_position

DEGENERATE_FRACTION = 1e-12
# A stored normal whose length is off 1 by more than this is not a unit normal (glTF requires
# unit normals; normalized int8 ones are within about 0.014 of 1).
NORMAL_LENGTH_SLACK = 0.02


@dataclass(frozen=True)
class Thresholds:
    """Limits a mesh must keep to pass ``--strict`` (see README); None: not judged.

    By default only defects are refused (degenerate triangles, non-manifold topology,
    self-intersections, flipped normals): slivers, UV flips and normals far from the faces'
    also occur on valid surfaces (along a fold of a ribbon, at a pinch point), so their limits
    are opt-in.
    """

    degenerate_triangles: int | None = 0
    non_manifold_edges: int | None = 0
    non_manifold_vertices: int | None = 0
    self_intersecting_triangles: int | None = 0
    flipped_normals: int | None = 0
    non_unit_normals: int | None = 0
    max_normal_deviation_degrees: float | None = None
    uv_flips: int | None = None
    min_angle_degrees: float | None = None
    max_aspect_ratio: float | None = None


@dataclass
class SurfaceReport:
    name: str
    vertices: int
    triangles: int
    points: int
    aspect_ratio: dict
    min_angle_degrees: dict
    degenerate_triangles: int
    non_manifold_edges: int
    non_manifold_vertices: int
    boundary_edges: int
    holes: int
    connected_components: int
    self_intersecting_triangles: int
    normal_deviation_degrees: dict | None
    flipped_normals: int | None
    uv_flips: int | None
    uv_triangles: int
    non_unit_normals: int | None = None

    def failures(self, limits: Thresholds) -> list[str]:
        out = []

        def over(label, value, limit):
            if value is not None and limit is not None and value > limit:
                out.append(f"{self.name}: {label} {value:g} > {limit:g}")

        over("degenerate triangles", self.degenerate_triangles, limits.degenerate_triangles)
        over("non-manifold edges", self.non_manifold_edges, limits.non_manifold_edges)
        over("non-manifold vertices", self.non_manifold_vertices, limits.non_manifold_vertices)
        over("self-intersecting triangles", self.self_intersecting_triangles, limits.self_intersecting_triangles)
        over("flipped normals", self.flipped_normals, limits.flipped_normals)
        over("zero or non-unit normals", self.non_unit_normals, limits.non_unit_normals)
        if self.normal_deviation_degrees is not None:
            over("normal deviation (degrees)", self.normal_deviation_degrees["max"],
                 limits.max_normal_deviation_degrees)
        over("UV flips", self.uv_flips, limits.uv_flips)
        over("aspect ratio", self.aspect_ratio["max"], limits.max_aspect_ratio)
        if limits.min_angle_degrees is not None and self.min_angle_degrees["min"] < limits.min_angle_degrees:
            out.append(f"{self.name}: minimum angle {self.min_angle_degrees['min']:g} < "
                       f"{limits.min_angle_degrees:g} degrees")
        return out


@dataclass
class Report:
    source: str
    surfaces: list[SurfaceReport]
    thresholds: Thresholds = field(default_factory=Thresholds)

    def failures(self) -> list[str]:
        return [line for s in self.surfaces for line in s.failures(self.thresholds)]

    def to_dict(self) -> dict:
        failures = self.failures()
        return {"source": self.source, "passed": not failures, "failures": failures,
                "thresholds": asdict(self.thresholds), "surfaces": [asdict(s) for s in self.surfaces]}

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=2, allow_nan=False)

    def table(self) -> str:
        """A human-readable table, one column per surface."""
        rows = [("", [s.name for s in self.surfaces])]

        def add(label, values):
            rows.append((label, values))

        def stats(d, digits=3):
            return f"{d['min']:.{digits}g} / {d['mean']:.{digits}g} / {d['p99']:.{digits}g} / {d['max']:.{digits}g}"

        ss = self.surfaces
        add("vertices (points)", [f"{s.vertices} ({s.points})" for s in ss])
        add("triangles", [str(s.triangles) for s in ss])
        add("aspect min/mean/p99/max", [stats(s.aspect_ratio) for s in ss])
        add("min angle deg min/mean/p99/max", [stats(s.min_angle_degrees) for s in ss])
        add("degenerate triangles", [str(s.degenerate_triangles) for s in ss])
        add("non-manifold edges / vertices", [f"{s.non_manifold_edges} / {s.non_manifold_vertices}" for s in ss])
        add("boundary edges (holes)", [f"{s.boundary_edges} ({s.holes})" for s in ss])
        add("connected components", [str(s.connected_components) for s in ss])
        add("self-intersecting triangles", [str(s.self_intersecting_triangles) for s in ss])
        add("normal deviation deg mean/p99/max",
            [("-" if s.normal_deviation_degrees is None else
              "{mean:.3g} / {p99:.3g} / {max:.3g}".format(**s.normal_deviation_degrees)) for s in ss])
        add("flipped normals", ["-" if s.flipped_normals is None else str(s.flipped_normals) for s in ss])
        add("zero or non-unit normals", ["-" if s.non_unit_normals is None else str(s.non_unit_normals) for s in ss])
        add("UV flips", ["-" if s.uv_flips is None else f"{s.uv_flips} of {s.uv_triangles}" for s in ss])
        width = max(len(label) for label, _ in rows)
        columns = [max(len(row[1][i]) for row in rows) for i in range(len(ss))]
        lines = [f"quality of {self.source}"]
        for label, values in rows:
            lines.append("  " + label.ljust(width) + "  " + "  ".join(v.rjust(w) for v, w in zip(values, columns)))
        failures = self.failures()
        lines.append("  passed" if not failures else "  FAILED:\n" + "\n".join(f"    {f}" for f in failures))
        return "\n".join(lines)


def report(meshes: list[SurfaceMesh], source: str, thresholds: Thresholds = Thresholds()) -> Report:
    return Report(source, [surface_report(mesh) for mesh in meshes], thresholds)


def surface_report(mesh: SurfaceMesh) -> SurfaceReport:
    positions = np.asarray(mesh.positions, dtype=np.float64)
    faces = np.asarray(mesh.faces, dtype=np.int64)
    weld = weld_by_position(positions)
    keep = np.flatnonzero(weld == np.arange(len(weld)))
    point_of = np.empty(len(weld), dtype=np.int64)
    point_of[keep] = np.arange(len(keep))
    welded_faces = point_of[weld][faces]

    corners = positions[faces]
    edges = np.stack([corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 1], corners[:, 0] - corners[:, 2]], 1)
    lengths = np.linalg.norm(edges, axis=2)
    cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    area = 0.5 * np.linalg.norm(cross, axis=1)
    longest = lengths.max(axis=1)
    degenerate = area <= DEGENERATE_FRACTION * longest**2
    with np.errstate(divide="ignore", invalid="ignore"):
        aspect = np.where(degenerate, np.inf, longest * lengths.sum(axis=1) / (4.0 * math.sqrt(3.0) * area))
    angles = _angles(edges, lengths)

    topology, intersecting = _meshlab(positions[keep], welded_faces[~degenerate])
    deviation, flipped = _normal_consistency(mesh, weld, faces, cross)
    uv_area = _signed_uv_area(np.asarray(mesh.uvs, dtype=np.float64), faces)
    scale = max(float(np.abs(mesh.uvs).max(initial=0.0)), 1e-300) ** 2
    has_uv = np.abs(uv_area) > 1e-14 * scale
    return SurfaceReport(
        name=mesh.name,
        vertices=mesh.vertex_count,
        triangles=mesh.triangle_count,
        points=len(keep),
        aspect_ratio=_stats(aspect),
        min_angle_degrees=_stats(angles.min(axis=1)),
        degenerate_triangles=int(degenerate.sum()),
        non_manifold_edges=int(topology["non_two_manifold_edges"]),
        non_manifold_vertices=int(topology["non_two_manifold_vertices"]),
        boundary_edges=int(topology["boundary_edges"]),
        holes=int(topology.get("number_holes", 0)),
        connected_components=int(topology["connected_components_number"]),
        self_intersecting_triangles=intersecting,
        normal_deviation_degrees=deviation,
        flipped_normals=flipped,
        uv_flips=int(((uv_area < 0.0) & has_uv).sum()) if has_uv.any() else None,
        uv_triangles=int(has_uv.sum()),
        non_unit_normals=_non_unit_normals(mesh),
    )


def _angles(edges: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """(F, 3) interior angles in degrees; each between the two edges meeting at a corner."""
    out = np.empty(lengths.shape)
    for corner in range(3):
        a, b = -edges[:, corner - 1], edges[:, corner]  # into and out of the corner
        cos = np.einsum("ij,ij->i", a, b) / np.maximum(lengths[:, corner - 1] * lengths[:, corner], 1e-300)
        out[:, corner] = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
    return out


def _stats(values: np.ndarray) -> dict:
    finite = values[np.isfinite(values)]
    if finite.size == 0:
        return {"min": math.inf, "mean": math.inf, "p99": math.inf, "max": math.inf} if values.size else \
            {"min": 0.0, "mean": 0.0, "p99": 0.0, "max": 0.0}
    big = float(values.max()) if np.isfinite(values).all() else 1e300
    return {"min": float(values.min()), "mean": float(finite.mean()), "p99": float(np.percentile(finite, 99)),
            "max": big}


def _meshlab(points: np.ndarray, faces: np.ndarray) -> tuple[dict, int]:
    from cgamesh.optional import require

    pymeshlab = require("pymeshlab", "check", "the mesh-quality report")
    meshes = pymeshlab.MeshSet()
    meshes.add_mesh(pymeshlab.Mesh(vertex_matrix=points, face_matrix=faces.astype(np.int32)))
    topology = meshes.get_topological_measures()
    meshes.compute_selection_by_self_intersections_per_face()
    return topology, int(meshes.current_mesh().selected_face_number())


def _non_unit_normals(mesh: SurfaceMesh) -> int | None:
    """How many stored normals are zero or not of unit length; None when the mesh has none."""
    normals = np.asarray(mesh.normals, dtype=np.float64)
    if normals.shape != mesh.positions.shape:
        return None
    size = np.linalg.norm(normals, axis=1)
    return int(np.count_nonzero(~(np.abs(size - 1.0) <= NORMAL_LENGTH_SLACK)))


def _normal_consistency(mesh: SurfaceMesh, weld: np.ndarray, faces: np.ndarray, cross: np.ndarray):
    normals = np.asarray(mesh.normals, dtype=np.float64)
    if normals.shape != mesh.positions.shape or not np.isfinite(normals).all():
        return None, None
    lengths = np.linalg.norm(normals, axis=1)
    key = np.concatenate([weld[:, None].astype(np.float64), np.round(normals, 6) + 0.0], axis=1)
    _, group = np.unique(key, axis=0, return_inverse=True)
    group = group.ravel()
    summed = np.zeros((group.max() + 1, 3))
    for corner in range(3):
        np.add.at(summed, group[faces[:, corner]], cross)  # |cross| = 2 area: area-weighted
    reference = summed[group]
    size = np.linalg.norm(reference, axis=1)
    used = (size > 0.0) & (lengths > 0.0)  # a zero normal has no direction (counted by _non_unit_normals)
    cos = np.einsum("ij,ij->i", reference[used], normals[used]) / (size[used] * lengths[used])
    angle = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
    if angle.size == 0:
        return None, None
    return _stats(angle), int((angle > 90.0).sum())


def _signed_uv_area(uvs: np.ndarray, faces: np.ndarray) -> np.ndarray:
    if uvs.shape[0] == 0 or uvs.ndim != 2 or uvs.shape[1] != 2:
        return np.zeros(len(faces))
    a1 = uvs[faces[:, 1]] - uvs[faces[:, 0]]
    a2 = uvs[faces[:, 2]] - uvs[faces[:, 0]]
    return 0.5 * (a1[:, 0] * a2[:, 1] - a1[:, 1] * a2[:, 0])


# --- reading meshes back from files -------------------------------------------------------------

def load_meshes(path: str | Path, limit: int | None = None) -> list[SurfaceMesh]:
    """The surfaces of an exported file (.glb, .gltf, .usd*, .obj, .ply, .stl) as SurfaceMeshes.

    Stored vertices as the file has them (a USD mesh's faceVarying values become one vertex per
    triangle corner); glTF and USD positions are in metres / stage units, without transforms;
    STL carries no vertex normals (normals are then the face normals, and not judged), OBJ /
    PLY / STL no names beyond the file's. ``limit``: the most bytes read and decoded
    (readers.files.read_limit; None for its default).
    """
    from cgamesh.readers.files import check_regular, read_limit

    path = Path(path)
    suffix = path.suffix.lower()
    limit = read_limit() if limit is None else limit
    check_regular(path, limit)  # a missing file, a folder, a FIFO or a device: one line, before any reader
    if suffix in (".glb", ".gltf"):
        from cgamesh.readers.readback import read_gltf

        return read_gltf(path, limit=limit)
    if suffix in (".usd", ".usda", ".usdc", ".usdz"):
        from cgamesh.readers.readback import read_usd

        return read_usd(path, limit=limit)
    if suffix in (".obj", ".ply", ".stl"):
        from cgamesh.readers.readback import read_trimesh

        return read_trimesh(path, limit=limit)
    raise InvalidInputError(f"{path}: cannot check this kind of file; expected a scene (.yaml) or one of "
                            ".glb, .gltf, .usd, .usda, .usdc, .usdz, .obj, .ply, .stl")
