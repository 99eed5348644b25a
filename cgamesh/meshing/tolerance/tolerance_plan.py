"""Counts and ring placement for a tolerance, from a priori bounds: no trial meshes, no search.

The mesh of a surface family x(t, theta) (circles: x = c + r F(t) e(theta); ribbons:
x = a + s (b - a)) is its (t, theta) grid split into triangles. docs/tolerance.md proves that
over the quad between rings t_k and t_k+1 = t_k + h, columns theta_j and theta_j + k, every
point of both triangles lies within

    E = sag + A h^2 / 8 + B h k' / 4

of the true surface, where sag is the chord sag around (r (1 - cos(pi / M)) for circles, 0 for
straight rulings), A bounds |d^2 x / dt^2| and B |d^2 x / dt dtheta| over the quad (the twist
term) and k' the chord's length per unit of r (2 sin(pi / M)) or the fraction across (1 / (N - 1)).
A and B come from bounds of the members' derivatives per cell of a dense sampling
(cgamesh.meshing.tolerance.derivative_bounds): for circles |c''|, |r'|, |r''|, |n'|, |n''| and the
frame's angular velocity; for ribbons |a''|, |b''| and |(b - a)'|. For circles two more bounds
count only the twist's part across the surface: a reparametrisation of each triangle removes
its shear along P_t and P_theta (docs/tolerance.md, "The twist's normal part"), and the error
is projected on the surface's normal, its tangential part costing only the curvature over a
short step (cgamesh.meshing.tolerance.normal_projection): an interval's E is the smallest of the three.
For ribbons the bubble removes the twist's tangential part, or only the rulings' stretching
(cgamesh.meshing.tolerance.ribbon_twist): E is the smallest of the lemma's and those.

From these, per cell and for each candidate count around, the spacing h whose bound meets the
tolerance gives a ring density 1 / h; its integral per segment is the ring count, so the count
around (or across) minimising vertices is chosen without meshing anything (``plan_counts``,
cheap: usable by a resource budget before any mesh-sized allocation). Rings are then placed
equidistributing that density in one pass, segment joints always rings; intervals whose
bound (maxima over every cell they touch) still exceeds the tolerance have their density raised
and are placed again, and any left are split evenly. The plan's ``bound`` is the largest E over
its intervals: at most the tolerance, by construction. The bounds and spacings themselves, per
cell and per interval, are cgamesh.meshing.tolerance.quad_bounds'.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from cgamesh.errors import InvalidInputError
from cgamesh.geometry.objects import circle_euclidean
from cgamesh.geometry.surface import EvolvedSurface
from cgamesh.meshing.tolerance.dense_samples import DenseSamples, circle_members, pair_members, read_blades
from cgamesh.meshing.tolerance.derivative_bounds import segment_samples
from cgamesh.meshing.tolerance.quad_bounds import (Cells, circle_cells, circle_error, circle_spacing, holonomy,
                                                   ribbon_cells, ribbon_error, ribbon_spacing)

# Cells per segment of the derivative sampling: at least this many, and about this many per
# ring of a first estimate (the Lipschitz margin shrinks with the cells; the cost grows).
MIN_CELLS = 32
MAX_CELLS = 256
CELLS_PER_RING = 4
# Counts around / across tried when choosing the split of the tolerance.
AROUND_CANDIDATES = 48
MAX_ACROSS = 64
# Candidates priced in the first, coarse pass of the choice (every this many).
COARSE_STRIDE = 4
# Rounds of raising the density where an interval's bound misses, before splitting it.
DENSITY_ROUNDS = 4
# Rings are placed again with a lowered density when their intervals' bounds average below
# this share of the tolerance.
RELAX_BELOW = 0.85
# A closed loop's holonomy rate is bounded again at most this often, with this margin.
HOLONOMY_ROUNDS = 6
HOLONOMY_MARGIN = 1.05
# Refuse (InvalidInputError) rather than allocate beyond these; the budget's floor refuses earlier.
MAX_AROUND = 1 << 16
MAX_RINGS = 1 << 24


@dataclass(frozen=True)
class TolerancePlan:
    """around: vertices around each circle (the mesh adds a seam column) or across a ribbon;
    t: ring (ruling) parameters, increasing from 0 to the segment count; bound: the proven
    upper bound of the mesh's deviation from the surface over triangle interiors (file units)."""

    around: int
    t: np.ndarray
    bound: float

    @property
    def rings(self) -> int:
        return len(self.t)


@dataclass(frozen=True)
class PlannedCounts:
    """The counts a tolerance needs, known before placing rings: around (or across) and rings."""

    around: int
    rings: int


