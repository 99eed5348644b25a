"""Tolerance-driven tessellation: every example meets 1e-2, 1e-3 and 1e-4 of its size, measured on
the exported file, and is compared with the smallest uniform grid that meets it.

The measurement here is the test's own: the GLB is read back through its node transforms, each
triangle is sampled at 15 barycentric points (interior and edges), each sample finds its nearest
member of the surface (circle or ruling segment) through a k-d tree over a point cloud of the
surface, and golden-section search in t refines it on exact members. It is denser than
cgamesh.meshing.tolerance.deviation and shares only the closed-form distances to a circle and to a segment.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import cKDTree

from cgamesh.export.options import WriteOptions
from cgamesh.meshing.tolerance.deviation import CIRCLES, SEGMENTS, grid_deviation
from cgamesh.export.gltf import write_glb
from cgamesh.meshing.circles import mesh_circle_surface
from cgamesh.pipelines.scene import Resolution, build_surface, mesh_surface
from cgamesh.readers.readback import read_gltf
from cgamesh.meshing.ribbons import mesh_ribbon_surface
from cgamesh.meshing.tolerance.tolerance_plan import plan_tolerance
from cgamesh.inputs.scene import load_scene

EXAMPLES = sorted((Path(__file__).resolve().parent.parent / "examples").glob("*.yaml"))
CASES = [(path, index) for path in EXAMPLES for index in range(len(load_scene(path).surfaces))]
BARYCENTRIC = np.array([(i, j, 4 - i - j) for i in range(5) for j in range(5 - i)], dtype=np.float64) / 4.0


def dense_deviation(surface, family, positions: np.ndarray, faces: np.ndarray) -> float:
    """Largest distance of 15 barycentric samples per triangle from the surface (file units).

    A first bound for every sample comes from a k-d tree over a cloud of the surface (MEMBERS
    per segment, 64 points on each member): the nearest cloud points name candidate members
    and the nearest of those counts. Then, largest first, samples are measured against every
    member and refined by golden-section search in t around the nearest, until the largest of
    all has been. Every figure is a distance to a curve on the surface: none underestimates.
    """
    samples = np.einsum("bk,tki->tbi", BARYCENTRIC, positions[faces]).reshape(-1, 3)
    t = np.linspace(0.0, surface.segment_count, MEMBERS * surface.segment_count + 1)
    params = family.read_out(surface, t)
    cloud = _cloud(family, params)  # (len(t), 64, 3)
    _, index = cKDTree(cloud.reshape(-1, 3)).query(samples, k=NEIGHBOURS)
    candidates = index // cloud.shape[1]  # (S, k)
    best = family.distance(samples[:, None, :], *(p[candidates] for p in params)).min(axis=1)
    refined = np.zeros(len(samples), dtype=bool)
    while not refined[np.argmax(best)]:
        open_ = np.flatnonzero(~refined)
        batch = open_[np.argsort(best[open_])[-1024:]]
        every = family.distance(samples[batch][:, None, :], *(p[None] for p in params))  # (B, members)
        member = np.argmin(every, axis=1)
        low, high = t[np.maximum(member - 2, 0)], t[np.minimum(member + 2, len(t) - 1)]
        exact = np.minimum(every.min(axis=1), _golden(surface, family, samples[batch], low, high))
        best[batch] = np.minimum(best[batch], exact)
        refined[batch] = True
    return float(best.max())


MEMBERS = 1025
NEIGHBOURS = 16
GOLDEN = (np.sqrt(5.0) - 1.0) / 2.0


def _cloud(family, params) -> np.ndarray:
    """64 points on each member: around each circle, or along each segment."""
    if family is SEGMENTS:
        a, b = params
        return a[:, None, :] + np.linspace(0.0, 1.0, 64)[None, :, None] * (b - a)[:, None, :]
    centre, normal, radius = params
    helper = np.where(np.abs(normal[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    u = np.cross(normal, helper)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(normal, u)
    angle = 2.0 * np.pi * np.arange(64) / 64
    return centre[:, None, :] + radius[:, None, None] * (np.cos(angle)[None, :, None] * u[:, None, :]
                                                         + np.sin(angle)[None, :, None] * v[:, None, :])


def _golden(surface, family, samples, low, high, steps: int = 30) -> np.ndarray:
    """The least distance of each sample to the members over [low, high] found by golden section."""
    best = np.full(len(samples), np.inf)
    for _ in range(steps):
        a, b = high - GOLDEN * (high - low), low + GOLDEN * (high - low)
        da = family.distance(samples, *family.read_out(surface, a))
        db = family.distance(samples, *family.read_out(surface, b))
        best = np.minimum(best, np.minimum(da, db))
        closer_to_a = da < db
        high, low = np.where(closer_to_a, b, high), np.where(closer_to_a, low, a)
    return best


def exported_positions(mesh, scene, folder: Path) -> np.ndarray:
    """The mesh's vertices as the GLB stores them, mapped back into the scene's frame."""
    path = folder / "tolerance.glb"
    write_glb(path, [(mesh, scene.surfaces[0].material)], WriteOptions(scene.up, scene.meters_per_unit, scene.units))
    world = read_gltf(path, world=True)[0].positions / scene.meters_per_unit
    if scene.up == "z":  # glTF (x, y, z) is the scene's (x, -z, y)
        world = np.stack([world[:, 0], -world[:, 2], world[:, 1]], axis=1)
    return world


@pytest.mark.parametrize("relative", [1e-2, 1e-3, 1e-4])
@pytest.mark.parametrize("path, index", CASES, ids=[f"{p.stem}[{i}]" for p, i in CASES])
def test_tolerance_is_met_on_the_exported_mesh(path, index, relative, tmp_path):
    """The plan's bound is at most the tolerance, and the deviation measured independently is at
    most the bound: by the 15-sample k-d-tree measure on the exported GLB at 1e-2 and 1e-3, and
    by cgamesh.meshing.tolerance.deviation at 1e-4 (where the meshes are too large for the dense measure)."""
    scene = load_scene(path)
    spec = scene.surfaces[index]
    surface = build_surface(spec)
    tolerance = relative * surface.frame.scale
    mesh = mesh_surface(spec, Resolution(tolerance=tolerance))
    assert mesh.max_deviation <= tolerance  # the a priori bound
    family = SEGMENTS if spec.type == "point_pairs" else CIRCLES
    if relative >= 1e-3:
        grid_faces = mesh.faces[np.all(mesh.faces < _grid_size(mesh, spec), axis=1)]  # caps are exact discs
        measured = dense_deviation(surface, family, exported_positions(mesh, scene, tmp_path), grid_faces)
        # float32 storage moves vertices by about 6e-8 of the surface's size
        assert measured <= mesh.max_deviation + 1e-6 * tolerance, f"{measured / tolerance:.3f} of the tolerance"
    else:
        columns, rings = _grid_shape(mesh, spec)
        plan = plan_tolerance(surface, tolerance, "point_pairs" if spec.type == "point_pairs" else "circles",
                              spec.closed)  # deterministic: the mesh's own rings
        assert (plan.rings, plan.bound) == (rings, mesh.max_deviation)
        t = plan.t
        grid = mesh.positions[: rings * columns].reshape(rings, columns, 3)
        assert grid_deviation(surface, t, grid, family).max <= mesh.max_deviation


# A flat ribbon (fig. 12's linear chords): its end points' in-plane curvature leaves the mesh on
# the surface, but the bound counts it in full (docs/tolerance.md, "Where the bound is not tight").
# At 1e-2 and 1e-3 its smallest uniform grid has 2 rings: no mesh with the same count across has
# fewer vertices, so even an exact bound would not pass here.
FLAT_RIBBON = pytest.mark.xfail(strict=True, reason="flat ribbon: in-plane curvature counted in full")
COMPARED = [pytest.param(path, index, marks=FLAT_RIBBON if (path.stem, index) == ("fig12_cocircular_chords", 0) else ())
            for path, index in CASES]


# Cases over twice the smallest uniform grid, each a known shortfall of the bound: the motor
# hairpin (motor_tube[1]) at 1e-2, whose rotation terms the bound counts in full
# (docs/tolerance.md). A case that comes within twice fails here, to be taken off the list.
# (The hairpin's uniform grids' deviation does not fall monotonically with the ring count, so
# the grid the bisection finds depends on the count around: with 23 around it found 61 rings,
# with 19 it finds 9; docs/accuracy.md.)
OVER_TWICE = {("motor_tube", 1, 1e-2)}


@pytest.mark.parametrize("relative", [1e-2, 1e-3])  # 1e-4: benchmarks/report_accuracy.py --compare-only
@pytest.mark.parametrize("path, index", COMPARED, ids=[f"{p.stem}[{i}]" for p, i in CASES])
def test_vertices_against_the_smallest_uniform_grid(path, index, relative):
    """The smallest uniform grid with the same vertices around that reaches the tolerance, found
    by bisection on its ring count (measured by cgamesh.meshing.tolerance.deviation): the tolerance mesh
    never needs more than twice its vertices, and the target is fewer. Where the target is
    missed (the bound is conservative: docs/tolerance.md), the test reports an expected failure
    with the ratio, not a pass."""
    spec = load_scene(path).surfaces[index]
    surface = build_surface(spec)
    tolerance = relative * surface.frame.scale
    mesh = mesh_surface(spec, Resolution(tolerance=tolerance))
    across, rings = _grid_shape(mesh, spec)
    low, high = 2, max(3, rings // 2)
    while uniform_deviation(surface, spec, across, high)[1] > tolerance:
        low, high = high, 2 * high
    while high - low > 1:
        middle = (low + high) // 2
        if uniform_deviation(surface, spec, across, middle)[1] <= tolerance:
            high = middle
        else:
            low = middle
    uniform_vertices = uniform_deviation(surface, spec, across, high)[0]
    ratio = mesh.vertex_count / uniform_vertices
    if (path.stem, index, relative) in OVER_TWICE:
        assert ratio > 2.0, f"{ratio:.2f} x: within twice now, take the case off OVER_TWICE"
        pytest.xfail(f"{ratio:.2f} x the smallest uniform grid's vertices (known: the bound is loose here)")
    assert ratio <= 2.0, f"{mesh.vertex_count} vertices against {uniform_vertices} uniform"
    if ratio >= 1.0:
        pytest.xfail(f"{ratio:.2f} x the smallest uniform grid's vertices (target < 1)")


def uniform_deviation(surface, spec, across: int, rings: int) -> tuple[int, float]:
    """(vertices, deviation) of the grid with ``rings`` rings evenly spaced in t."""
    t = np.linspace(0.0, surface.segment_count, rings)
    if spec.type == "point_pairs":
        uniform = mesh_ribbon_surface(surface, across, t=t, closed=spec.closed)
        return uniform.vertex_count, grid_deviation(surface, t, uniform.positions.reshape(rings, across, 3),
                                                    SEGMENTS).max
    uniform = mesh_circle_surface(surface, across - 1, t=t, caps=spec.caps, closed=spec.closed)
    grid = uniform.positions[: rings * across].reshape(rings, across, 3)
    return uniform.vertex_count, grid_deviation(surface, t, grid, CIRCLES).max


def _grid_shape(mesh, spec) -> tuple[int, int]:
    """(columns, rings) of the mesh's (t, theta) grid, read from its UVs (u is the column's)."""
    columns = int(np.argmax(np.diff(mesh.uvs[:, 0]) < 0.0)) + 1 if spec.type == "circles" else None
    if spec.type == "point_pairs":
        columns = int(np.argmax(np.diff(mesh.uvs[:, 0]) < 0.0)) + 1
    return columns, _grid_size(mesh, spec) // columns


def _grid_size(mesh, spec) -> int:
    """Vertices in the grid (a circle surface's caps come after it: 2 (around + 1) vertices)."""
    if spec.type == "circles" and spec.caps:
        columns = int(np.argmax(np.diff(mesh.uvs[:, 0]) < 0.0)) + 1
        return mesh.vertex_count - 2 * columns
    return mesh.vertex_count


@pytest.mark.parametrize("stem", ["kb_tube", "closed_loop", "motor_tube"])
def test_a_tolerance_mesh_is_the_mesher_s_mesh_on_the_plan_s_rings(stem):
    """The tolerance run reads its rings once and hands them to the mesher: the mesh must be, bit
    for bit, the one the mesher makes reading them itself (caps and closed loops included)."""
    from cgamesh.meshing.circles import read_rings

    spec = load_scene(Path(__file__).resolve().parent.parent / "examples" / f"{stem}.yaml").surfaces[0]
    surface = build_surface(spec)
    tolerance = 1e-3 * surface.frame.scale
    plan = plan_tolerance(surface, tolerance, "circles", spec.closed)
    run = mesh_surface(spec, Resolution(tolerance=tolerance))
    read_here = mesh_circle_surface(surface, plan.around, t=plan.t, caps=spec.caps, closed=spec.closed)
    handed = mesh_circle_surface(surface, plan.around, t=plan.t, caps=spec.caps, closed=spec.closed,
                                 rings=read_rings(surface, plan.t))
    for mesh in (run, handed):
        for name in ("positions", "normals", "uvs", "faces"):
            assert np.array_equal(getattr(mesh, name), getattr(read_here, name)), (stem, name)
    assert run.max_deviation == plan.bound <= tolerance
