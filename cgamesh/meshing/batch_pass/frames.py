"""Ring axes of many open chains, carried from ring to ring by rotation rotors, blade-major.

``circles.transported_frames`` for every chain at once: each ring's smallest rotation from the
previous ring's plane (from e3 at a chain's first ring), composed along the chain by a
segmented log-depth scan, applied to e1. The rotors are Euclidean (blades 1, e12, e13, e23)
and are kept as four rows (4, K) instead of (K, 32) multivectors; every product sums the same
terms in the same order as ``rotors.rotation_between``, ``rotors.prefix_products``,
``rotors.renormalise`` and ``rotors.apply_to_euclidean`` do, so the axes have the per-chain
path's bits.
"""

from __future__ import annotations

import numpy as np

from cgamesh.geometry.algebra import products, rotors
from cgamesh.geometry.algebra.layout import REVERSE_SIGN, grade_indices

ROTOR = rotors.EUCLIDEAN_ROTOR_BLADES  # 1, e12, e13, e23
_ROTOR_REVERSE = REVERSE_SIGN[list(ROTOR)][:, None]


# Products skip the blades an operand never carries (e4 and e5 of a Euclidean vector, every
# blade but e1 of e1): their terms are exact zeros, and a sum from zero of finite terms is the
# same float with or without them, so the rows keep their bits with fewer terms.
_EUCLIDEAN_VECTOR = products.Blades(int(b) for b in grade_indices(1)[:3])  # e1, e2, e3
_E1 = products.Blades((int(grade_indices(1)[0]),))
_E1_ROW = np.ones((1, 1))


def rotation_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``rotors.rotation_between(a, b)`` for unit vectors a, b (K, 3), as rotor rows (4, K)."""
    blades, rows = products.row_product("geometric", np.ascontiguousarray(b.T), np.ascontiguousarray(a.T),
                                        _EUCLIDEAN_VECTOR, _EUCLIDEAN_VECTOR, ROTOR)
    rotor = products.admitted_rows(blades, rows, ROTOR)
    rotor[0] += 1.0  # 1 + b a (every other blade as the multivector sum makes it: 0.0 + x)
    rotor[1:] += 0.0
    norm = np.sqrt(rotor[0] ** 2 + rotor[1] ** 2 + rotor[2] ** 2 + rotor[3] ** 2)
    opposite = norm < 1e-8
    if np.any(opposite):
        half_turn = rotors.rotation_between(a[opposite], b[opposite])  # the chosen half turn, unit
        rotor[:, opposite] = half_turn[:, list(ROTOR)].T
        norm[opposite] = 1.0
    return rotor / norm


def _geometric(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return products.row_product("geometric", a, b, ROTOR, ROTOR, ROTOR)[1]


def segmented_prefix(steps: np.ndarray, local: np.ndarray) -> np.ndarray:
    """``rotors.prefix_products(steps, ROTOR, unit=True)`` within each chain, on rotor rows
    (4, K): element k combines with k - shift only when that lies in its chain, the same
    products in the same order; renormalised once at the end."""
    acc = np.array(steps, dtype=np.float64)
    shift = 1
    longest = int(local.max()) + 1 if len(local) else 0
    while shift < longest:
        # every element times the one shift before it, kept where that lies in its chain: whole
        # contiguous slices (the same products) instead of gathers of the elements that combine
        np.copyto(acc[:, shift:], _geometric(acc[:, shift:], acc[:, :-shift]), where=local[shift:] >= shift)
        shift *= 2
    norm_sq = products.row_product("geometric", acc, acc * _ROTOR_REVERSE, ROTOR, ROTOR, (0,))[1][0]
    return acc / np.sqrt(norm_sq)


def apply_to_e1(rotor: np.ndarray) -> np.ndarray:
    """``rotors.apply_to_euclidean(rotor, e1)``: R e1 ~R (K, 3) of rotor rows (4, K)."""
    blades, rows = products.row_product("geometric", rotor, _E1_ROW, ROTOR, _E1, (1, 3))
    _, moved = products.row_product("geometric", rows, rotor * _ROTOR_REVERSE,
                                    products.Blades(int(b) for b in blades), ROTOR, (1,))
    # laid out as ``rotors.apply_to_euclidean``'s column gather lays it out, (3, K) in memory:
    # the caller's einsum sums a row in an order that depends on the layout
    return moved[:3].T


def transported_axes(normal: np.ndarray, ring_local: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """In-plane unit axes u, v (K, 3) of rings with unit normals (K, 3), ring_local (K,) the
    ring's index within its chain (chains one after another)."""
    previous = np.empty_like(normal)  # the ring before each ring, e3 before a chain's first
    previous[1:] = normal[:-1]
    previous[ring_local == 0] = (0.0, 0.0, 1.0)
    accumulated = segmented_prefix(rotation_rows(previous, normal), ring_local)
    u = apply_to_e1(accumulated)
    u -= np.einsum("ki,ki->k", u, normal)[:, None] * normal
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    return u, np.cross(normal, u)
