"""Meshing to a tolerance: counts and ring placement from a priori bounds (docs/tolerance.md).

A tolerance is the largest distance the mesh may stray from the true surface over triangle
interiors. It is priced before anything mesh-sized is made, planned from bounds of the
surface's derivatives, and the mesh is then made once by the ordinary mesher on the planned
rings; nothing is measured on the way. Internal: the pipelines call ``tessellation`` and
``tolerance_budget``; the public face is ``cgamesh.api``.

    tessellation.py       the entry points: a circle surface or a ribbon meshed to a tolerance
    tolerance_budget.py   the floor under a tolerance, its a priori price, the tolerance that fits
    tolerance_plan.py     the counts around / across and the ring placement (PreparedPlan)
    quad_bounds.py        the bound of a quad per interval of rings, and the spacing meeting it
    derivative_bounds.py  bounds of a curve's derivatives over each cell of a dense sampling
    dense_samples.py      the surface read at the plan's samplings, each parameter once
    normal_projection.py  a circle quad's bound counting only the error normal to the surface
    ribbon_twist.py       a ribbon quad's bound without the tangential part of its twist
    deviation.py          the measure of a grid mesh's distance to the surface (tests, benchmarks)
"""
