"""The a priori tolerance bound (cgamesh.meshing.tolerance.tolerance_plan) is never exceeded.

Property tests over random tubes and ribbons (every curve kind, sizes and positions at the
extremes' ranges of tests/test_extremes.py): the plan's bound is at most the tolerance, and the
deviation measured by cgamesh.meshing.tolerance.deviation on the mesh made on the plan's rings is at most
the bound. Also: the derivative bounds cover analytic derivatives; impossible tolerances are
refused with an InvalidInputError, quickly; the planned counts are those the plan uses.
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from cgamesh.errors import InvalidInputError
from cgamesh.inputs.scene import Location, PointPairControl, SurfaceSpec
from cgamesh.material import Material
from cgamesh.meshing.circles import mesh_circle_surface
from cgamesh.meshing.tolerance.derivative_bounds import cell_bounds, segment_samples
from cgamesh.meshing.tolerance.deviation import CIRCLES, SEGMENTS, grid_deviation
from cgamesh.meshing.ribbons import mesh_ribbon_surface
from cgamesh.meshing.tolerance.tolerance_plan import plan_counts, plan_tolerance
from cgamesh.pipelines.scene import build_surface
from test_extremes import spec_of, tube

HERE = Location("bound.yaml", 1, "surfaces[0]")
PROPERTIES = settings(max_examples=12, suppress_health_check=[HealthCheck.too_slow], deadline=None)
CURVES = ["linear", "bezier", "kb", "catmull_rom", "rational_bezier"]


def measured(surface, plan, kind: str) -> float:
    """cgamesh.meshing.tolerance.deviation's figure for the mesh on the plan's rings."""
    if kind == "point_pairs":
        mesh = mesh_ribbon_surface(surface, plan.around, t=plan.t)
        return grid_deviation(surface, plan.t, mesh.positions.reshape(plan.rings, plan.around, 3), SEGMENTS).max
    mesh = mesh_circle_surface(surface, plan.around, t=plan.t)
    grid = mesh.positions.reshape(plan.rings, plan.around + 1, 3)
    return grid_deviation(surface, plan.t, grid, CIRCLES).max


def placed_terms(surface, tolerance: float, kind: str, closed: bool = False):
    """(plan, cells, table, names, error, terms) of the plan placed for ``tolerance``: each
    interval's bound and its terms, as the plan prices them (tolerance_plan's private tables)."""
    from cgamesh.meshing.tolerance import tolerance_plan

    prepared = tolerance_plan.PreparedPlan(surface, tolerance, kind, closed)
    plan = prepared.place()
    cells = prepared._cells
    names = sorted(cells.terms)
    table = tolerance_plan._RangeMax(np.stack([cells.terms[name].ravel() for name in names], axis=1))
    error, _, _, terms = tolerance_plan._interval_errors(prepared._family, cells, table, names, plan.t, plan.around)
    return plan, cells, table, names, error, terms


def ribbon_spec(a, b, curve: str, weights=None) -> SurfaceSpec:
    weights = [1.0] * len(a) if weights is None else weights
    controls = tuple(PointPairControl(tuple(map(float, p)), tuple(map(float, q)), float(w), HERE)
                     for p, q, w in zip(a, b, weights))
    return SurfaceSpec("ribbon", "point_pairs", curve, 0.0, 0.0, 0.0, False, True, controls, 2, 16, None,
                       False, Material(), HERE)


@PROPERTIES
@given(log_scale=st.floats(-4.0, 4.0), distance=st.floats(0.0, 1e5), curve=st.sampled_from(CURVES),
       count=st.integers(2, 5), log_relative=st.floats(-3.0, -1.0), seed=st.integers(0, 2**32 - 1))
def test_tube_bound_is_never_exceeded(log_scale, distance, curve, count, log_relative, seed):
    rng = np.random.default_rng(seed)
    offset = distance * rng.normal(size=3) / np.sqrt(3.0)
    centres, normals, radii = tube(10.0**log_scale, offset, count if curve != "catmull_rom" else max(count, 3), rng)
    weights = list(10.0 ** rng.uniform(-1.0, 1.0, size=len(radii))) if curve == "rational_bezier" else None
    surface = build_surface(spec_of(centres, normals, radii, curve=curve, weights=weights))
    tolerance = 10.0**log_relative * surface.frame.scale
    plan = plan_tolerance(surface, tolerance, "circles")
    assert plan.bound <= tolerance
    assert measured(surface, plan, "circles") <= plan.bound


@PROPERTIES
@given(log_scale=st.floats(-4.0, 4.0), distance=st.floats(0.0, 1e5), curve=st.sampled_from(CURVES),
       count=st.integers(2, 5), twist=st.floats(0.0, 2.5), flat=st.booleans(), log_relative=st.floats(-3.0, -1.0),
       seed=st.integers(0, 2**32 - 1))
def test_ribbon_bound_is_never_exceeded(log_scale, distance, curve, count, twist, flat, log_relative, seed):
    surface = random_ribbon(log_scale, distance, curve, count, twist, flat, seed)
    tolerance = 10.0**log_relative * surface.frame.scale
    plan = plan_tolerance(surface, tolerance, "point_pairs")
    assert plan.bound <= tolerance
    assert measured(surface, plan, "point_pairs") <= plan.bound


def random_ribbon(log_scale, distance, curve, count, twist, flat, seed):
    """A random ribbon of size 10^log_scale at ``distance`` from the origin whose rulings turn by
    about ``twist`` radians; ``flat``: its controls in one plane (the plane z = offset's), so that
    its twist, its rulings' turning and stretching, is tangent to it."""
    rng = np.random.default_rng(seed)
    count = max(count, 3) if curve == "catmull_rom" else count
    scale = 10.0**log_scale
    offset = distance * rng.normal(size=3) / np.sqrt(3.0)
    angle = twist * np.arange(count) / max(count - 1, 1) + 0.2 * rng.normal(size=count)
    height = np.cumsum(rng.uniform(0.5, 1.5, size=count)) * scale
    half = scale * rng.uniform(0.5, 1.5, size=count)
    if flat:  # along x, the rulings across it turning by at most about 0.75 + 0.06 radians
        middle = offset + np.stack([height, 0.5 * scale * rng.normal(size=count), np.zeros(count)], 1)
        across = np.stack([-np.sin(0.3 * angle), np.cos(0.3 * angle), np.zeros(count)], axis=1) * half[:, None]
    else:
        middle = offset + np.stack([0.2 * scale * rng.normal(size=count), 0.2 * scale * rng.normal(size=count),
                                    height], 1)
        across = np.stack([np.cos(angle), np.sin(angle), np.zeros(count)], axis=1) * half[:, None]
    weights = list(10.0 ** rng.uniform(-1.0, 1.0, size=count)) if curve == "rational_bezier" else None
    return build_surface(ribbon_spec(middle - across, middle + across, curve, weights))


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(log_scale=st.floats(-4.0, 4.0), distance=st.floats(0.0, 1e5), curve=st.sampled_from(CURVES),
       count=st.integers(2, 4), twist=st.floats(0.0, 2.5), flat=st.booleans(), log_relative=st.floats(-3.0, -1.5),
       seed=st.integers(0, 2**32 - 1))
def test_the_ribbon_twist_bound_covers_every_interval_alone(log_scale, distance, curve, count, twist, flat,
                                                           log_relative, seed):
    """The ribbon bound without the twist's tangential part (cgamesh.meshing.tolerance.ribbon_twist), taken
    alone, is at least each interval's measured deviation wherever it applies, on random flat
    and twisted ribbons (the plan's bound is the smaller of two, so the end-to-end tests would
    not notice one that fails), and the plan's bound is that minimum."""
    from cgamesh.meshing.tolerance.ribbon_twist import ribbon_twist_error

    surface = random_ribbon(log_scale, distance, curve, count, twist, flat, seed)
    plan, _, _, _, error, terms = placed_terms(surface, 10.0**log_relative * surface.frame.scale, "point_pairs")
    h = np.diff(plan.t)
    bubble = ribbon_twist_error(terms, h, plan.around)
    whole = terms["A"] * h * h / 8.0 + terms["B"] * h / (4.0 * (plan.around - 1))
    assert np.all(error == np.minimum(whole, bubble))
    grid = mesh_ribbon_surface(surface, plan.around, t=plan.t).positions.reshape(plan.rings, plan.around, 3)
    applies = np.flatnonzero(np.isfinite(bubble))
    assume(applies.size > 0)
    for k in applies:  # one interval at a time: its own measured deviation against its own bound
        assert grid_deviation(surface, plan.t[k:k + 2], grid[k:k + 2], SEGMENTS).max <= bubble[k], k


def test_a_flat_ribbons_twist_is_tangent():
    """Fig. 12's linear chords lie in one plane: the normal part of their twist bounded per cell
    is a small fraction of the whole twist (it is zero but for the cells' margins), and the bound
    without the tangential part is the smaller one on most intervals at 1e-4 (83% of them, with 11
    across: enough for the bubble's shift, kappa |gamma_t|, to be small)."""
    from cgamesh.inputs.scene import load_scene
    from cgamesh.meshing.tolerance.ribbon_twist import ribbon_twist_error

    spec = load_scene("examples/fig12_cocircular_chords.yaml").surfaces[0]
    surface = build_surface(spec)
    plan, cells, _, _, _, terms = placed_terms(surface, 1e-4 * surface.frame.scale, "point_pairs")
    assert np.max(cells.terms["Nt"] / cells.terms["B"]) < 0.2
    h = np.diff(plan.t)
    whole = terms["A"] * h * h / 8.0 + terms["B"] * h / (4.0 * (plan.around - 1))
    assert np.mean(ribbon_twist_error(terms, h, plan.around) < whole) >= 0.75


def tilted_flaring_tube(log_scale, distance, curve, count, tilt, flare, seed):
    """(centres, normals, radii, weights) of a random tube of size 10^log_scale at ``distance``
    from the origin, its circles tilted against the path by up to ``tilt`` and its radii changed
    by up to 10^flare between controls (weights for a rational Bezier curve, else None)."""
    rng = np.random.default_rng(seed)
    offset = distance * rng.normal(size=3) / np.sqrt(3.0)
    centres, normals, radii = tube(10.0**log_scale, offset, count if curve != "catmull_rom" else max(count, 3), rng)
    normals = normals + tilt * rng.normal(size=normals.shape)
    radii = radii * 10.0 ** rng.uniform(-flare, flare, size=len(radii))
    weights = list(10.0 ** rng.uniform(-1.0, 1.0, size=len(radii))) if curve == "rational_bezier" else None
    return centres, normals, radii, weights


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), log_relative=st.floats(-3.0, -1.5))
def test_closed_loop_bound_is_never_exceeded(seed, log_relative):
    """A closed loop's frames carry its holonomy, spread along it: the bound covers that spin."""
    rng = np.random.default_rng(seed)
    angle = np.linspace(0.0, 2.0 * np.pi, 6, endpoint=False)
    centres = np.stack([2.0 * np.cos(angle), 2.0 * np.sin(angle), rng.uniform(-0.8, 0.8, size=6)], axis=1)
    normals = np.stack([-np.sin(angle), np.cos(angle), 0.3 * rng.normal(size=6)], axis=1)
    spec = spec_of(centres, normals, rng.uniform(0.3, 0.6, size=6), curve="catmull_rom", closed=True)
    surface = build_surface(spec)
    tolerance = 10.0**log_relative * surface.frame.scale
    plan = plan_tolerance(surface, tolerance, "circles", closed=True)
    mesh = mesh_circle_surface(surface, plan.around, t=plan.t, closed=True)
    grid = mesh.positions.reshape(plan.rings, plan.around + 1, 3)
    assert plan.bound <= tolerance
    assert grid_deviation(surface, plan.t, grid, CIRCLES).max <= plan.bound