def _ring_counts(density: np.ndarray, cells: int) -> np.ndarray:
    """Intervals per segment (..., segments) for densities (..., segments, cells)."""
    with np.errstate(over="ignore", invalid="ignore"):
        integral = density.sum(axis=-1) / cells
        return np.maximum(1.0, np.ceil(integral * (1.0 + 1e-12)))


class _Surface:
    """What planning needs of one family: its cells' terms, error and spacing formulas."""

    def __init__(self, surface: EvolvedSurface, kind: str, closed: bool):
        self.surface, self.kind, self.closed = surface, kind, closed
        self._samples = DenseSamples(surface, circle_members if kind == "circles" else pair_members)

    def cells(self, count: int) -> Cells:
        members = self._samples.read(count)
        if self.kind == "circles":
            return circle_cells(self.surface, count, self.closed, members)
        return ribbon_cells(self.surface, count, members)

    def error(self, terms, h, around, rate, wide=None):
        if self.kind == "circles":
            return circle_error(terms, h, around, rate, wide)
        return ribbon_error(terms, h, around, rate)

    def spacing(self, terms, around, tolerance, rate):
        return (circle_spacing if self.kind == "circles" else ribbon_spacing)(terms, around, tolerance, rate)

    def candidates(self, cells: Cells, tolerance: float) -> np.ndarray:
        if self.kind != "circles":
            return np.arange(2, MAX_ACROSS + 1)
        largest = float(cells.terms["Rm"].max())
        # Fewest M whose sag r (1 - cos(pi / M)) is below the tolerance; acos(1 - x) written as
        # 2 asin(sqrt(x / 2)), which stays accurate for tiny x.
        half_angle = math.pi if tolerance >= largest else 2.0 * math.asin(math.sqrt(0.5 * tolerance / largest))
        if half_angle <= math.pi / MAX_AROUND:
            raise InvalidInputError(
                f"tolerance {tolerance:.3g} is too small for surface '{self.surface.name}': "
                f"it needs more than {MAX_AROUND} vertices around")
        smallest = max(3, math.ceil(math.pi / half_angle))
        # The sag takes part of the tolerance; the optimum lies where the rest is not too small.
        high = min(MAX_AROUND, 4 * smallest + 8)
        return np.unique(np.round(np.geomspace(smallest, high, AROUND_CANDIDATES)).astype(int))

    def columns(self, around: int) -> int:
        return around + 1 if self.kind == "circles" else around


def _choose_counts(family: _Surface, cells: Cells, tolerance: float) -> tuple[int, np.ndarray, np.ndarray]:
    """(around, density (segments, cells), intervals per segment) minimising planned vertices.

    The planned vertices against the count around fall, then rise (the sag's share of the
    tolerance against the rings'): every COARSE_STRIDE-th candidate is priced first, then every
    candidate between the best one's neighbours."""
    options = family.candidates(cells, tolerance)
    coarse = np.unique(np.append(np.arange(0, len(options), COARSE_STRIDE), len(options) - 1))
    best = coarse[_price(family, cells, tolerance, options[coarse])[0]]
    position = int(np.searchsorted(coarse, best))
    low, high = coarse[max(position - 1, 0)], coarse[min(position + 1, len(coarse) - 1)]
    fine = options[low:high + 1]
    chosen, density, counts = _price(family, cells, tolerance, fine)
    return int(fine[chosen]), density, counts


def _price(family: _Surface, cells: Cells, tolerance: float, options: np.ndarray):
    """(index of the option with the fewest planned vertices, its density, its counts)."""
    terms = {k: v[None] for k, v in cells.terms.items()}
    with np.errstate(divide="ignore"):
        density = 1.0 / family.spacing(terms, options[:, None, None], tolerance, cells.closed_rate)
    density = _neighbourhood_max(density)
    counts = _ring_counts(density, cells.cells)  # (options, segments)
    rings = counts.sum(axis=1) + 1.0
    vertices = rings * np.array([family.columns(int(m)) for m in options])
    best = int(np.argmin(np.where(np.isfinite(vertices), vertices, np.inf)))
    if not np.isfinite(vertices[best]) or rings[best] > MAX_RINGS:
        raise InvalidInputError(
            f"tolerance {tolerance:.3g} is too small for surface '{family.surface.name}': "
            f"it needs more than {MAX_RINGS} rings")
    return best, density[best], counts[best]


