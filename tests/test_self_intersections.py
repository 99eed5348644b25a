"""The exact self-intersection test (cgamesh.meshing.self_intersections) against rational
arithmetic (tests/exact_intersections.py) on triangles built to hit every degenerate case
(small integer coordinates: touching, coplanar, collinear and shared corners everywhere), and
the float32 grid repair (cgamesh.meshing.float32_grid) on a closed surface whose slivers cross
once rounded."""

from __future__ import annotations

import numpy as np
import pytest
from exact_intersections import triangles_meet as rational_meet

from cgamesh.meshing.float32_grid import grid_step, on_grid, repair
from cgamesh.meshing.self_intersections import (candidate_pairs, degenerate_faces, self_intersections,
                                                triangles_meet)


@pytest.mark.parametrize("seed", range(4))
def test_triangles_meet_agrees_with_rational_arithmetic(seed):
    rng = np.random.default_rng(seed)
    A = rng.integers(-2, 3, size=(600, 3, 3)).astype(np.float64)
    B = rng.integers(-2, 3, size=(600, 3, 3)).astype(np.float64)
    B[::3, :, 2] = A[::3, :1, 2]  # a third exactly coplanar with z = const planes of A's first corner
    A[::3, :, 2] = A[::3, :1, 2]
    scale = rng.choice([1.0, 2.0 ** -20, 3.0e4], size=(600, 1, 1))  # exact scalings too
    A, B = A * scale + 0.125, B * scale + 0.125
    keep = np.array([np.linalg.norm(np.cross(t[1] - t[0], t[2] - t[0])) > 0 for t in np.concatenate([A, B])])
    keep = keep[:600] & keep[600:]
    A, B = A[keep], B[keep]
    got = triangles_meet(A, B)
    want = np.array([rational_meet(a, b) for a, b in zip(A, B)])
    np.testing.assert_array_equal(got, want)
    assert 0.2 < want.mean() < 0.8  # both answers are well represented


def test_a_tilted_pair_decided_by_one_unit_in_the_last_place():
    """Coordinates far from the origin where the float64 determinant alone cannot decide."""
    base = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]) + 35_000.0
    for dz, expected in ((0.0, True), (np.spacing(35_000.0), False)):
        other = np.array([[0.2, 0.2, dz], [0.6, 0.2, 1.0], [0.2, 0.6, 1.0]]) + 35_000.0
        assert triangles_meet(base[None], other[None])[0] == expected == rational_meet(base, other)


def _closed_box(n: int = 6) -> tuple[np.ndarray, np.ndarray]:
    """A closed, outward-wound grid of a cube's six faces, n x n quads each, vertices shared."""
    import trimesh

    box = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    for _ in range(int(np.log2(n))):
        box = box.subdivide()
    return np.asarray(box.vertices, dtype=np.float64), np.asarray(box.faces, dtype=np.int64)


def test_candidate_pairs_are_every_overlapping_pair_once():
    points, faces = _closed_box()
    rng = np.random.default_rng(1)
    points = points + rng.normal(scale=0.01, size=points.shape)
    got = {tuple(p) for p in candidate_pairs(points, faces).tolist()}
    lo, hi = points[faces].min(axis=1), points[faces].max(axis=1)
    overlap = (lo[:, None] <= hi[None]).all(axis=2) & (hi[:, None] >= lo[None]).all(axis=2)
    want = {(i, j) for i, j in zip(*np.nonzero(np.triu(overlap, 1)))}
    assert got == want
    assert len(candidate_pairs(points, faces)) == len(got)  # each once


def test_a_closed_box_has_no_crossing_and_a_pushed_in_corner_has_some():
    points, faces = _closed_box()
    assert len(self_intersections(points, faces)) == 0
    assert len(degenerate_faces(points, faces)) == 0
    corner = np.argmax(points.sum(axis=1))
    pushed = points.copy()
    pushed[corner] = -0.7  # through the box and out past the far corner
    pairs = self_intersections(pushed, faces)
    assert len(pairs) > 0
    assert all(rational_meet(pushed[faces[a]], pushed[faces[b]]) for a, b in pairs
               if not set(faces[a]) & set(faces[b]))


def test_the_union_far_from_the_origin_is_repaired_on_the_float32_grid(monkeypatch):
    """A random 60-tube arbor 30,000 units from the origin (where a neuron in voxel units
    lies): rounded to the float32 grid, hundreds of its triangles cross another or lose their
    area; after the repair none does, decided exactly, and the surface is still closed and
    2-manifold with every position a float32 number."""
    pytest.importorskip("manifold3d", reason="SKIPPED, NOT CHECKED: manifold3d is not installed")
    import dataclasses

    from closed_pieces import arbor

    from cgamesh.meshing import float32_grid
    from cgamesh.meshing.watertight import union

    pieces = [dataclasses.replace(p, positions=p.positions + 3.0e4) for p in arbor(60, 8, 4, np.random.default_rng(3))]
    counts = {}

    def counted(reference, step, faces, topology, removable, rounds=float32_grid.ROUNDS):
        counts["rounded"] = repair(reference, step, faces, topology, removable, rounds=0)[2]
        return repair(reference, step, faces, topology, removable, rounds)

    monkeypatch.setattr(float32_grid, "repair", counted)
    result = union(pieces, "arbor")
    assert counts["rounded"] > 100  # what rounding alone leaves
    positions = result.positions
    np.testing.assert_array_equal(positions.astype(np.float32).astype(np.float64), positions)
    np.testing.assert_array_equal(positions, on_grid(positions, grid_step(positions)))
    assert len(self_intersections(positions, result.faces)) == 0
    points, welded = _welded(result)
    assert len(degenerate_faces(points, welded)) == 0
    edges = np.sort(np.concatenate([welded[:, [0, 1]], welded[:, [1, 2]], welded[:, [2, 0]]]), axis=1)
    _, counts_per_edge = np.unique(edges, axis=0, return_counts=True)
    assert (counts_per_edge == 2).all()  # closed, 2-manifold


def _welded(mesh):
    from cgamesh.meshing.self_intersections import welded_faces

    return welded_faces(mesh.positions, mesh.faces)