@PROPERTIES
@given(log_scale=st.floats(-4.0, 4.0), distance=st.floats(0.0, 1e5), curve=st.sampled_from(CURVES),
       count=st.integers(2, 5), tilt=st.floats(0.0, 1.0), flare=st.floats(0.0, 0.7),
       interpolation=st.sampled_from(["blade", "motor"]), log_relative=st.floats(-3.0, -1.0),
       seed=st.integers(0, 2**32 - 1))
def test_tilted_flaring_tube_bound_is_never_exceeded(log_scale, distance, curve, count, tilt, flare,
                                                     interpolation, log_relative, seed):
    """Circles tilted against their path (the twist's normal part grows with the tilt), radii
    changing by up to 5x between controls (the shear around the ring), blade and motor
    interpolation: the bound with the twist's normal part still covers the measured deviation."""
    centres, normals, radii, weights = tilted_flaring_tube(log_scale, distance, curve, count, tilt, flare, seed)
    spec = replace(spec_of(centres, normals, radii, curve=curve, weights=weights), interpolation=interpolation)
    surface = build_surface(spec)
    tolerance = 10.0**log_relative * surface.frame.scale
    plan = plan_tolerance(surface, tolerance, "circles")
    assert plan.bound <= tolerance
    assert measured(surface, plan, "circles") <= plan.bound


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(log_scale=st.floats(-4.0, 4.0), distance=st.floats(0.0, 1e5), curve=st.sampled_from(CURVES),
       count=st.integers(2, 4), tilt=st.floats(0.0, 0.6), flare=st.floats(0.0, 0.5),
       log_relative=st.floats(-3.0, -1.5), seed=st.integers(0, 2**32 - 1))