def _neighbourhood_max(density: np.ndarray) -> np.ndarray:
    """Each cell's density raised to its neighbours' within the segment (an interval spanning
    a cell boundary is bounded with both cells' maxima)."""
    padded = np.concatenate([density[..., :1], density, density[..., -1:]], axis=-1)
    return np.maximum(np.maximum(padded[..., :-2], padded[..., 1:-1]), padded[..., 2:])


def _place(density: np.ndarray, counts: np.ndarray, cells: int) -> np.ndarray:
    """Ring parameters equidistributing ``density`` (segments, cells): counts[s] intervals in
    segment s, its ends always rings."""
    segments = density.shape[0]
    density = density + 1e-9  # strictly increasing integrals, also where a segment is straight
    integral = np.concatenate([np.zeros((segments, 1)), np.cumsum(density, axis=1) / cells], axis=1)
    total = integral[:, -1]
    offset = np.concatenate([[0.0], np.cumsum(total)[:-1]])
    counts = counts.astype(np.int64)
    segment = np.repeat(np.arange(segments), counts)
    step = np.arange(len(segment)) - np.repeat(np.cumsum(counts) - counts, counts)
    level = offset[segment] + total[segment] * step / counts[segment]
    knots = (integral + offset[:, None]).ravel()
    t_knots = segment_samples(segments, cells).ravel()
    t = np.interp(level, knots, t_knots)
    t[step == 0] = segment[step == 0]  # joints exactly
    return np.append(t, float(segments))


class _RangeMax:
    """Maxima of per-cell arrays over ranges of cells (a sparse table: O(n log n) to build).

    Level j holds the maxima over 2^j cells from each cell on; a range is covered by two
    (overlapping) blocks of its level. The levels share one array (levels, cells, columns),
    so a query of any ranges is two gathers (entries past a level's end are never read)."""

    def __init__(self, columns: np.ndarray):
        count = len(columns)
        depth = max(1, count.bit_length())  # levels 0 .. floor(log2(count))
        self.levels = np.empty((depth,) + columns.shape)
        self.levels[0] = columns
        for j in range(1, depth):
            width, size = 1 << (j - 1), count - (1 << j) + 1  # level j's valid entries
            last = self.levels[j - 1]
            np.maximum(last[:size], last[width:width + size], out=self.levels[j, :size])

    def query(self, first: np.ndarray, last: np.ndarray) -> np.ndarray:
        level = np.floor(np.log2(last - first + 1)).astype(int)
        return np.maximum(self.levels[level, first], self.levels[level, last - (1 << level) + 1])


def _interval_errors(family: _Surface, cells: Cells, table: _RangeMax, names, t: np.ndarray, around: int):
    """The bound E of every interval [t_k, t_k+1] (K-1,), with the maxima over every cell it touches,
    and the first and last cell indices."""
    first, last = _touched(cells, t)
    if family.kind == "circles":  # the widened maxima too, in the same query
        wide_first, wide_last, margin = _widened_range(cells, t)
        maxima = table.query(np.concatenate([first, wide_first]), np.concatenate([last, wide_last]))
        terms, wide = _named(names, maxima[:len(first)]), _named(names, maxima[len(first):])
        wide["margin"] = margin
    else:
        terms, wide = _named(names, table.query(first, last)), None
    return family.error(terms, t[1:] - t[:-1], around, cells.closed_rate, wide), first, last, terms


def _named(names, maxima: np.ndarray) -> dict:
    return {name: maxima[:, i] for i, name in enumerate(names)}


