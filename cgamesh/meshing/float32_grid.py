"""A closed mesh put on the grid that float32 files store exactly, with no triangle crossing
another or collapsing to a line there (checked exactly, repaired locally).

Every writer stores positions as float32: absolute (PLY, STL), relative to the float64 centre
of the bounding box (USD, glTF), or as decimals with 8 places (OBJ). A union computed in
float64 is free of self-intersections, but rounding moves each vertex by up to half a float32
step (0.002 at 35,000 units), and a sliver triangle narrower than that, left where two cut lines
of the boolean nearly meet, can flip over and pass through its neighbours, or lose its area.

So the positions are rounded here, once, to the grid of step ``h`` = two float32 steps at the
largest coordinate (a power of two): every grid point, and every grid point minus the centre of
the grid points' bounding box (itself on the grid of h / 2), is a float32 number, and with h at
least 2**-8 a decimal with 8 places too, so those writers store exactly the mesh checked here.
Then, round after round until nothing is left, every triangle that has zero area or crosses
another (``cgamesh.meshing.self_intersections``, exact) is removed locally: its shortest edge is
collapsed onto one of its end points (a vertex of the grid, so nothing leaves it; a vertex the
union made on a cut line goes before an original one), or failing that its longest edge is
flipped, each only where the surface stays a closed 2-manifold and no neighbouring triangle
turns over.
"""

from __future__ import annotations

import numpy as np

from cgamesh.meshing.self_intersections import degenerate_faces, self_intersections
from cgamesh.meshing.weld import weld_by_position

ROUNDS = 12  # each round removes every flagged triangle it can; the real neurons need 1-3


def grid_step(positions: np.ndarray) -> float:
    """Two float32 steps at the largest |coordinate| (a power of two; 2**-126 at the least)."""
    largest = float(np.abs(positions).max()) if positions.size else 0.0
    return 2.0 * float(np.spacing(np.float32(max(largest, 2.0 ** -100))))


def on_grid(positions: np.ndarray, step: float) -> np.ndarray:
    """Positions rounded to the nearest multiple of ``step`` (exact: ``step`` is a power of two)."""
    return np.round(positions / step) * step


def repair(reference: np.ndarray, step: float, faces: np.ndarray, topology: np.ndarray, removable: np.ndarray,
           rounds: int = ROUNDS) -> tuple[np.ndarray, np.ndarray, int]:
    """Remove degenerate and crossing triangles of a closed mesh on a grid, on copies.

    reference: (V, 3) float64 positions (the float64 surface, free of crossings), rounded here to
    the grid of ``step`` and kept as the reference orientation of every triangle; faces: (T, 3)
    indices; topology: (V,) the surface's
    vertex of each row (rows of one vertex repeat it at seams and creases; distinct vertices may
    share a grid point after rounding, and an edge between two such is what gets collapsed);
    removable: (V,) bool, vertices to collapse first. Returns (positions, faces, flagged): the
    repaired mesh (unused rows kept, faces dropped) and how many triangles the last exact check
    still flags (0 on success). The first check covers every pair of triangles; later ones every
    pair with a triangle an edit changed or could not fix.
    """
    reference = np.asarray(reference, dtype=np.float64)
    positions = on_grid(reference, step)
    faces = np.array(faces, dtype=np.int64)
    topology = np.array(topology, dtype=np.int64)
    among = None
    for _ in range(rounds):
        flagged = _flagged(positions, faces, topology, among)
        if not len(flagged):
            return positions, faces, 0
        faces, among = _fix(positions, faces, topology, reference, flagged, removable)
    return positions, faces, len(_flagged(positions, faces, topology, among))


def _flagged(positions: np.ndarray, faces: np.ndarray, topology: np.ndarray, among: np.ndarray | None) -> np.ndarray:
    """Faces with zero area, faces that cross another, and faces at a grid point that two
    vertices of the surface not joined by an edge both reached (a reader that merges equal
    positions, as MeshLab does, would see the surface pinched there)."""
    place = weld_by_position(positions)
    welded = place[faces]
    pairs = self_intersections(positions, faces, among)
    corners = np.unique(np.stack([welded.ravel(), topology[faces].ravel()], axis=1), axis=0)
    shared_place = corners[:, 0][np.r_[corners[1:, 0] == corners[:-1, 0], False]
                                 | np.r_[False, corners[1:, 0] == corners[:-1, 0]]]
    pinched = np.flatnonzero(np.isin(welded, shared_place).any(axis=1))
    return np.unique(np.r_[degenerate_faces(positions, welded), pairs.ravel(), pinched]).astype(np.int64)


def _fix(positions, faces, topology, reference, flagged, removable) -> tuple[np.ndarray, np.ndarray]:
    """One round: an edge collapse or flip at each flagged face whose neighbourhood no earlier
    operation of this round touched. Returns the new faces and which of them to check again
    (positions and topology change in place)."""
    surface = _Surface(positions, faces, topology, reference)
    # slivers first: a fat triangle that crosses another is usually pushed there by one
    tri = positions[faces[flagged]]
    shortest = np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2).min(axis=1)
    for f in flagged[np.argsort(shortest, kind="stable")]:
        if surface.alive[f] and not surface.touched(f):
            (surface.collapse_shortest(f, removable) or surface.flip_longest(f)
             or surface.collapse_nearby(f, removable))
    again = surface.changed
    again[flagged] = True  # fixed or not, look again
    return surface.faces[surface.alive], again[surface.alive]