def test_the_normal_projection_bounds_every_interval_alone(log_scale, distance, curve, count, tilt, flare,
                                                          log_relative, seed):
    """The bound by the error normal to the surface (cgamesh.meshing.tolerance.normal_projection), taken
    alone, is at least each interval's measured deviation wherever it applies: the plan's bound
    is the smallest of three, so the end-to-end tests above would not notice one that fails."""
    from cgamesh.meshing.tolerance import tolerance_plan
    from cgamesh.meshing.tolerance.normal_projection import normal_projection_error

    centres, normals, radii, weights = tilted_flaring_tube(log_scale, distance, curve, count, tilt, flare, seed)
    surface = build_surface(spec_of(centres, normals, radii, curve=curve, weights=weights))
    plan, cells, table, names, _, terms = placed_terms(surface, 10.0**log_relative * surface.frame.scale, "circles")
    wide = tolerance_plan._widened(cells, table, names, plan.t)
    normal = normal_projection_error(terms, wide, np.diff(plan.t), plan.around, cells.closed_rate)
    grid = mesh_circle_surface(surface, plan.around, t=plan.t).positions.reshape(plan.rings, plan.around + 1, 3)
    applies = np.flatnonzero(np.isfinite(normal))
    assume(applies.size > 0)  # (it applies nowhere on a few short, strongly tilted tubes)
    for k in applies:  # one interval at a time: its own measured deviation against its own bound
        assert grid_deviation(surface, plan.t[k:k + 2], grid[k:k + 2], CIRCLES).max <= normal[k], k


