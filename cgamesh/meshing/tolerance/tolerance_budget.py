"""What a tolerance run will cost, estimated a priori, and the floor under a tolerance.

Priced before ``tessellation`` starts, so that a tolerance far below the surface's size is
refused in one line instead of growing until memory runs out (cgamesh.budget).

- Floor: a tolerance below TOLERANCE_FLOOR times the surface's bounding radius (the radius of
  the ball its controls' circles or end points fit in), or below FLOAT_SPACING_FACTOR float64
  spacings of its coordinates, asks for more than float64 vertices can show; it is refused.
- Size: the counts around (across) and along come from the tolerance's own a priori plan
  (``tolerance_plan.PreparedPlan``: the bounds that will place the rings, read at a few
  hundred parameters, nothing mesh-sized), so the price is that of the mesh the run will make,
  with RINGS_MARGIN for the few rings the placement adds where an interval's bound misses.
  The prepared plan is kept with the price and places the rings when the run meshes: the
  surface is planned once.
- Memory: that mesh's keeping and meshing peak (cgamesh.budget.surface_bytes) plus the plan's
  own tables (RUN_OVERHEAD).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from cgamesh import budget as costs
from cgamesh.geometry.surface import EvolvedSurface

TOLERANCE_FLOOR = 1e-7  # of the surface's bounding radius
FLOAT_SPACING_FACTOR = 64  # float64 spacings (of the largest coordinate) a tolerance must exceed
RINGS_MARGIN = 1.25  # rings the placement may add over the planned count, at most (measured: a few %)
RUN_OVERHEAD = 8 * 2**20  # per run, whatever its size: the plan's cells and tables
# A refusal names a tolerance this much above the one whose price scales to the limit exactly.
FIT_MARGIN = 1.25


@dataclass(frozen=True)
class ToleranceCost:
    around: int  # vertices around (or across) each ring
    along: int  # rings (rulings), estimated
    bytes: int  # peak memory, estimated
    plan: object = field(default=None, compare=False, repr=False)  # the PreparedPlan priced

    @property
    def vertices(self) -> int:
        return (self.around + 1) * self.along


def size_of(surface: EvolvedSurface) -> tuple[float, float]:
    """(bounding radius, largest coordinate magnitude) of the surface's controls, file units."""
    radius = float(surface.frame.scale)
    return radius, float(np.max(np.abs(surface.frame.origin))) + radius


def tolerance_floor(surface: EvolvedSurface) -> float:
    """The least tolerance this surface can be meshed to (see the module doc)."""
    radius, extent = size_of(surface)
    return max(TOLERANCE_FLOOR * radius, FLOAT_SPACING_FACTOR * float(np.spacing(extent)))


def estimate(surface: EvolvedSurface, tolerance: float, closed: bool = False) -> ToleranceCost:
    """The a priori size and memory of meshing ``surface`` to ``tolerance`` (see the module doc)."""
    from cgamesh.meshing.tolerance.tolerance_plan import PreparedPlan

    kind = "circles" if surface.grade == 3 else "point_pairs"
    prepared = PreparedPlan(surface, tolerance, kind, closed)
    counts = prepared.counts
    along = max(2, math.ceil(counts.rings * RINGS_MARGIN))
    _, peak = costs.surface_bytes(kind, counts.around, along)
    return ToleranceCost(counts.around, along, peak + RUN_OVERHEAD, prepared)


def fitting_tolerance(tolerance: float, needed: float, limit: float, fixed: float = RUN_OVERHEAD) -> float | None:
    """About the smallest tolerance whose run fits ``limit`` bytes, from ``tolerance`` whose run
    needs ``needed``: the bytes beyond ``fixed`` scale with the vertices, which grow about as
    1 / tolerance (the count around and the rings each as 1 / sqrt(tolerance)); FIT_MARGIN over
    that. None when not even the fixed part fits."""
    if limit <= fixed or needed <= fixed:
        return None
    return tolerance * (needed - fixed) / (limit - fixed) * FIT_MARGIN


def fitting_advice(tolerance: float, needed: float):
    """The advice a refusal of a tolerance run needing ``needed`` bytes gives for a limit
    (cgamesh.budget.Budget.require): about the tolerance that would fit, or None."""

    def advice(limit):
        fitting = fitting_tolerance(tolerance, needed, limit)
        return None if fitting is None else f"a tolerance of about {fitting:.2g} would fit"

    return advice
