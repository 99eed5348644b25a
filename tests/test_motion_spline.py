"""The splined similarity motion (geometry.motors.Motions) against its definition (docs/interpolation.md).

Each property is checked on batches of motions of every curve kind, open and closed, aligned or
not, with normals among them along the exact axes: the spline passes through its control circles,
its rates are the central differences of its values, its normal is unit, its radius stays within
each span's two radii (the monotone limit), a certified motion's normal spline stays longer than
the minimum; and a batch of many evaluates each of its motions exactly as a batch of one does.
"""

from __future__ import annotations

from unittest import mock

import numpy as np
import pytest
from direction_strategies import direction
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cgamesh.errors import DegenerateGeometryError
from cgamesh.geometry import motors
from cgamesh.geometry.motors import (GLOBAL_KINDS, KINDS, MIN_NORMAL_LENGTH, MotionNodes, Motions, MotionSpline)

PROPERTIES = settings(max_examples=40, deadline=None, derandomize=True,
                      suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
coordinate = st.floats(-1.0, 1.0, allow_nan=False)


@st.composite
def motion(draw, kinds=KINDS):
    """One motion's controls and options: (centre, normal, radius, kind, closed, tension, bias,
    continuity, weights, align)."""
    kind = draw(st.sampled_from(kinds))
    count = draw(st.integers(2, 6))
    centre = np.array(draw(st.lists(st.tuples(coordinate, coordinate, coordinate), min_size=count, max_size=count)))
    normal = np.array(draw(st.lists(direction, min_size=count, max_size=count)))
    radius = np.array(draw(st.lists(st.floats(0.05, 1.0), min_size=count, max_size=count)))
    tension, bias, continuity = draw(st.tuples(coordinate, coordinate, coordinate)) if kind == "kb" else (0.0,) * 3
    weights = tuple(draw(st.lists(st.floats(0.01, 100.0), min_size=count, max_size=count)))
    return (centre, normal, radius, kind, draw(st.booleans()), tension, bias, continuity,
            weights if kind == "rational_bezier" else None, draw(st.booleans()))


def batch(motions) -> Motions:
    """The motions as one batch: their nodes concatenated, each with its own kind and options."""
    count = np.array([len(m[2]) for m in motions])
    nodes = MotionNodes(np.concatenate([[0], np.cumsum(count)[:-1]]), count, np.array([m[4] for m in motions]))
    column = lambda k: np.array([m[k] for m in motions])  # noqa: E731
    weights = np.concatenate([m[8] if m[8] is not None else np.ones(len(m[2])) for m in motions])
    return Motions.through(np.vstack([m[0] for m in motions]), np.vstack([m[1] for m in motions]),
                           np.concatenate([m[2] for m in motions]), nodes, column(3), column(5), column(6), column(7),
                           weights, column(9))


def rows(motions: Motions, per_segment: int = 7) -> tuple[np.ndarray, np.ndarray]:
    """Rows (motion, t): per_segment parameters strictly inside every segment of every motion."""
    segments = motions.segment_count
    motion = np.repeat(np.arange(len(segments)), segments * per_segment)
    local = np.arange(len(motion)) - np.repeat(np.cumsum(segments * per_segment) - segments * per_segment,
                                               segments * per_segment)
    return motion, (local + 0.5) / per_segment


@PROPERTIES
@given(st.lists(motion(), min_size=1, max_size=6))
def test_a_batch_evaluates_each_motion_as_a_batch_of_one(motions):
    many = batch(motions)
    motion, t = rows(many)
    state = many.evaluate(motion, t)
    ok = many.normals_ok(16)
    for m, case in enumerate(motions):
        one = MotionSpline.through(*case)
        assert one.segment_count == many.segment_count[m]
        alone = one.evaluate(t[motion == m])
        for name in ("centre", "normal", "radius", "d_centre", "d_normal", "d_radius", "normal_length"):
            np.testing.assert_array_equal(getattr(state, name)[motion == m], getattr(alone, name))
        assert one.motions.certified[0] == many.certified[m]
        assert one.motions.normals_ok(16)[0] == ok[m]


@PROPERTIES
@given(motion())
def test_the_spline_passes_through_its_control_circles(case):
    centre, normal, radius, kind, closed = case[:5]
    spline = MotionSpline.through(*case)
    given_normal = normal / np.linalg.norm(normal, axis=1, keepdims=True)
    nodes = [0, len(radius) - 1] if kind in GLOBAL_KINDS else list(range(len(radius)))
    t = np.array([0.0, 1.0] if kind in GLOBAL_KINDS else nodes, dtype=np.float64)
    state = spline.evaluate(t)
    np.testing.assert_allclose(state.centre, centre[nodes], rtol=0, atol=1e-14)
    np.testing.assert_allclose(state.radius, radius[nodes], rtol=1e-14)
    # the normal is the control's, with the sign the orientation chose
    np.testing.assert_allclose(state.normal, spline.nodes[nodes, 3:6], rtol=0, atol=1e-14)
    np.testing.assert_allclose(np.abs(np.einsum("ai,ai->a", state.normal, given_normal[nodes])), 1.0, atol=1e-14)
    if closed and kind not in GLOBAL_KINDS:  # the closing span ends on the first circle
        end = spline.evaluate(np.array([float(spline.segment_count)]))
        np.testing.assert_allclose(end.centre[0], centre[0], rtol=0, atol=1e-14)
        np.testing.assert_allclose(end.radius[0], radius[0], rtol=1e-14)


@PROPERTIES
@given(motion())
def test_rates_are_central_differences_of_the_values(case):
    spline = MotionSpline.through(*case)
    motion, t = rows(spline.motions)
    h = 1e-6
    state, plus, minus = (spline.evaluate(t + d) for d in (0.0, h, -h))
    # the normal's rate grows as 1 / |H|: compare where the normal spline is well away from zero
    steady = np.minimum.reduce([state.normal_length, plus.normal_length, minus.normal_length]) > 0.05
    for name in ("centre", "normal", "radius"):
        rate = getattr(state, "d_" + name)
        difference = (getattr(plus, name) - getattr(minus, name)) / (2 * h)
        scale = 1.0 + np.abs(rate).max()
        np.testing.assert_allclose(rate[steady], difference[steady], rtol=0, atol=2e-6 * scale / 0.05)
    np.testing.assert_allclose(state.omega, np.cross(state.normal, state.d_normal), rtol=0, atol=0)


@PROPERTIES
@given(motion())
def test_the_normal_is_unit_and_the_radius_stays_within_its_span(case):
    radius, kind = case[2], case[3]
    spline = MotionSpline.through(*case)
    motion, t = rows(spline.motions, 31)
    state = spline.evaluate(t)
    real = state.normal_length >= MIN_NORMAL_LENGTH
    np.testing.assert_allclose(np.linalg.norm(state.normal[real], axis=1), 1.0, atol=1e-14)
    if kind in GLOBAL_KINDS:  # a Bezier curve stays in its controls' convex hull
        low, high = np.full(len(t), radius.min()), np.full(len(t), radius.max())
    else:
        segment = np.floor(t).astype(np.int64)
        ends = radius[segment], radius[(segment + 1) % len(radius)]
        low, high = np.minimum(*ends), np.maximum(*ends)
    assert np.all(state.radius >= low * (1 - 1e-14)) and np.all(state.radius <= high * (1 + 1e-14))


@PROPERTIES
@given(st.lists(motion(kinds=("linear", "kb", "catmull_rom")), min_size=1, max_size=4),
       st.sampled_from([MIN_NORMAL_LENGTH, 0.2, 0.4]))
def test_a_certified_normal_spline_stays_above_the_minimum(motions, minimum):
    # the bound is checked at the real minimum and at larger ones, which piecewise normal
    # splines (kept off zero by the bump) do fall below
    with mock.patch.object(motors, "MIN_NORMAL_LENGTH", minimum):
        many = batch(motions)
        ok = many.normals_ok(128)
    motion, t = rows(many, 1000)
    length = many.evaluate(motion, t).normal_length
    shortest = np.full(len(motions), np.inf)
    np.minimum.at(shortest, motion, length)
    assert np.all(shortest[many.certified] > minimum)
    assert np.all(ok[many.certified])


def test_bezier_kinds_are_left_to_the_sampled_check():
    rng = np.random.default_rng(1)
    for kind in GLOBAL_KINDS:
        spline = MotionSpline.through(rng.normal(size=(4, 3)), np.tile([0.0, 0.0, 1.0], (4, 1)), np.ones(4), kind)
        assert not spline.motions.certified[0] and spline.motions.normals_ok(128)[0]


def test_a_normal_spline_through_zero_is_refused_naming_the_surface_segment_and_alpha():
    # opposite normals kept as given: a Bezier's H = (1 - t) n - t n (no bump) vanishes at t = 1/2;
    # a linear span's bump turns its half turn through a perpendicular instead
    centre = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    normal = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]])
    spline = MotionSpline.through(centre, normal, np.ones(2), "bezier", align=False)
    assert not spline.motions.normals_ok(128)[0]
    with pytest.raises(DegenerateGeometryError, match=r"surface 'tube'.*segment 0, alpha = 0\.5 "):
        spline.check_normals("tube", 128)
    # in a batch, the first motion that fails is named
    both = Motions.concatenate([MotionSpline.through(centre, normal, np.ones(2), "linear").motions, spline.motions])
    assert both.normals_ok(128).tolist() == [True, False]
    with pytest.raises(DegenerateGeometryError, match="surface 'second'"):
        both.check_normals(["first", "second"], 128)
