"""cgamesh.geometry.algebra: the product tables, the conformal model and the TRS rotors equal clifford's."""

from __future__ import annotations

import numpy as np
import pytest

from cgamesh.geometry.algebra import conformal, products, rotors
from cgamesh.geometry.algebra.layout import BLADE_NAMES, GRADES

BATCH = 50


def _close(got, want, rtol=1e-12):
    """Elementwise |got - want| <= rtol * (1 + max |want|)."""
    got, want = np.asarray(got), np.asarray(want)
    return np.max(np.abs(got - want)) <= rtol * (1.0 + np.max(np.abs(want)))


@pytest.fixture
def multivectors(rng):
    return rng.standard_normal((BATCH, 32)), rng.standard_normal((BATCH, 32))


def _points(rng, count=BATCH):
    return rng.uniform(-3.0, 3.0, (count, 3))


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _sandwich_point(oracle, versor, x):
    """down(V up(x) ~V) computed by clifford, for a versor given as 32 coefficients."""
    V = oracle.mv(versor)
    return oracle.down(V * oracle.point(x) * ~V)


def test_blade_order_is_cliffords(g3c):
    assert list(BLADE_NAMES) == ["1" if name == "" else name for name in g3c.layout.names]


@pytest.mark.parametrize("op", ["geometric", "outer", "inner"])
def test_products_of_general_multivectors_equal_cliffords(oracle, multivectors, op):
    a, b = multivectors
    symbol = {"geometric": lambda x, y: x * y, "outer": lambda x, y: x ^ y, "inner": lambda x, y: x | y}[op]
    want = np.array([symbol(oracle.mv(x), oracle.mv(y)).value for x, y in zip(a, b)])
    assert _close(getattr(products, op)(a, b), want)


@pytest.mark.parametrize(
    "grades_a, grades_b, grades_out",
    [((3,), (3,), (0, 4)), ((3,), (3,), (2,)), ((0, 4), (3,), (3,)), ((0, 2, 4), (1,), (1, 3)),
     ((2,), (1,), (1,)), ((1,), (1,), (0, 2)), ((4,), (4,), (0,)), ((1, 3, 5), (0, 2, 4), (1,))],
)
def test_grade_restricted_geometric_product_equals_cliffords_grade_selection(
        oracle, multivectors, grades_a, grades_b, grades_out):
    a = np.where(np.isin(GRADES, grades_a), multivectors[0], 0.0)
    b = np.where(np.isin(GRADES, grades_b), multivectors[1], 0.0)
    want = []
    for x, y in zip(a, b):
        full = oracle.mv(x) * oracle.mv(y)
        want.append(sum((full(g) for g in grades_out), oracle.mv(np.zeros(32))).value)
    assert _close(products.geometric(a, b, grades_a, grades_b, grades_out), np.array(want))


def test_products_restricted_to_named_blades_equal_cliffords(oracle, rng):
    # Euclidean rotors live on the blades 1, e12, e13, e23: their product, restricted to
    # those blades, is the whole product.
    blades = rotors.EUCLIDEAN_ROTOR_BLADES
    a = rotors.rotation_between(_unit(rng.standard_normal((BATCH, 3))), _unit(rng.standard_normal((BATCH, 3))))
    b = rotors.rotation_between(_unit(rng.standard_normal((BATCH, 3))), _unit(rng.standard_normal((BATCH, 3))))
    want = np.array([(oracle.mv(x) * oracle.mv(y)).value for x, y in zip(a, b)])
    assert _close(products.geometric(a, b, blades, blades, blades), want)


def test_named_blades_and_grades_with_the_same_numbers_differ(multivectors):
    # Blades (1, 2) are e1 and e2; grades (1, 2) are every vector and bivector.
    a, b = multivectors
    by_blades = products.geometric(a, b, products.Blades((1, 2)), products.Blades((1, 2)))
    by_grades = products.geometric(a, b, (1, 2), (1, 2))
    kept = np.zeros(32)
    kept[[1, 2]] = 1.0
    assert _close(by_blades, products.geometric(a * kept, b * kept))
    assert not _close(by_blades, by_grades)


