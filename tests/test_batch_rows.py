"""The batched pass's blade-major readout equals the per-chain functions bit for bit, and the ring
frames (``ring_frames``) are the transport their definition says.

``circle_rows.CircleRows`` (circles, rates, centre, normal, radius, Omega) against
``motor_surface.circle_blades`` / ``circle_blade_rates``, ``objects.circle_euclidean`` and the
product C dC/dt. ``ring_frames.transported_axes`` over many surfaces at once against the
definition of the transport, written independently with Rodrigues' formula: e1 turned by the
smallest rotation from e3 to the first normal, then each ring's axis turned by the smallest
rotation between consecutive normals; on normals along the axes (+-e3 included, where the first
rotation from e3 is none or a half turn), reversing between rings, and random. Array layouts are
compared too: numpy's einsum sums a row in an order that depends on them.
"""

from __future__ import annotations

import numpy as np
import pytest

from cgamesh.geometry.algebra import products
from cgamesh.geometry.algebra.layout import grade_indices
from cgamesh.geometry.motor_surface import circle_blade_rates, circle_blades
from cgamesh.geometry.motors import MotionState
from cgamesh.geometry.objects import circle_euclidean
from cgamesh.meshing.batch_pass.circle_rows import CircleRows
from cgamesh.meshing.ring_frames import transported_axes, transported_frames


def _unit(x: np.ndarray) -> np.ndarray:
    return x / np.linalg.norm(x, axis=-1, keepdims=True)


def _states(count: int, seed: int) -> MotionState:
    rng = np.random.default_rng(seed)
    normal = _unit(rng.normal(size=(count, 3)))
    axis = count // 3
    normal[:axis] = np.eye(3)[rng.integers(0, 3, axis)] * rng.choice([-1.0, 1.0], (axis, 1))
    d_normal = rng.normal(size=(count, 3))
    d_normal -= normal * np.einsum("ai,ai->a", normal, d_normal)[:, None]
    d_normal[: count // 5] = 0.0  # a ring whose plane does not turn
    centre = rng.normal(size=(count, 3)) * 10.0 ** rng.uniform(-3, 1, (count, 1))
    return MotionState(centre, normal, 10.0 ** rng.uniform(-3, 1, count), rng.normal(size=(count, 3)), d_normal,
                       rng.normal(size=count), np.ones(count))


@pytest.mark.parametrize("count", [2, 3, 64, 3000])
def test_circle_rows_equal_the_per_chain_readout(count):
    state = _states(count, count)
    blades, rates = circle_blades(state), circle_blade_rates(state)
    rows = CircleRows.of(state)
    got_blades, got_rates = rows.as_multivectors()
    np.testing.assert_array_equal(got_blades, blades)
    np.testing.assert_array_equal(got_rates, rates)
    for got, expected in zip(rows.euclidean(), circle_euclidean(blades)):
        np.testing.assert_array_equal(got, expected)
        assert got.strides == expected.strides
    omega = products.geometric(blades, rates, (3,), (3,), (2,))
    np.testing.assert_array_equal(rows.omega(), omega[:, grade_indices(2)].T)
    assert not np.any(np.delete(omega, grade_indices(2), axis=1))


def _chains(seed: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    chains = []
    for kind in range(60):
        rings = int(rng.integers(2, 150))
        walk = np.cumsum(rng.normal(size=(rings, 3)) * rng.choice([1e-3, 0.3, 2.0]), axis=0) + rng.normal(size=3)
        if kind % 5 == 1:
            walk[1] = -walk[0]  # a half turn between two rings
        if kind % 5 == 2:
            walk[0] = [0.0, 0.0, -1.0]  # the first ring a half turn from e3
        if kind % 5 == 3:
            walk[:] = [0.0, 0.0, 1.0]  # no rotation at all
        if kind % 5 == 4:
            walk[::2] = np.eye(3)[rng.integers(0, 3)]  # exact axes every other ring
        chains.append(_unit(walk))
    return chains


def _smallest_rotation(a: np.ndarray, b: np.ndarray, x: np.ndarray) -> np.ndarray:
    """x turned by the smallest rotation taking unit a to unit b (Rodrigues), about the axis
    a x b; where b = -a, the half turn about the axis ``objects.perpendicular_unit`` picks."""
    from cgamesh.geometry.objects import perpendicular_unit

    axis = np.cross(a, b)
    sine, cosine = np.linalg.norm(axis), float(np.dot(a, b))
    if sine < 1e-12:
        if cosine > 0.0:
            return x
        k = perpendicular_unit(a[None])[0]
        return 2.0 * np.dot(k, x) * k - x
    k = axis / sine
    return x * cosine + np.cross(k, x) * sine + k * np.dot(k, x) * (1.0 - cosine)


@pytest.mark.parametrize("seed", [1, 2])
def test_transported_axes_are_the_smallest_rotations_ring_to_ring(seed):
    chains = _chains(seed)
    u, v = transported_axes(np.concatenate(chains), np.concatenate([np.arange(len(c)) for c in chains]))
    start = 0
    for normal in chains:
        expected = _smallest_rotation(np.array([0.0, 0.0, 1.0]), normal[0], np.array([1.0, 0.0, 0.0]))
        for k in range(len(normal)):
            if k:
                expected = _smallest_rotation(normal[k - 1], normal[k], expected)
                expected -= np.dot(expected, normal[k]) * normal[k]
                expected /= np.linalg.norm(expected)
            np.testing.assert_allclose(u[start + k], expected, atol=1e-9)
        # a surface among many is transported as it is alone
        alone_u, alone_v = transported_frames(normal, False, np.arange(len(normal), dtype=np.float64))
        np.testing.assert_array_equal(u[start:start + len(normal)], alone_u)
        np.testing.assert_array_equal(v[start:start + len(normal)], alone_v)
        start += len(normal)
    # the axes are a right-handed orthonormal frame in each ring's plane
    normal = np.concatenate(chains)
    np.testing.assert_allclose(np.einsum("ki,ki->k", u, normal), 0.0, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(u, axis=1), 1.0, rtol=1e-15)
    np.testing.assert_allclose(np.cross(u, v), normal, atol=1e-15)


@pytest.mark.parametrize("seed", [3, 4])
def test_closed_loops_end_on_their_first_axes_with_the_twist_spread_evenly(seed):
    """Each closed loop's holonomy is spread evenly along its parameter: its last ring's axes equal
    its first's, and the turn of each ring's axis away from the open transport grows linearly in t."""
    chains = [c for c in _chains(seed) if len(c) >= 3][:20]
    for normal in chains:
        normal = np.concatenate([normal, normal[:1]])  # a loop: the last ring is the first
        t = np.concatenate([[0.0], np.sort(np.random.default_rng(seed).uniform(0.0, 3.0, len(normal) - 2)), [3.0]])
        u, v = transported_frames(normal, True, t)
        np.testing.assert_allclose(u[-1], u[0], atol=1e-9)
        np.testing.assert_allclose(v[-1], v[0], atol=1e-9)
        open_u, open_v = transported_frames(normal, False, t)
        turn = np.arctan2(np.einsum("ki,ki->k", u, open_v), np.einsum("ki,ki->k", u, open_u))
        total = turn[-1]
        np.testing.assert_allclose(np.angle(np.exp(1j * (turn - total * t / t[-1]))), 0.0, atol=1e-9)
