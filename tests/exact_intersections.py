"""Exact triangle-triangle intersection tests (rational arithmetic on the floats as stored), to
confirm or refute the self-intersections MeshLab reports.

MeshLab's test (vcglib's NoDivTriTriIsect, Moeller's interval method in floating point) reaches
its interval comparison with plane distances of ~1e-17 for triangles that are coplanar up to
rounding, as every triangle a boolean cuts into pieces is, and can then report two disjoint
coplanar triangles as crossing. Every float is a rational number, so these predicates decide
the stored mesh exactly.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np


def _exact(points: np.ndarray) -> list[tuple[Fraction, ...]]:
    return [tuple(Fraction(float(x)) for x in p) for p in points]


def _sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def _sign(x) -> int:
    return (x > 0) - (x < 0)


def orient3d(a, b, c, d) -> int:
    u, v, w = _sub(b, a), _sub(c, a), _sub(d, a)
    return _sign(u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
                 + u[2] * (v[0] * w[1] - v[1] * w[0]))


def _orient2d(a, b, c) -> int:
    return _sign((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))


def _on_segment_2d(p, a, b) -> bool:
    return min(a[0], b[0]) <= p[0] <= max(a[0], b[0]) and min(a[1], b[1]) <= p[1] <= max(a[1], b[1])


def _segments_meet_2d(p, q, a, b) -> bool:
    d1, d2, d3, d4 = _orient2d(a, b, p), _orient2d(a, b, q), _orient2d(p, q, a), _orient2d(p, q, b)
    if d1 * d2 < 0 and d3 * d4 < 0:
        return True
    return ((d1 == 0 and _on_segment_2d(p, a, b)) or (d2 == 0 and _on_segment_2d(q, a, b))
            or (d3 == 0 and _on_segment_2d(a, p, q)) or (d4 == 0 and _on_segment_2d(b, p, q)))


def _point_in_triangle_2d(p, t) -> bool:
    s = [_orient2d(t[i], t[(i + 1) % 3], p) for i in range(3)]
    return all(x >= 0 for x in s) or all(x <= 0 for x in s)


def _coplanar_overlap(A, B) -> bool:
    normal = np.abs(np.cross(np.array(A[1], float) - np.array(A[0], float),
                             np.array(A[2], float) - np.array(A[0], float)))
    keep = [k for k in range(3) if k != int(np.argmax(normal))]  # project along the dominant axis
    a = [tuple(p[k] for k in keep) for p in A]
    b = [tuple(p[k] for k in keep) for p in B]
    if any(_segments_meet_2d(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3]) for i in range(3) for j in range(3)):
        return True
    return _point_in_triangle_2d(a[0], b) or _point_in_triangle_2d(b[0], a)


def _segment_meets_triangle(p, q, T) -> bool:
    s1, s2 = orient3d(*T, p), orient3d(*T, q)
    if s1 * s2 > 0:
        return False
    if s1 == 0 and s2 == 0:
        return False  # within the plane: the coplanar case is decided separately
    t = [orient3d(p, q, T[i], T[(i + 1) % 3]) for i in range(3)]
    return all(x >= 0 for x in t) or all(x <= 0 for x in t)


def triangles_meet(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two closed triangles (3, 3) share any point, decided exactly."""
    A, B = _exact(a), _exact(b)
    side_b = [orient3d(*A, p) for p in B]
    side_a = [orient3d(*B, p) for p in A]
    if all(s > 0 for s in side_b) or all(s < 0 for s in side_b):
        return False
    if all(s > 0 for s in side_a) or all(s < 0 for s in side_a):
        return False
    if all(s == 0 for s in side_b):
        return _coplanar_overlap(A, B)
    return (any(_segment_meets_triangle(A[i], A[(i + 1) % 3], B) for i in range(3))
            or any(_segment_meets_triangle(B[i], B[(i + 1) % 3], A) for i in range(3)))


def confirmed_intersections(positions: np.ndarray, faces: np.ndarray, suspects: np.ndarray) -> list[tuple[int, int]]:
    """Pairs (suspect face, other face) sharing no vertex that truly meet, decided exactly for
    every face whose bounding box overlaps a suspect's."""
    lo = positions[faces].min(axis=1)
    hi = positions[faces].max(axis=1)
    found = []
    for f in np.asarray(suspects):
        near = np.flatnonzero((lo <= hi[f]).all(axis=1) & (hi >= lo[f]).all(axis=1))
        for g in near:
            if g != f and not np.isin(faces[g], faces[f]).any() and triangles_meet(positions[faces[f]], positions[faces[g]]):
                found.append((int(f), int(g)))
    return found