@pytest.mark.parametrize("kind", ["geometric", "outer", "inner"])
def test_right_operator_rows_applied_to_a_equal_the_product(oracle, multivectors, kind):
    a, b = multivectors
    a = np.where(GRADES == 1, a, 0.0)
    blades_a, matrix = products.right_operator(kind, b, (1,))
    symbol = {"geometric": lambda x, y: x * y, "outer": lambda x, y: x ^ y, "inner": lambda x, y: x | y}[kind]
    want = np.array([symbol(oracle.mv(x), oracle.mv(y)).value for x, y in zip(a, b)])
    assert _close(np.einsum("ki,kio->ko", a[:, blades_a], matrix), want)


def test_reverse_equals_cliffords(oracle, multivectors):
    a = multivectors[0]
    assert _close(products.reverse(a), np.array([(~oracle.mv(x)).value for x in a]))


def test_dual_equals_cliffords(oracle, multivectors):
    # clifford's M.dual(I) = M I^-1 (its argument-free form, identical, costs seconds of JIT).
    a, pseudoscalar = multivectors[0], oracle.layout.pseudoScalar
    assert _close(products.dual(a), np.array([oracle.mv(x).dual(pseudoscalar).value for x in a]))


@pytest.mark.parametrize("grades", [(0,), (1,), (2,), (3,), (4,), (5,), (0, 4), (1, 3, 5)])
def test_grade_selection_equals_cliffords(oracle, multivectors, grades):
    a = multivectors[0]
    want = np.array([sum((oracle.mv(x)(g) for g in grades), oracle.mv(np.zeros(32))).value for x in a])
    assert np.array_equal(products.grade(a, *grades), want)


def test_up_equals_cliffords(oracle, rng):
    x = _points(rng)
    assert _close(conformal.up(x), np.array([oracle.point(p).value for p in x]))


def test_down_inverts_cliffords_up_at_any_weight(oracle, rng):
    x = _points(rng)
    weights = rng.uniform(0.1, 10.0, BATCH) * rng.choice([-1.0, 1.0], BATCH)
    scaled = np.array([(w * oracle.point(p)).value for w, p in zip(weights, x)])
    assert _close(conformal.down(scaled), x)


def test_null_vectors_of_the_model_equal_cliffords(g3c):
    assert np.array_equal(conformal.N_INF, g3c.einf.value) and np.array_equal(conformal.N_0, g3c.eo.value)


def test_translator_equals_cliffords_generate_translation_rotor(oracle, g3c_tools, rng):
    shifts = _points(rng)
    want = np.array([g3c_tools.generate_translation_rotor(
        oracle.mv(conformal.vector(s))).value for s in shifts])
    assert _close(rotors.translator(shifts), want)


def test_translator_moves_points_by_its_vector(oracle, rng):
    shifts, x = _points(rng), _points(rng)
    moved = np.array([_sandwich_point(oracle, T, p) for T, p in zip(rotors.translator(shifts), x)])
    assert _close(moved, x + shifts)


@pytest.mark.parametrize("scale", [0.25, 0.9, 1.0 + 2e-5, 3.0])
def test_dilator_acts_as_cliffords_generate_dilation_rotor(oracle, g3c_tools, rng, scale):
    x = _points(rng, 10)
    theirs = g3c_tools.generate_dilation_rotor(scale)
    want = np.array([oracle.down(theirs * oracle.point(p) * ~theirs) for p in x])
    got = np.array([_sandwich_point(oracle, rotors.dilator(scale), p) for p in x])
    assert _close(got, want)


@pytest.mark.parametrize("scale", [1.0 + 1e-7, 1.0 - 1e-9, 1.0 + 1e-12])
def test_dilator_scales_below_cliffords_cutoff(oracle, rng, scale):
    # clifford's generate_dilation_rotor returns 1 for |scale - 1| < 1e-5; ours must not.
    x = _points(rng, 10)
    got = np.array([_sandwich_point(oracle, rotors.dilator(scale), p) for p in x])
    assert np.max(np.abs(got - scale * x)) <= 1e-14 * np.max(np.abs(x))  # 100 times below 1e-12


