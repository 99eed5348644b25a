"""Centreline inputs meshed to a tolerance: every chain planned, the whole run priced, then meshed.

Each chain's tube is planned by the tolerance's a priori bound (cgamesh.meshing.tolerance.tolerance_plan)
before any mesh is made, and priced as it is planned (``TolerancePrice``, the spheres' vertices
counted first): the merged mesh, the largest meshing transient and the largest export against
the memory budget, refused as soon as the spheres and the chains so far exceed it, with about
the tolerance that would fit. The junction and soma spheres get the fewest vertices around that
keep them within the tolerance (cgamesh.pipelines.spheres.spheres_around,
cgamesh.meshing.junctions.deviation_bound; docs/tolerance.md, "Junction and soma spheres").
Then the chains are meshed from their plans, each plan let go once its mesh is made.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cgamesh.errors import CgameshError, InvalidInputError
from cgamesh.inputs.centerlines import Centerlines
from cgamesh.pipelines.chains import Chain, take_chain
from cgamesh.pipelines.spheres import sphere_groups
from cgamesh.pipelines.tube_options import TubeOptions
from cgamesh.pipelines.tubes import TubeSpec, finish_tube, tube_spec


@dataclass
class PlannedTube:
    """A chain planned under a tolerance: its tube and the plan priced (SurfacePlan)."""

    chain: Chain
    index: int
    tube: TubeSpec
    plan: object


def plan_tubes(chains, points, radii, soma, tangents, segment_of, lines, options, stem, skipped,
               progress, price: "TolerancePrice") -> list[PlannedTube]:
    """Every chain's tube planned to the tolerance (counts chosen, nothing mesh-sized made), in
    chain order, each priced as it is planned (``price`` refuses as soon as the run cannot fit);
    a chain that cannot be planned is skipped (``skipped``), or raises when strict."""
    from cgamesh.pipelines.scene import Resolution, plan_surface

    planned = []
    done = np.cumsum(chains.counts)  # nodes planned after each chain
    for index, chain in enumerate(chains):
        try:
            tube = tube_spec(chain, index, points, radii, soma, tangents, segment_of, lines, options, stem)
            if tube is not None:
                planned.append(PlannedTube(chain, index, tube, plan_surface(tube.request, Resolution(), surface=tube.surface)))
        except CgameshError as error:
            if options.strict:
                raise
            skipped.append(str(error))
            tube = None
        if tube is not None:
            price.add(planned[-1].plan, share=float(done[index] / done[-1]))
        progress(chain.label)
    return planned


class TolerancePrice:
    """What a tolerance run of centrelines will hold and allocate, summed as its chains are
    planned: the merged mesh's bytes, the largest meshing transient of one tube and the largest
    export of ``outputs``; refused (ResourceLimitError) as soon as it exceeds the budget, with
    about the tolerance that would fit (cgamesh.meshing.tolerance.tolerance_budget.fitting_tolerance)."""

    def __init__(self, lines: Centerlines, tolerance: float, max_memory, outputs: Sequence[str],
                 sphere_vertices: int):
        from cgamesh import budget as costs

        self.budget = costs.Budget.of(max_memory)
        self.where = f"{lines.source} with tolerance {tolerance:g}"
        self.tolerance = tolerance
        self.suffixes = costs.output_suffixes(outputs)
        self.spheres = sphere_vertices
        self.vertices = self.tubes = 0
        self.transient = 0
        if not self.budget.allows(self.needed(0)):  # the spheres alone: refused before any tube is planned
            self._refuse(self.needed(0), f"junction and soma spheres meshed to it (about {sphere_vertices} vertices)")

    def needed(self, vertices: int) -> int:
        """Bytes of a run of ``vertices`` tube vertices and the spheres."""
        from cgamesh import budget as costs

        vertices += self.spheres
        return costs.HELD_PER_VERTEX * vertices + max(self.transient, costs.export_bytes(self.suffixes, vertices))

    def add(self, plan, share: float) -> None:
        """One more tube planned; ``share``: the fraction of the input's nodes planned so far."""
        self.vertices += plan.vertices
        self.tubes += 1
        self.transient = max(self.transient, plan.peak - plan.held)
        if not self.budget.allows(self.needed(self.vertices)):
            whole = int(self.vertices / max(share, 1e-12))  # the rest like the chains so far
            self._refuse(self.needed(whole), f"tubes and spheres meshed to it (about {whole + self.spheres} "
                                             f"vertices, extrapolated from the first {self.tubes} tubes planned)")

    def finish(self) -> None:
        """The whole run, every tube planned."""
        self._refuse(self.needed(self.vertices), f"tubes and spheres meshed to it ({self.tubes} tubes, about "
                                                 f"{self.vertices + self.spheres} vertices)")

    def _refuse(self, needed: int, what: str) -> None:
        from cgamesh.meshing.tolerance.tolerance_budget import fitting_advice

        self.budget.require(needed, self.where, what, fitting_advice(self.tolerance, needed))


def mesh_planned_tubes(planned: list[PlannedTube], scalar, options, stem, skipped, progress, sink) -> None:
    """Mesh the planned tubes in order into ``sink``, each plan let go once its mesh is made."""
    from cgamesh.pipelines.scene import mesh_planned

    for k, item in enumerate(planned):
        planned[k] = None  # the plan's cells go with it
        take_chain(lambda: finish_tube(item.tube, mesh_planned(item.plan, False), item.chain, item.index, scalar,
                                       options, stem), options, skipped, sink)
        progress(item.chain.label)


def planned_size(planned: list[PlannedTube], options: TubeOptions) -> tuple[int, int]:
    """Vertices and triangles of the planned tubes, at most: each plan's estimate (with the
    placement's margin, tolerance_budget.estimate) and its caps; a grid has fewer triangles than
    twice its vertices."""
    vertices = sum(item.plan.vertices for item in planned)
    if options.caps:
        vertices += sum(2 * (_around(item.plan) + 2) for item in planned)
    return vertices, 2 * vertices


def _around(plan) -> int:
    """A plan's count around: its tolerance's, or its fixed resolution's."""
    return plan.prepared.counts.around if plan.prepared is not None else plan.around


def sphere_size(lines: Centerlines, radii, junctions, soma, options: TubeOptions) -> tuple[int, int]:
    """Vertices and triangles of the junction and soma spheres at their counts around for the
    tolerance; a located InvalidInputError when a sphere cannot be meshed to it."""
    from cgamesh.meshing.junctions import sphere_bands

    vertices = triangles = 0
    try:
        for _, _, _, around in sphere_groups(junctions, soma, radii, options):
            spheres = np.bincount(around)
            counts = np.flatnonzero(spheres)  # the counts present (np.unique imports numpy.ma)
            bands = np.array([sphere_bands(int(m)) for m in counts])
            vertices += int(((counts + 1) * (bands + 1) * spheres[counts]).sum())
            triangles += int((2 * counts * (bands - 1) * spheres[counts]).sum())
    except InvalidInputError as error:
        raise InvalidInputError(f"{lines.source}: {error}") from None
    return vertices, triangles
