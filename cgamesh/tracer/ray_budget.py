"""What tracing costs per ray, for the resource budget (cgamesh.budget): rays are traced in
chunks sized to fit it, and requests that cannot fit even one ray are refused.

The polynomial root finder solves, per ray and segment, a polynomial whose degree is at most
12 d for circles and 6 d for point pairs (d: the interpolant's degree, roots.py), through the
eigenvalues of its colleague matrix: about 16 degree^2 bytes per ray (the matrices and
LAPACK's copies) and degree^3 work. Past MAX_POLYNOMIAL_DEGREE that work is refused (a
50-control Bezier tube would solve degree-588 polynomials: hours for one mesh); the sampled
finder, whose cost is linear in the samples, traces any order. The sampled finder keeps its
samples' meet matrices per segment (10 x 5 floats each) and evaluates at most SAMPLED_CHUNK
values at once.
"""

from __future__ import annotations

from cgamesh.budget import Budget, ResourceLimitError
from cgamesh.tracer.roots import MOTOR_PROXY_DEGREE, SAMPLED_CHUNK, interpolant_degree

MAX_POLYNOMIAL_DEGREE = 240  # Bezier tubes of up to 21 controls, ribbons of up to 41
RAY_STATE = 16 * 2**10  # bytes per ray of everything else: rays, hits, shading, shadow rays
PIXEL_BYTES = 3 * 8 * 2  # a band's float RGB and its clipped copy


def polynomial_degree(surface) -> int:
    """An upper bound on the degree of the intersection polynomial of a traced surface (a motor
    surface's is the fixed degree of its Chebyshev proxy, roots.py)."""
    if surface.surface.interpolation == "motor":
        return MOTOR_PROXY_DEGREE
    return (12 if surface.grade == 3 else 6) * interpolant_degree(surface.surface.curve)


def check_surfaces(surfaces, budget: Budget) -> None:
    """Refuse surfaces whose tracing cannot fit the budget or the work limit (see the module doc)."""
    for surface in surfaces:
        finder = surface.finder
        if finder.kind == "polynomial":
            degree = polynomial_degree(surface)
            if degree > MAX_POLYNOMIAL_DEGREE:
                raise ResourceLimitError(
                    f"surface '{surface.name}': the polynomial root finder would solve polynomials of degree "
                    f"{degree} per ray; "
                    f"the most it solves is {MAX_POLYNOMIAL_DEGREE}: use --root-finder sampled")
        else:
            objects = finder.samples + 1
            fixed = surface.surface.segment_count * objects * 10 * 5 * 8 + max(SAMPLED_CHUNK, objects) * 5 * 8 * 4
            budget.require(fixed, f"--samples {finder.samples} on surface '{surface.name}'", "sampled objects")


def ray_bytes(surfaces) -> int:
    """Bytes one ray needs while it is traced, at most, over these surfaces."""
    most = 0
    for surface in surfaces:
        if surface.finder.kind == "polynomial":
            degree = polynomial_degree(surface)
            most = max(most, 16 * degree * degree + 256 * degree)
    return RAY_STATE + most


def rays_at_once(surfaces, budget: Budget, where: str, most: int) -> int:
    """How many rays to trace at once within the budget (refusing when one ray does not fit)."""
    check_surfaces(surfaces, budget)
    return budget.items(ray_bytes(surfaces), where, "ray-tracing state per ray", most)


__all__ = ["ResourceLimitError", "check_surfaces", "ray_bytes", "rays_at_once"]
