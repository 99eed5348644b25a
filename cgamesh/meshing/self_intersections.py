"""Which triangles of a mesh cross each other, decided exactly on the stored floats.

A closed surface written to a file is a set of float triangles; whether two of them cross is a
question about those floats, and rounding the positions (float64 -> float32) can change the
answer for sliver triangles. This module answers it exactly, in array code over whole batches:

- broad phase: every triangle's bounding box is hashed into a uniform grid of cubes, and a
  pair of triangles is a candidate once, in the cube holding the low corner of the overlap of
  their boxes;
- narrow phase: signs of orientation determinants (Shewchuk's ``orient3d`` / ``orient2d``),
  evaluated in float64 with his a-priori error bound and, where that bound cannot decide the
  sign, again in rational arithmetic (every float is a rational number), so no answer depends
  on rounding.

What counts as a crossing, for triangles of the welded mesh (equal positions are one vertex):
two triangles with no common vertex that share any point; two triangles with one common vertex
that share any other point (MeshLab counts these too: a fan folded through itself); two
triangles with a common edge that lie in one plane on the same side of it (folded flat onto
each other). A triangle whose corners are collinear is reported apart (``degenerate_faces``).
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np

_EPS = 2.0 ** -53
_O3D_BOUND = (7.0 + 56.0 * _EPS) * _EPS  # Shewchuk's o3derrboundA
_O2D_BOUND = (3.0 + 16.0 * _EPS) * _EPS  # Shewchuk's ccwerrboundA
_CHUNK = 1 << 20  # candidate pairs tested at once (bounded temporary memory)


def welded_faces(positions: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(points, faces) with every bit-identical position stored once."""
    rows = np.ascontiguousarray(positions, dtype=np.float64) + 0.0  # -0.0 is 0.0
    keys = rows.view(np.dtype((np.void, 24))).ravel()
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    return rows[first], inverse.ravel()[np.asarray(faces, dtype=np.int64)]


def _integers(*columns: np.ndarray) -> list[np.ndarray]:
    """The float64 columns (N,) of each row scaled by one power of two per row so that every
    value is an integer, as object arrays of Python ints (exact, unbounded)."""
    stacked = np.stack(columns, axis=1)
    _, exponent = np.frexp(stacked)
    nonzero = stacked != 0.0
    shift = np.where(nonzero, 53 - exponent, -10**6).max(axis=1)  # x * 2**(53 - e) is an integer
    shift = np.where(nonzero.any(axis=1), shift, 0)
    scaled = np.ldexp(stacked, shift[:, None])
    if not np.isfinite(scaled).all():  # exponents too far apart for float64: exact rationals
        return [np.array([Fraction(float(x)) for x in c], dtype=object) for c in columns]
    rows = scaled.astype(object)
    return [np.array([int(x) for x in rows[:, j]], dtype=object) for j in range(stacked.shape[1])]


def _sign(values: np.ndarray) -> np.ndarray:
    return np.array([(v > 0) - (v < 0) for v in values], dtype=np.int8)


