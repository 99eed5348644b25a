"""cgamesh.geometry.curves: basis matrices hit their controls, equal the paper's formulas, and differentiate right."""

from __future__ import annotations

import numpy as np
import pytest

from cgamesh.geometry.curves import split_parameter
from cgamesh.geometry.curves.bezier import Bezier, RationalBezier, bernstein, bernstein_derivative
from cgamesh.geometry.curves.kochanek_bartels import KochanekBartels, catmull_rom
from cgamesh.geometry.curves.linear import Linear

H = 1e-6  # central-difference step in t

# (id, curve, reference kind for the paper_weights fixture, its keyword arguments)
CURVES = [
    ("linear", Linear(5), "linear", {}),
    ("bezier1", Bezier(2), "bezier", {}),
    ("bezier3", Bezier(4), "bezier", {}),
    ("bezier6", Bezier(7), "bezier", {}),
    ("rational", RationalBezier((1.0, 3.0, 0.5, 2.0)), "rational_bezier", {"weights": (1.0, 3.0, 0.5, 2.0)}),
    ("kb", KochanekBartels(5, 0.3, -0.4, 0.25), "kb", {"tension": 0.3, "bias": -0.4, "continuity": 0.25}),
    ("kb_closed", KochanekBartels(5, -0.2, 0.5, -0.6, closed=True), "kb",
     {"tension": -0.2, "bias": 0.5, "continuity": -0.6, "closed": True}),
    ("catmull_rom", catmull_rom(6), "catmull_rom", {}),
    ("catmull_rom_closed", catmull_rom(4, closed=True), "catmull_rom", {"closed": True}),
]
IDS = [c[0] for c in CURVES]


@pytest.fixture
def controls(rng):
    """Ten random 32-vectors: the curves are linear in their controls, blades or not."""
    return rng.standard_normal((10, 32))


def _evaluate(curve, t, controls):
    return curve.basis(np.asarray(t, dtype=np.float64)).evaluate(controls[:curve.control_count])


def _interior_samples(curve, rng, count=200):
    """Parameters away from the segment joints (where KB is only C0 for continuity != 0)."""
    segment = rng.integers(0, curve.segment_count, count)
    return segment + rng.uniform(0.01, 0.99, count)


@pytest.mark.parametrize("curve", [Linear(5), KochanekBartels(5, 0.3, -0.4, 0.25), catmull_rom(6)],
                         ids=["linear", "kb", "catmull_rom"])
def test_piecewise_curves_pass_through_controls_at_integer_t(curve, controls):
    value, _ = _evaluate(curve, np.arange(curve.control_count, dtype=np.float64), controls)
    assert np.max(np.abs(value - controls[:curve.control_count])) <= 1e-14


@pytest.mark.parametrize("curve", [KochanekBartels(5, 0.3, -0.4, 0.25, closed=True), catmull_rom(4, closed=True)],
                         ids=["kb", "catmull_rom"])
def test_closed_curves_pass_through_controls_at_integer_t_and_wrap(curve, controls):
    n = curve.control_count
    value, _ = _evaluate(curve, np.arange(n + 1, dtype=np.float64), controls)
    want = controls[np.arange(n + 1) % n]
    assert np.max(np.abs(value - want)) <= 1e-14


@pytest.mark.parametrize("curve", [Bezier(2), Bezier(4), Bezier(7), RationalBezier((1.0, 3.0, 0.5, 2.0))],
                         ids=["bezier1", "bezier3", "bezier6", "rational"])
def test_bezier_curves_pass_through_their_end_controls(curve, controls):
    value, _ = _evaluate(curve, [0.0, 1.0], controls)
    want = controls[[0, curve.control_count - 1]]
    assert np.max(np.abs(value - want)) <= 1e-14


@pytest.mark.parametrize("order", [1, 2, 3, 5, 9])
def test_bernstein_polynomials_are_a_partition_of_unity(order, rng):
    alpha = rng.uniform(0.0, 1.0, 100)
    assert np.max(np.abs(bernstein(order, alpha).sum(axis=1) - 1.0)) <= 1e-14


@pytest.mark.parametrize("order", [1, 2, 3, 5, 9])
def test_bernstein_derivatives_sum_to_zero(order, rng):
    alpha = rng.uniform(0.0, 1.0, 100)
    assert np.max(np.abs(bernstein_derivative(order, alpha).sum(axis=1))) <= 1e-12


@pytest.mark.parametrize("case", CURVES, ids=IDS)
def test_weights_form_a_partition_of_unity(case, rng):
    # Affine combinations: every curve here reproduces a constant control.
    curve = case[1]
    basis = curve.basis(_interior_samples(curve, rng))
    assert np.max(np.abs(basis.weights.sum(axis=1) - 1.0)) <= 1e-14