@pytest.mark.parametrize("path, twist_share, normal_share",
                         [("examples/closed_loop.yaml", 0.05, 0.85), ("examples/kb_tube.yaml", 0.05, 0.7)])
def test_the_error_normal_to_the_surface_is_what_bounds_tubes(path, twist_share, normal_share):
    """On tubes whose circles are about perpendicular to their path, the bounds that drop the
    twist's tangential part (the bubble reparametrisation, and the projection on the surface's
    normal, cgamesh.meshing.tolerance.normal_projection) are the smaller ones on most intervals, so the
    rings follow them (measured at 1e-3: the normal projection on 91% of closed_loop's intervals,
    81% of kb_tube's); an interval's bound is the smallest of the three, exactly."""
    from cgamesh.inputs.scene import load_scene
    from cgamesh.meshing.tolerance import quad_bounds, tolerance_plan
    from cgamesh.meshing.tolerance.normal_projection import normal_projection_error

    spec = load_scene(path).surfaces[0]
    surface = build_surface(spec)
    plan, cells, table, names, error, terms = placed_terms(surface, 1e-3 * surface.frame.scale, "circles", spec.closed)
    sag = terms["Rm"] * (1.0 - np.cos(np.pi / plan.around))
    h = np.diff(plan.t)
    n1 = terms["N1"]
    q = 2.0 - 0.5 * (h * n1) ** 2
    spin = h * n1 * n1 / q + cells.closed_rate
    spin_rate = h * n1 * terms["N2"] / q + (h * n1 * n1 / q) ** 2
    a = terms["A"] + 2.0 * terms["B"] * spin + terms["Rm"] * (spin * spin + spin_rate)
    b = terms["B"] + terms["Rm"] * spin
    whole = sag + a * h * h / 8.0 + b * h * np.sin(np.pi / plan.around) / 2.0
    twist = sag + quad_bounds.normal_twist_error(terms, h, plan.around, a, b, spin, spin_rate)
    wide = tolerance_plan._widened(cells, table, names, plan.t)
    normal = normal_projection_error(terms, wide, h, plan.around, cells.closed_rate)
    assert np.all(error == np.minimum(np.minimum(whole, twist), normal))
    assert np.mean(twist < whole) >= twist_share
    assert np.mean(normal < np.minimum(whole, twist)) >= normal_share