def _touched(cells: Cells, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The first and last cell each interval [t_k, t_k+1] touches (np.minimum and np.maximum
    rather than np.clip: the same integers, at less overhead on the few intervals of a plan)."""
    n = cells.segments * cells.cells
    first = np.minimum(np.maximum(np.floor(t[:-1] * cells.cells).astype(np.int64), 0), n - 1)
    last = np.minimum(np.maximum(np.ceil(t[1:] * cells.cells).astype(np.int64) - 1, first), n - 1)
    return first, last


def _widened(cells: Cells, table: _RangeMax, names, t: np.ndarray) -> dict:
    """Per interval the term maxima over it widened by ``margin`` = min(h, its distance to its
    segment's ends) on each side: where the normal projection's step along t may reach (never
    across a joint, where the members are not twice differentiable)."""
    first, last, margin = _widened_range(cells, t)
    wide = _named(names, table.query(first, last))
    wide["margin"] = margin
    return wide


def _widened_range(cells: Cells, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(first cell, last cell, margin) of each interval widened as ``_widened`` says."""
    segment = np.minimum(np.maximum(np.floor(t[:-1]), 0), cells.segments - 1)
    margin = np.maximum(np.minimum(np.minimum(t[1:] - t[:-1], t[:-1] - segment), segment + 1.0 - t[1:]), 0.0)
    low, high = segment * cells.cells, (segment + 1) * cells.cells - 1
    first = np.minimum(np.maximum(np.floor((t[:-1] - margin) * cells.cells), low), high).astype(np.int64)
    last = np.minimum(np.maximum(np.ceil((t[1:] + margin) * cells.cells) - 1, first), high).astype(np.int64)
    return first, last, margin


class _IntervalErrors:
    """``_interval_errors`` of one placement (its family, term table and count around), remembered
    for the last few ring sets: placing asks it of the same rings up to three times in a row (the
    last round of raising, the first of splitting, the test for relaxing). The arrays returned
    are shared: read only."""

    KEEP = 4

    def __init__(self, family: _Surface, table: _RangeMax, names, around: int):
        self.family, self.table, self.names, self.around = family, table, names, around
        self._known: dict = {}

    def __call__(self, cells: Cells, t: np.ndarray):
        key = (t.tobytes(), cells.cells, cells.closed_rate)
        if key not in self._known:
            if len(self._known) >= self.KEEP:
                self._known.pop(next(iter(self._known)))
            self._known[key] = _interval_errors(self.family, cells, self.table, self.names, t, self.around)
        return self._known[key]


def _plan(family: _Surface, tolerance: float) -> tuple[Cells, int, np.ndarray, np.ndarray]:
    """The sampled cells, the count around and the per-cell density and counts for ``tolerance``."""
    if not (math.isfinite(tolerance) and tolerance > 0.0):
        raise InvalidInputError(f"tolerance must be a finite number > 0, got {tolerance!r}")
    cells = family.cells(MIN_CELLS)
    around, density, counts = _choose_counts(family, cells, tolerance)
    wanted = int(min(MAX_CELLS, max(MIN_CELLS, CELLS_PER_RING * counts.max())))
    wanted = 1 << max(0, (wanted - 1).bit_length())  # a power of two: few distinct samplings
    if wanted > cells.cells:
        cells = family.cells(min(MAX_CELLS, wanted))
        around, density, counts = _choose_counts(family, cells, tolerance)
    return cells, around, density, counts


class PreparedPlan:
    """A tolerance's counts, chosen from the sampled bounds, before any ring is placed.

    ``counts`` is what a resource budget prices (nothing mesh-sized is allocated yet); ``place()``
    then places the rings from the same cells, so a run that is priced is planned once."""

    def __init__(self, surface: EvolvedSurface, tolerance: float, kind: str = "circles", closed: bool = False):
        self.surface, self.tolerance, self.kind, self.closed = surface, tolerance, kind, closed
        self._family = _Surface(surface, kind, closed)
        self._cells, self._around, self._density, self._counts = _plan(self._family, tolerance)
        self._placed: TolerancePlan | None = None

    @property
    def counts(self) -> PlannedCounts:
        return PlannedCounts(self._around, int(self._counts.sum()) + 1)

    def place(self) -> TolerancePlan:
        if self._placed is None:
            self._placed = _place_rings(self._family, self._cells, self._around, self._density, self._counts,
                                        self.tolerance)
        return self._placed


def plan_counts(surface: EvolvedSurface, tolerance: float, kind: str = "circles", closed: bool = False) -> PlannedCounts:
    """The counts around (across) and along that ``plan_tolerance`` would choose, before placing
    any ring: reads the surface at a few hundred parameters and allocates nothing mesh-sized.
    (The final ring count can exceed this estimate by the few rings the placement adds where an
    interval's bound misses.) Vertices scale about as 1 / tolerance."""
    return PreparedPlan(surface, tolerance, kind, closed).counts


def plan_tolerance(surface: EvolvedSurface, tolerance: float, kind: str = "circles", closed: bool = False) -> TolerancePlan:
    """Counts and ring parameters for a mesh within ``tolerance`` of the surface (file units).

    kind: "circles" or "point_pairs". Raises InvalidInputError for a tolerance that is not a
    positive finite number or would need more than MAX_AROUND around or MAX_RINGS rings.
    """
    return PreparedPlan(surface, tolerance, kind, closed).place()


def _place_rings(family: _Surface, cells: Cells, around: int, density: np.ndarray, counts: np.ndarray,
                 tolerance: float) -> TolerancePlan:
    """Rings equidistributing ``density``, raised where an interval's bound misses (see the module doc)."""
    surface, kind, closed = family.surface, family.kind, family.closed
    names = sorted(cells.terms)
    errors = _IntervalErrors(family, _RangeMax(np.stack([cells.terms[name].ravel() for name in names], axis=1)),
                             names, around)
    t, density = _raised(errors, cells, density, counts, tolerance)
    t, bound = _split_missed(errors, cells, t, tolerance)
    error, first, last, _ = errors(cells, t)
    if np.mean(error) < RELAX_BELOW * tolerance:
        # The leading-term spacing was pessimistic here (most intervals' bound is well below the
        # tolerance): lower the density over each cell as its intervals' bounds allow (E grows
        # about as h^2), place again, and keep whichever placement has fewer rings.
        factor = np.zeros(density.size)
        lengths = last - first + 1
        touched = np.repeat(first - np.cumsum(lengths) + lengths, lengths) + np.arange(lengths.sum())
        np.maximum.at(factor, touched, np.repeat(np.sqrt(np.clip(error / tolerance, 1.0 / 16.0, 1.0)), lengths))
        lowered = density * np.where(factor > 0.0, factor, 1.0).reshape(density.shape)
        relaxed, _ = _raised(errors, cells, lowered, _ring_counts(lowered, cells.cells), tolerance)
        relaxed, relaxed_bound = _split_missed(errors, cells, relaxed, tolerance)
        if len(relaxed) < len(t):
            t, bound = relaxed, relaxed_bound
    if kind == "circles" and closed:
        # The loop's frames are turned by the holonomy of these rings' transport, spread evenly:
        # bound again with its rate until the rate assumed covers it.
        for _ in range(HOLONOMY_ROUNDS):
            _, normal, _ = circle_euclidean(read_blades(surface, t))
            rate = holonomy(normal, t) / surface.segment_count
            if rate <= cells.closed_rate:
                break
            cells = replace(cells, closed_rate=rate * HOLONOMY_MARGIN)
            t, bound = _split_missed(errors, cells, t, tolerance)
        else:
            raise InvalidInputError(f"surface '{surface.name}': the closed loop's frame holonomy does not settle")
    return TolerancePlan(around, t, bound)


def _raised(errors, cells, density, counts, tolerance):
    """(rings equidistributing ``density``, the density): raised over the cells of the intervals
    whose bound misses, as their error needs, and placed again (at most DENSITY_ROUNDS times)."""
    t = None
    for _ in range(DENSITY_ROUNDS):
        t = _place(density, counts, cells.cells)
        error, first, last, _ = errors(cells, t)
        missed = error > tolerance
        if not np.any(missed):
            break
        factor = np.ones(density.size)
        raise_by = np.sqrt(np.minimum(error[missed] / tolerance, 4.0)) * 1.02
        lengths = last[missed] - first[missed] + 1
        touched = np.repeat(first[missed] - np.cumsum(lengths) + lengths, lengths) + np.arange(lengths.sum())
        np.maximum.at(factor, touched, np.repeat(raise_by, lengths))
        density = density * factor.reshape(density.shape)
        counts = _ring_counts(density, cells.cells)
        if counts.sum() + 1 > MAX_RINGS:
            break
    return t, density


def _split_missed(errors, cells, t, tolerance):
    """Split each interval whose bound misses into as many equal parts as its maxima need."""
    family, around = errors.family, errors.around
    for _ in range(64):
        error, _, _, terms = errors(cells, t)
        missed = np.flatnonzero(error > tolerance)
        if missed.size == 0:
            return t, float(error.max())
        h = np.diff(t)[missed]
        picked = {name: value[missed] for name, value in terms.items()}
        spacing = family.spacing(picked, around, tolerance, cells.closed_rate)
        with np.errstate(divide="ignore", invalid="ignore"):
            parts = np.where(spacing > 0.0, np.ceil(h / spacing), np.inf)
        parts = np.maximum(parts, 2.0)
        if not np.all(np.isfinite(parts)) or len(t) + parts.sum() > MAX_RINGS:
            raise InvalidInputError(
                f"tolerance {tolerance:.3g} is too small for surface '{family.surface.name}': "
                f"it needs more than {MAX_RINGS} rings")
        # parts[i] - 1 new rings inside interval missed[i], evenly spaced: one array, no loop.
        extra = (parts - 1.0).astype(np.int64)
        owner = np.repeat(np.arange(len(missed)), extra)
        step = np.arange(extra.sum()) - np.repeat(np.cumsum(extra) - extra, extra) + 1
        inserted = t[missed][owner] + h[owner] * step / parts[owner]
        t = np.sort(np.concatenate([t, inserted]))
    raise InvalidInputError(f"tolerance {tolerance:.3g}: no ring placement meets it for surface "
                            f"'{family.surface.name}'")