@pytest.mark.parametrize("weight", [1.0, 0.3, 7.0])
def test_rational_bezier_with_equal_weights_equals_bezier(weight, controls, rng):
    t = rng.uniform(0.0, 1.0, 100)
    rational = _evaluate(RationalBezier((weight,) * 5), t, controls)
    plain = _evaluate(Bezier(5), t, controls)
    assert all(np.max(np.abs(r - p)) <= 1e-13 for r, p in zip(rational, plain))


@pytest.mark.parametrize("case", CURVES, ids=IDS)
def test_values_equal_the_papers_formulas(case, controls, rng, paper_weights):
    _, curve, kind, kwargs = case
    t = np.concatenate([_interior_samples(curve, rng), np.arange(curve.segment_count + 1.0)])
    value, _ = _evaluate(curve, t, controls)
    want = paper_weights(kind, curve.control_count, t, **kwargs) @ controls[:curve.control_count]
    assert np.max(np.abs(value - want)) <= 1e-12


@pytest.mark.parametrize("case", CURVES, ids=IDS)
def test_derivative_equals_central_differences(case, controls, rng):
    curve = case[1]
    t = _interior_samples(curve, rng)
    _, derivative = _evaluate(curve, t, controls)
    difference = (_evaluate(curve, t + H, controls)[0] - _evaluate(curve, t - H, controls)[0]) / (2 * H)
    assert np.max(np.abs(derivative - difference)) <= 1e-7 * (1.0 + np.max(np.abs(derivative)))


def test_catmull_rom_equals_the_textbook_cubic(controls, rng):
    # P(a) = 1/2 [2 P1 + (-P0 + P2) a + (2 P0 - 5 P1 + 4 P2 - P3) a^2 + (-P0 + 3 P1 - 3 P2 + P3) a^3]
    curve = catmull_rom(6)
    t = rng.uniform(1.0, 4.0, 100)  # the segments with both neighbours present
    value, _ = _evaluate(curve, t, controls)
    i, a = split_parameter(t, curve.segment_count)
    p0, p1, p2, p3 = (controls[i + k] for k in (-1, 0, 1, 2))
    a = a[:, None]
    want = 0.5 * (2 * p1 + (-p0 + p2) * a + (2 * p0 - 5 * p1 + 4 * p2 - p3) * a**2
                  + (-p0 + 3 * p1 - 3 * p2 + p3) * a**3)
    assert np.max(np.abs(value - want)) <= 1e-13


@pytest.mark.parametrize("closed", [False, True])
def test_catmull_rom_equals_kb_with_zero_parameters(closed, controls, rng):
    t = rng.uniform(0.0, 5.0 if closed else 4.0, 100)
    cr = _evaluate(catmull_rom(5, closed=closed), t, controls)
    kb = _evaluate(KochanekBartels(5, 0.0, 0.0, 0.0, closed), t, controls)
    assert all(np.array_equal(x, y) for x, y in zip(cr, kb))


def test_closed_kb_wraps_value_at_t_n_to_t_0(controls):
    curve = KochanekBartels(5, 0.3, -0.4, 0.25, closed=True)
    start, end = _evaluate(curve, [0.0, 5.0], controls)[0]
    assert np.max(np.abs(start - end)) <= 1e-14


def test_closed_kb_with_zero_continuity_wraps_derivative(controls):
    # Tangents are shared across a joint when continuity is 0, the wrap included.
    curve = KochanekBartels(5, 0.3, -0.4, 0.0, closed=True)
    start, end = _evaluate(curve, [0.0, 5.0], controls)[1]
    assert np.max(np.abs(start - end)) <= 1e-13


def test_open_kb_end_tangents_use_the_end_control_as_missing_neighbour(controls):
    # With C_{-1} = C_0 the first outgoing tangent is (1-t)(1-b)(1-c)/2 (C_1 - C_0).
    t_, b, c = 0.3, -0.4, 0.25
    curve = KochanekBartels(5, t_, b, c)
    _, derivative = _evaluate(curve, [0.0, 4.0], controls)
    first = (1 - t_) * (1 - b) * (1 - c) / 2 * (controls[1] - controls[0])
    last = (1 - t_) * (1 + b) * (1 - c) / 2 * (controls[4] - controls[3])
    assert np.max(np.abs(derivative - np.stack([first, last]))) <= 1e-13


def test_split_parameter_puts_the_end_in_the_last_segment():
    segment, alpha = split_parameter(np.array([0.0, 0.5, 1.0, 2.999, 3.0]), 3)
    assert np.array_equal(segment, [0, 0, 1, 2, 2]) and np.allclose(alpha, [0.0, 0.5, 0.0, 0.999, 1.0])