class _Surface:
    """Adjacency for local edits: a vertex is a topology id (``vid``), a face keeps the rows of
    its corners (which carry the normals, UVs ...)."""

    def __init__(self, positions: np.ndarray, faces: np.ndarray, topology: np.ndarray, reference: np.ndarray):
        self.positions = positions
        self.reference = reference
        self.faces = faces
        self.alive = np.ones(len(faces), dtype=bool)
        self.changed = np.zeros(len(faces), dtype=bool)
        weld = topology
        self.vid = weld  # the surface's vertex of each row (updated in place by collapses)
        corner_ids = weld[faces].ravel()
        order = np.argsort(corner_ids, kind="stable")
        ids = corner_ids[order]
        starts = np.searchsorted(ids, np.arange(len(positions) + 1))
        self._face_order, self._face_starts = order // 3, starts
        members = np.argsort(weld, kind="stable")
        self._members, self._member_starts = members, np.searchsorted(weld[members], np.arange(len(positions) + 1))
        self.locked: set[int] = set()

    def faces_of(self, v: int) -> list[int]:
        found = self._face_order[self._face_starts[v]:self._face_starts[v + 1]]
        return [int(f) for f in found if self.alive[f]]

    def corners(self, f: int) -> list[int]:
        return [int(self.vid[c]) for c in self.faces[f]]

    def touched(self, f: int) -> bool:
        return any(v in self.locked for v in self.corners(f))

    def _normal(self, vertices) -> np.ndarray:
        a, b, c = (self.positions[v] for v in vertices)
        return np.cross(b - a, c - a)

    def _neighbours(self, v: int) -> set[int]:
        return {w for f in self.faces_of(v) for w in self.corners(f)} - {v}

    def _lock_around(self, vertices) -> None:
        for v in vertices:
            self.locked.add(v)
            self.locked.update(self._neighbours(v))

    def collapse_shortest(self, f: int, removable: np.ndarray) -> bool:
        ids = self.corners(f)
        edges = sorted(((ids[i], ids[(i + 1) % 3]) for i in range(3)),
                       key=lambda e: float(np.sum((self.positions[e[0]] - self.positions[e[1]]) ** 2)))
        return self._collapse_first(edges, removable)

    def _collapse_first(self, edges, removable: np.ndarray) -> bool:
        """Collapse the first of ``edges`` that can go, either way round."""
        for u, v in edges:
            if u == v:
                continue
            # remove a vertex the union made before one of the pieces'
            for gone, kept in sorted([(u, v), (v, u)], key=lambda e: not removable[e[0]]):
                if self._collapse(gone, kept):
                    return True
        return False

    def _collapse(self, gone: int, kept: int) -> bool:
        around_gone, around_kept = self.faces_of(gone), set(self.faces_of(kept))
        common = [g for g in around_gone if g in around_kept]
        if len(common) != 2:
            return False
        apexes = {w for g in common for w in self.corners(g)} - {gone, kept}
        if len(apexes) != 2 or (self._neighbours(gone) & self._neighbours(kept)) != apexes:
            return False  # the link condition: otherwise the collapse pinches the surface
        target = self.positions[kept]
        for g in around_gone:
            if g in common:
                continue
            ids = self.corners(g)
            before = self._normal(ids)
            after = self._normal([kept if v == gone else v for v in ids])
            if not np.any(before):
                continue  # already flat: collapsed later on, or made whole by this collapse
            if not np.any(after):
                return False  # the triangle would lose its area
            reference = np.cross(*(self.reference[self.faces[g][1:]] - self.reference[self.faces[g][0]]))
            if float(np.dot(before, after)) <= 0.0 or float(np.dot(reference, after)) <= 0.0:
                return False  # the triangle would turn over
        self._lock_around([gone, kept])
        members = self._members[self._member_starts[gone]:self._member_starts[gone + 1]]
        self.positions[members] = target
        self.vid[members] = kept
        self.alive[common] = False
        self.changed[around_gone] = True
        return True

    def collapse_nearby(self, f: int, removable: np.ndarray, tries: int = 16) -> bool:
        """The shortest edges of the triangles around f's corners, collapsed until one goes:
        a triangle that crosses another is often pushed there by a sliver beside it."""
        edges = {tuple(sorted((ids[i], ids[(i + 1) % 3])))
                 for g in {g for v in self.corners(f) for g in self.faces_of(v)}
                 for ids in [self.corners(g)] for i in range(3)}
        edges = sorted(edges, key=lambda e: float(np.sum((self.positions[e[0]] - self.positions[e[1]]) ** 2)))
        return self._collapse_first(edges[:tries], removable)

    def flip_longest(self, f: int) -> bool:
        ids = self.corners(f)
        i = max(range(3), key=lambda i: float(np.sum((self.positions[ids[i]] - self.positions[ids[(i + 1) % 3]]) ** 2)))
        a, b, c = ids[i], ids[(i + 1) % 3], ids[(i + 2) % 3]
        other = [g for g in self.faces_of(b) if g != f and a in self.corners(g)]
        if len(other) != 1:
            return False
        g = other[0]
        gi = self.corners(g)
        j = gi.index(b)
        if gi[(j + 1) % 3] != a:
            return False  # inconsistent orientation: not ours to fix
        d = gi[(j + 2) % 3]
        if c == d or d in self._neighbours(c):
            return False
        old = self._normal([a, b, c]) + self._normal([b, a, d])
        new1, new2 = self._normal([c, a, d]), self._normal([d, b, c])
        if float(np.dot(new1, old)) <= 0.0 or float(np.dot(new2, old)) <= 0.0:
            return False
        corner = {int(self.vid[x]): int(x) for x in self.faces[f]}
        corner_g = {int(self.vid[x]): int(x) for x in self.faces[g]}
        self._lock_around([a, b, c, d])
        self.faces[f] = [corner[c], corner[a], corner_g[d]]
        self.faces[g] = [corner_g[d], corner_g[b], corner[c]]
        self.changed[[f, g]] = True
        return True