def test_rotation_between_takes_a_to_b(oracle, rng):
    a, b = _unit(rng.standard_normal((BATCH, 3))), _unit(rng.standard_normal((BATCH, 3)))
    a[:3] = [[0, 0, 1], [1, 0, 0], [0.6, 0.8, 0]]
    b[:3] = [[0, 0, -1], [-1, 0, 0], [-0.6, -0.8, 0]]  # opposite: a half turn
    R = rotors.rotation_between(a, b)
    moved = np.array([oracle.euclidean(oracle.mv(r) * oracle.mv(conformal.vector(x)) * ~oracle.mv(r))
                      for r, x in zip(R, a)])
    assert _close(moved, b)


def test_apply_to_euclidean_equals_clifford_sandwich(oracle, rng):
    R = rotors.rotation_between(_unit(rng.standard_normal((BATCH, 3))), _unit(rng.standard_normal((BATCH, 3))))
    x = _points(rng)
    want = np.array([oracle.euclidean(oracle.mv(r) * oracle.mv(conformal.vector(p)) * ~oracle.mv(r))
                     for r, p in zip(R, x)])
    assert _close(rotors.apply_to_euclidean(R, x), want)


def test_trs_versor_is_the_similarity_centre_plus_scale_times_rotation(oracle, rng):
    centres, x = _points(rng), _points(rng)
    scales = rng.uniform(0.05, 5.0, BATCH)
    normals = _unit(rng.standard_normal((BATCH, 3)))
    R = rotors.rotation_between(np.broadcast_to([0.0, 0.0, 1.0], normals.shape), normals)
    Z = rotors.trs_versor(centres, R, scales)
    rotated = np.array([oracle.euclidean(oracle.mv(r) * oracle.mv(conformal.vector(p)) * ~oracle.mv(r))
                        for r, p in zip(R, x)])
    got = np.array([_sandwich_point(oracle, z, p) for z, p in zip(Z, x)])
    assert _close(got, centres + scales[:, None] * rotated)


@pytest.mark.parametrize("grades", [{}, {"grades": (0, 2)}], ids=["default", "euclidean"])
def test_prefix_products_equal_sequential_clifford_products(oracle, rng, grades):
    count = 37
    steps = rotors.rotation_between(_unit(rng.standard_normal((count, 3))), _unit(rng.standard_normal((count, 3))))
    running = oracle.mv(steps[0])
    want = [running.value]
    for step in steps[1:]:
        running = oracle.mv(step) * running
        want.append(running.value)
    assert _close(rotors.prefix_products(steps, **grades), np.array(want))


def test_prefix_products_of_trs_versors_equal_sequential_clifford_products(oracle, rng):
    count = 21
    R = rotors.rotation_between(_unit(rng.standard_normal((count, 3))), _unit(rng.standard_normal((count, 3))))
    steps = rotors.trs_versor(rng.uniform(-0.5, 0.5, (count, 3)), R, rng.uniform(0.8, 1.25, count))
    running = oracle.mv(steps[0])
    want = [running.value]
    for step in steps[1:]:
        running = oracle.mv(step) * running
        want.append(running.value)
    # TRS versors are not unit rotors: compare up to the positive scale renormalisation removes.
    got = rotors.prefix_products(steps)
    want = np.array(want)
    ratio = np.einsum("ki,ki->k", got, want) / np.einsum("ki,ki->k", got, got)
    assert np.all(ratio > 0) and _close(got * ratio[:, None], want, 1e-10)


def test_versor_matrix_applied_to_up_x_equals_clifford_sandwich(oracle, rng):
    centres, x = _points(rng), _points(rng)
    R = rotors.rotation_between(_unit(rng.standard_normal((BATCH, 3))), _unit(rng.standard_normal((BATCH, 3))))
    Z = rotors.trs_versor(centres, R, rng.uniform(0.05, 5.0, BATCH))
    vectors = GRADES == 1
    got = np.einsum("kij,kj->ki", rotors.versor_matrix(Z), conformal.up(x)[:, vectors])
    want = np.array([(oracle.mv(z) * oracle.point(p) * ~oracle.mv(z)).value for z, p in zip(Z, x)])
    assert _close(got, want[:, vectors]) and np.max(np.abs(want[:, ~vectors])) <= 1e-9 * np.max(np.abs(want))