def _orient3d(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Sign (-1, 0, 1) of det[a - d, b - d, c - d] for (N, 3) float64 rows, exact."""
    ad, bd, cd = a - d, b - d, c - d
    m1 = bd[:, 0] * cd[:, 1] - cd[:, 0] * bd[:, 1]
    m2 = cd[:, 0] * ad[:, 1] - ad[:, 0] * cd[:, 1]
    m3 = ad[:, 0] * bd[:, 1] - bd[:, 0] * ad[:, 1]
    det = ad[:, 2] * m1 + bd[:, 2] * m2 + cd[:, 2] * m3
    permanent = ((np.abs(bd[:, 0] * cd[:, 1]) + np.abs(cd[:, 0] * bd[:, 1])) * np.abs(ad[:, 2])
                 + (np.abs(cd[:, 0] * ad[:, 1]) + np.abs(ad[:, 0] * cd[:, 1])) * np.abs(bd[:, 2])
                 + (np.abs(ad[:, 0] * bd[:, 1]) + np.abs(bd[:, 0] * ad[:, 1])) * np.abs(cd[:, 2]))
    sign = np.sign(det).astype(np.int8)
    # permanent == 0: every product is exactly zero, so is the determinant
    unsure = np.flatnonzero((np.abs(det) <= _O3D_BOUND * permanent) & (permanent > 0))
    if len(unsure):
        k = unsure
        x = _integers(*(p[k, j] for p in (a, b, c, d) for j in range(3)))
        a3, b3, c3, d3 = x[0:3], x[3:6], x[6:9], x[9:12]
        ad = [u - v for u, v in zip(a3, d3)]
        bd = [u - v for u, v in zip(b3, d3)]
        cd = [u - v for u, v in zip(c3, d3)]
        exact = (ad[2] * (bd[0] * cd[1] - cd[0] * bd[1]) + bd[2] * (cd[0] * ad[1] - ad[0] * cd[1])
                 + cd[2] * (ad[0] * bd[1] - bd[0] * ad[1]))
        sign[k] = _sign(exact)
    return sign


def _orient2d(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Sign of det[a - c, b - c] for (N, 2) float64 rows, exact."""
    left = (a[:, 0] - c[:, 0]) * (b[:, 1] - c[:, 1])
    right = (a[:, 1] - c[:, 1]) * (b[:, 0] - c[:, 0])
    det = left - right
    sign = np.sign(det).astype(np.int8)
    bound = np.abs(left) + np.abs(right)
    unsure = np.flatnonzero((np.abs(det) <= _O2D_BOUND * bound) & (bound > 0))
    if len(unsure):
        k = unsure
        ax, ay, bx, by, cx, cy = _integers(a[k, 0], a[k, 1], b[k, 0], b[k, 1], c[k, 0], c[k, 1])
        sign[k] = _sign((ax - cx) * (by - cy) - (ay - cy) * (bx - cx))
    return sign


def degenerate_faces(points: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Indices of the faces whose three corners are collinear (zero area), decided exactly."""
    tri = points[faces]
    repeated = (faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (faces[:, 0] == faces[:, 2])
    collinear = np.ones(len(faces), dtype=bool)
    for i, j in ((0, 1), (1, 2), (0, 2)):  # zero area <=> every axis-plane projection is degenerate
        collinear &= _orient2d(tri[:, 0][:, [i, j]], tri[:, 1][:, [i, j]], tri[:, 2][:, [i, j]]) == 0
    return np.flatnonzero(repeated | collinear)


def candidate_pairs(points: np.ndarray, faces: np.ndarray, among: np.ndarray | None = None) -> np.ndarray:
    """(K, 2) pairs i < j of faces whose closed bounding boxes overlap, each pair once; with
    ``among`` ((T,) bool), only the pairs with at least one face among those."""
    tri = points[faces]
    lo, hi = tri.min(axis=1), tri.max(axis=1)
    if len(faces) < 2:
        return np.empty((0, 2), dtype=np.int64)
    extent = (hi - lo).max(axis=1)
    cell = float(np.quantile(extent, 0.9)) or 1.0  # most boxes span one or two cubes per axis
    origin = lo.min(axis=0)
    first = np.floor((lo - origin) / cell).astype(np.int64)
    last = np.floor((hi - origin) / cell).astype(np.int64)
    span = last - first + 1
    count = span.prod(axis=1)
    # One entry per (face, cube) its box touches.
    face = np.repeat(np.arange(len(faces)), count)
    rank = np.arange(len(face)) - np.repeat(np.cumsum(count) - count, count)
    sy, sz = span[face, 1], span[face, 2]
    cube = first[face] + np.stack([rank // (sy * sz), (rank // sz) % sy, rank % sz], axis=1)
    dims = cube.max(axis=0) + 1
    key = (cube[:, 0] * dims[1] + cube[:, 1]) * dims[2] + cube[:, 2]
    if among is not None:  # only the cubes that hold a face of interest
        wanted = np.unique(key[among[face]])
        keep = np.isin(key, wanted)
        key, face = key[keep], face[keep]
    order = np.argsort(key, kind="stable")
    key, face = key[order], face[order]
    start = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
    size = np.diff(np.r_[start, len(key)])
    group_end = np.repeat(start + size, size)
    partners = group_end - np.arange(len(key)) - 1
    found = []
    # chunks of entries whose pairs fit in _CHUNK
    bounds = np.searchsorted(np.cumsum(partners), np.arange(0, partners.sum() + _CHUNK, _CHUNK), side="left")
    bounds = np.unique(np.r_[0, bounds, len(key)])
    for s, e in zip(bounds[:-1], bounds[1:]):
        n = partners[s:e]
        if n.sum() == 0:
            continue
        i = np.repeat(np.arange(s, e), n)
        j = i + 1 + (np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n))
        a, b = face[i], face[j]
        low = np.maximum(lo[a], lo[b])
        keep = (low <= np.minimum(hi[a], hi[b])).all(axis=1) & (a != b)
        a, b, low, here = a[keep], b[keep], low[keep], key[i[keep]]
        home = np.minimum(np.floor((low - origin) / cell).astype(np.int64), dims - 1)
        keep = ((home[:, 0] * dims[1] + home[:, 1]) * dims[2] + home[:, 2]) == here
        if among is not None:
            keep &= among[a] | among[b]
        found.append(np.stack([np.minimum(a[keep], b[keep]), np.maximum(a[keep], b[keep])], axis=1))
    return np.concatenate(found) if found else np.empty((0, 2), dtype=np.int64)


def _segment_crosses_triangle(p, q, t0, t1, t2) -> np.ndarray:
    """Whether closed segments pq meet closed triangles (t0, t1, t2) at a point, for segments
    not lying in the triangle's plane (those are the coplanar test's)."""
    s1, s2 = _orient3d(t0, t1, t2, p), _orient3d(t0, t1, t2, q)
    straddle = (s1.astype(np.int16) * s2 <= 0) & ~((s1 == 0) & (s2 == 0))
    result = np.zeros(len(p), dtype=bool)
    k = np.flatnonzero(straddle)
    if len(k):
        o = np.stack([_orient3d(p[k], q[k], a[k], b[k]) for a, b in ((t0, t1), (t1, t2), (t2, t0))], axis=1)
        result[k] = (o >= 0).all(axis=1) | (o <= 0).all(axis=1)
    return result


def _segments_meet_2d(p, q, a, b) -> np.ndarray:
    d1, d2 = _orient2d(a, b, p), _orient2d(a, b, q)
    d3, d4 = _orient2d(p, q, a), _orient2d(p, q, b)
    proper = (d1.astype(np.int16) * d2 < 0) & (d3.astype(np.int16) * d4 < 0)

    def within(x, u, v):
        return ((np.minimum(u, v) <= x) & (x <= np.maximum(u, v))).all(axis=1)

    return (proper | ((d1 == 0) & within(p, a, b)) | ((d2 == 0) & within(q, a, b))
            | ((d3 == 0) & within(a, p, q)) | ((d4 == 0) & within(b, p, q)))


def _inside_2d(x, t) -> np.ndarray:
    s = np.stack([_orient2d(t[:, i], t[:, (i + 1) % 3], x) for i in range(3)], axis=1)
    return (s >= 0).all(axis=1) | (s <= 0).all(axis=1)


def _project(A, B) -> tuple[np.ndarray, np.ndarray]:
    """Both triangles projected along the dominant axis of A's normal (a projection that keeps
    A's plane, and so coplanar B, non-degenerate)."""
    normal = np.abs(np.cross(A[:, 1] - A[:, 0], A[:, 2] - A[:, 0]))
    drop = np.argmax(normal, axis=1)
    keep = np.array([[1, 2], [0, 2], [0, 1]])[drop]  # (N, 2)
    rows = np.arange(len(A))[:, None, None]
    return A[rows, np.arange(3)[None, :, None], keep[:, None, :]], B[rows, np.arange(3)[None, :, None], keep[:, None, :]]


def _coplanar_overlap(A, B) -> np.ndarray:
    a, b = _project(A, B)
    meet = np.zeros(len(A), dtype=bool)
    for i in range(3):
        for j in range(3):
            meet |= _segments_meet_2d(a[:, i], a[:, (i + 1) % 3], b[:, j], b[:, (j + 1) % 3])
    return meet | _inside_2d(a[:, 0], b) | _inside_2d(b[:, 0], a)


def triangles_meet(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Whether closed triangles A[k] and B[k] ((N, 3, 3) float64) share a point, exactly."""
    side_b = np.stack([_orient3d(A[:, 0], A[:, 1], A[:, 2], B[:, k]) for k in range(3)], axis=1)
    apart = (side_b > 0).all(axis=1) | (side_b < 0).all(axis=1)
    result = np.zeros(len(A), dtype=bool)
    k = np.flatnonzero(~apart)
    A, B, side_b = A[k], B[k], side_b[k]
    side_a = np.stack([_orient3d(B[:, 0], B[:, 1], B[:, 2], A[:, m]) for m in range(3)], axis=1)
    apart = (side_a > 0).all(axis=1) | (side_a < 0).all(axis=1)
    coplanar = (side_b == 0).all(axis=1) & ~apart
    crossing = ~apart & ~coplanar
    if coplanar.any():
        result[k[coplanar]] = _coplanar_overlap(A[coplanar], B[coplanar])
    if crossing.any():
        c = np.flatnonzero(crossing)
        A, B = A[c], B[c]
        hit = np.zeros(len(c), dtype=bool)
        for i in range(3):
            hit |= _segment_crosses_triangle(A[:, i], A[:, (i + 1) % 3], B[:, 0], B[:, 1], B[:, 2])
            hit |= _segment_crosses_triangle(B[:, i], B[:, (i + 1) % 3], A[:, 0], A[:, 1], A[:, 2])
        result[k[c]] = hit
    return result


def _segment_meets_triangle(p, q, T) -> np.ndarray:
    """Closed segment pq against closed triangle T ((N, 3, 3)), any configuration, exactly."""
    s1 = _orient3d(T[:, 0], T[:, 1], T[:, 2], p)
    s2 = _orient3d(T[:, 0], T[:, 1], T[:, 2], q)
    in_plane = (s1 == 0) & (s2 == 0)
    result = _segment_crosses_triangle(p, q, T[:, 0], T[:, 1], T[:, 2])
    if in_plane.any():
        k = np.flatnonzero(in_plane)
        seg = np.stack([p[k], q[k], q[k]], axis=1)  # a degenerate triangle: the segment
        t, s = _project(T[k], seg)
        meet = np.zeros(len(k), dtype=bool)
        for j in range(3):
            meet |= _segments_meet_2d(s[:, 0], s[:, 1], t[:, j], t[:, (j + 1) % 3])
        result[k] = meet | _inside_2d(s[:, 0], t)
    return result


def _classify(points, faces, pairs) -> np.ndarray:
    """Whether each candidate pair crosses (the module's definition)."""
    fa, fb = faces[pairs[:, 0]], faces[pairs[:, 1]]
    same = fa[:, :, None] == fb[:, None, :]  # (K, 3, 3)
    shared = same.any(axis=2).sum(axis=1)
    result = shared == 3  # the same triangle twice
    k = np.flatnonzero(shared == 0)
    if len(k):
        result[k] = triangles_meet(points[fa[k]], points[fb[k]])
    k = np.flatnonzero(shared == 1)
    if len(k):
        # Rotate each triangle so its common vertex comes first: they meet elsewhere exactly when
        # the edge opposite it in one meets the other triangle.
        ia = np.argmax(same[k].any(axis=2), axis=1)
        ib = np.argmax(same[k].any(axis=1), axis=1)
        ra = fa[k][np.arange(len(k))[:, None], (ia[:, None] + np.arange(3)) % 3]
        rb = fb[k][np.arange(len(k))[:, None], (ib[:, None] + np.arange(3)) % 3]
        A, B = points[ra], points[rb]
        result[k] = _segment_meets_triangle(A[:, 1], A[:, 2], B) | _segment_meets_triangle(B[:, 1], B[:, 2], A)
    proper = (same.any(axis=2).sum(axis=1) == 2) & (same.any(axis=1).sum(axis=1) == 2)
    k = np.flatnonzero((shared == 2) & proper)  # (a face with a repeated corner is degenerate_faces')
    if len(k):
        # Common edge uv: folded flat when both opposite corners lie in one plane with it, on
        # the same side.
        only_a = ~same[k].any(axis=2)
        only_b = ~same[k].any(axis=1)
        a = points[fa[k][only_a]]
        b = points[fb[k][only_b]]
        common = fa[k][~only_a].reshape(-1, 2)
        u, v = points[common[:, 0]], points[common[:, 1]]
        flat = _orient3d(u, v, a, b) == 0
        if flat.any():
            f = np.flatnonzero(flat)
            t, s = _project(np.stack([u[f], v[f], a[f]], axis=1), np.stack([u[f], v[f], b[f]], axis=1))
            result[k[f]] = (_orient2d(t[:, 0], t[:, 1], t[:, 2]) * _orient2d(s[:, 0], s[:, 1], s[:, 2])) > 0
    return result


def self_intersections(positions: np.ndarray, faces: np.ndarray, among: np.ndarray | None = None) -> np.ndarray:
    """(K, 2) pairs of face indices (i < j) that cross, decided exactly on ``positions`` as
    given (float64; round first to check what a float32 file stores). Equal positions are
    welded first, so repeated seam vertices count as one. With ``among`` ((T,) bool), only
    the pairs with at least one face among those are examined."""
    points, welded = welded_faces(positions, faces)
    pairs = candidate_pairs(points, welded, among)
    hits = [pairs[s:s + _CHUNK][_classify(points, welded, pairs[s:s + _CHUNK])]
            for s in range(0, len(pairs), _CHUNK)]
    return np.concatenate(hits) if hits else np.empty((0, 2), dtype=np.int64)