def test_derivative_bounds_cover_the_analytic_derivatives():
    """On f(t) = (sin 3t, t^3, exp(t) cos 5t) per segment, the per-cell bounds of |f|, |f'| and
    |f''| are at least their largest values over each cell (checked at 64 points per cell), and
    their excess shrinks as the cells get finer."""
    def f(t):
        return np.stack([np.sin(3.0 * t), t**3, np.exp(t) * np.cos(5.0 * t)], axis=-1)

    def f1(t):
        return np.stack([3.0 * np.cos(3.0 * t), 3.0 * t**2,
                         np.exp(t) * (np.cos(5.0 * t) - 5.0 * np.sin(5.0 * t))], axis=-1)

    def f2(t):
        return np.stack([-9.0 * np.sin(3.0 * t), 6.0 * t,
                         np.exp(t) * (-24.0 * np.cos(5.0 * t) - 10.0 * np.sin(5.0 * t))], axis=-1)

    excess = {}
    for cells in (16, 64):
        t = segment_samples(3, cells)
        value, first, second = cell_bounds(f(t))
        inside = t[:, :-1, None] + np.linspace(0.0, 1.0, 64)[None, None, :] / cells  # (3, S, 64)
        for order, (bound, derivative) in enumerate(((value, f), (first, f1), (second, f2))):
            true = np.linalg.norm(derivative(inside), axis=-1).max(axis=-1)
            assert np.all(bound >= true)
            excess[cells, order] = float(((bound - true) / true.max()).max())
    for order in range(3):  # the margins shrink with the cells (they are O(delta))
        assert excess[64, order] <= excess[16, order] / 3.0


@pytest.mark.parametrize("kind, path", [("circles", "examples/kb_tube.yaml"),
                                        ("point_pairs", "examples/ribbon_loop.yaml")])
@pytest.mark.parametrize("tolerance", [0.0, -1.0, float("nan"), float("inf"), 1e-30, 1e-15])
def test_impossible_tolerances_are_refused_quickly(kind, path, tolerance):
    from cgamesh.inputs.scene import load_scene

    spec = load_scene(path).surfaces[0]
    surface = build_surface(spec)
    start = time.perf_counter()
    with pytest.raises(InvalidInputError) as raised:
        plan_tolerance(surface, tolerance * surface.frame.scale, kind, spec.closed)
    assert "tolerance" in str(raised.value) and "\n" not in str(raised.value)
    assert time.perf_counter() - start < 30.0  # refused, not ground through


@pytest.mark.parametrize("kind, path", [("circles", "examples/kb_tube.yaml"),
                                        ("circles", "examples/closed_loop.yaml"),
                                        ("point_pairs", "examples/ribbon_loop.yaml")])
def test_planned_counts_are_those_the_plan_uses(kind, path):
    """plan_counts, for a resource budget, gives the count around and about the rings."""
    from cgamesh.inputs.scene import load_scene

    spec = load_scene(path).surfaces[0]
    surface = build_surface(spec)
    for relative in (1e-2, 1e-3):
        tolerance = relative * surface.frame.scale
        counts = plan_counts(surface, tolerance, kind, spec.closed)
        plan = plan_tolerance(surface, tolerance, kind, spec.closed)
        assert counts.around == plan.around
        assert counts.rings <= plan.rings <= 1.5 * counts.rings + 8
