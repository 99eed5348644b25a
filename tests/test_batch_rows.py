"""The batched pass's blade-major readout and frame transport equal the per-chain functions bit for bit.

``circle_rows.CircleRows`` (circles, rates, centre, normal, radius, Omega) against
``motor_surface.circle_blades`` / ``circle_blade_rates``, ``objects.circle_euclidean`` and the
product C dC/dt; ``frames.transported_axes`` over many chains at once against
``circles.transported_frames`` chain by chain, on normals along the axes (+-e3 included, where
the first rotation from e3 is none or a half turn), reversing between rings, and random.
Array layouts are compared too: numpy's einsum sums a row in an order that depends on them.
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
from cgamesh.meshing.batch_pass.frames import transported_axes
from cgamesh.meshing.circles import transported_frames


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


@pytest.mark.parametrize("seed", [1, 2])
def test_transported_axes_equal_the_per_chain_frames(seed):
    chains = _chains(seed)
    u, v = transported_axes(np.concatenate(chains), np.concatenate([np.arange(len(c)) for c in chains]))
    start = 0
    for normal in chains:
        expected_u, expected_v = transported_frames(normal, False, np.arange(len(normal), dtype=np.float64))
        np.testing.assert_array_equal(u[start:start + len(normal)], expected_u)
        np.testing.assert_array_equal(v[start:start + len(normal)], expected_v)
        start += len(normal)
    # the axes are a right-handed orthonormal frame in each ring's plane
    normal = np.concatenate(chains)
    np.testing.assert_allclose(np.einsum("ki,ki->k", u, normal), 0.0, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(u, axis=1), 1.0, rtol=1e-15)
    np.testing.assert_allclose(np.cross(u, v), normal, atol=1e-15)
