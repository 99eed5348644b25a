"""Ring frames carried along circle surfaces by TRS rotations (paper section 11), for rows of rings
of any number of surfaces: the one transported frame of the mesher and of the tolerance plan.

The TRS rotor from one ring's circle to the next fixes its translation and dilation by the two
circles' centres and radii; only its rotation, the smallest one between their planes,
accumulates. So ring k's in-plane axis is u_k = (R_k ... R_1 R_0) e1, R_0 the smallest rotation
from e3 to the first ring's normal. The rotations are Euclidean rotors (blades 1, e12, e13, e23),
kept as four rows (4, R) rather than (R, 32) multivectors, and composed by a segmented log-depth
scan (Hillis-Steele): about log2(K) batched products for surfaces of K rings, each result
carrying the rounding of only log2(K) products. Every product sums the terms of the algebra's
geometric product (``products.row_product``) in its order, so a surface's axes are the same
bits whether it is transported alone or among many.

For a closed loop the rotation accumulated around it (its holonomy) is spread evenly along the
loop's parameter, so its last ring's axes equal its first's.
"""

from __future__ import annotations

import numpy as np

from cgamesh.geometry.algebra import products, rotors
from cgamesh.geometry.algebra.layout import REVERSE_SIGN, grade_indices

ROTOR = rotors.EUCLIDEAN_ROTOR_BLADES  # 1, e12, e13, e23
_ROTOR_REVERSE = REVERSE_SIGN[list(ROTOR)][:, None]
E3 = (0.0, 0.0, 1.0)

# Products skip the blades an operand never carries (e4 and e5 of a Euclidean vector, every
# blade but e1 of e1): their terms are exact zeros, and a sum from zero of finite terms is the
# same float with or without them.
_EUCLIDEAN_VECTOR = products.Blades(int(b) for b in grade_indices(1)[:3])  # e1, e2, e3
_E1 = products.Blades((int(grade_indices(1)[0]),))
_E1_ROW = np.ones((1, 1))


def rotation_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotations taking unit vectors a to b (R, 3), as rotor rows (4, R):
    (1 + b a) / |1 + b a| (``rotors.rotation_between``, its half turn where b = -a)."""
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
    """Running products R_k ... R_0 of rotor rows (4, R) within each surface (``local`` (R,): each
    row's index within its surface, surfaces one after another): row k combines with row
    k - shift only when that lies in its surface. Unit rotors stay unit to rounding and are
    renormalised once, at the end (``rotors.prefix_products(..., unit=True)``)."""
    acc = np.array(steps, dtype=np.float64)
    shift = 1
    longest = int(local.max()) + 1 if len(local) else 0
    while shift < longest:
        # every row times the one shift before it, kept where that lies in its surface: whole
        # contiguous slices instead of gathers of the rows that combine
        np.copyto(acc[:, shift:], _geometric(acc[:, shift:], acc[:, :-shift]), where=local[shift:] >= shift)
        shift *= 2
    norm_sq = products.row_product("geometric", acc, acc * _ROTOR_REVERSE, ROTOR, ROTOR, (0,))[1][0]
    return acc / np.sqrt(norm_sq)


def _apply_to_e1(rotor: np.ndarray) -> np.ndarray:
    """R e1 ~R (R, 3) of rotor rows (4, R)."""
    blades, rows = products.row_product("geometric", rotor, _E1_ROW, ROTOR, _E1, (1, 3))
    _, moved = products.row_product("geometric", rows, rotor * _ROTOR_REVERSE,
                                    products.Blades(int(b) for b in blades), ROTOR, (1,))
    # laid out (3, R) in memory, as a column gather of (R, 32) multivectors lays it out: the
    # caller's einsum sums a row in an order that depends on the layout
    return moved[:3].T


def transported_axes(normal: np.ndarray, local: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """In-plane unit axes u, v (R, 3) of rings with unit normals (R, 3); ``local`` (R,) each
    ring's index within its surface (surfaces one after another, each from index 0)."""
    previous = np.empty_like(normal)  # the ring before each ring, e3 before a surface's first
    previous[1:] = normal[:-1]
    previous[local == 0] = E3
    accumulated = segmented_prefix(rotation_rows(previous, normal), local)
    u = _apply_to_e1(accumulated)
    u -= np.einsum("ki,ki->k", u, normal)[:, None] * normal
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    return u, np.cross(normal, u)


def holonomy(u: np.ndarray, normal: np.ndarray, first: np.ndarray, last: np.ndarray) -> np.ndarray:
    """Signed angles (L,) about the first ring's normal from the first to the last transported
    axis u of loops whose rings are rows ``first`` .. ``last`` (L,) of u and normal (R, 3)."""
    # loop by loop (there are few): np.dot's sums, which the angle's last bits follow
    return np.array([np.arctan2(np.dot(np.cross(u[a], u[b]), normal[a]), np.dot(u[a], u[b]))
                     for a, b in zip(first, last)], dtype=np.float64)


def close_loops(u: np.ndarray, v: np.ndarray, normal: np.ndarray, t: np.ndarray, first: np.ndarray,
                count: np.ndarray) -> None:
    """Spread each closed loop's holonomy evenly along its parameter, in place: loops of
    ``count`` (L,) rings from row ``first`` (L,) of u, v, normal (R, 3) at parameters t (R,), so
    each loop's last axes equal its first."""
    if not len(first):
        return
    last = first + count - 1
    twist = holonomy(u, normal, first, last)
    rows = np.repeat(first, count) + (np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count))
    loop = np.repeat(np.arange(len(first)), count)
    angle = -twist[loop] * (t[rows] - t[first][loop]) / (t[last] - t[first])[loop]
    turned = np.cos(angle)[:, None] * u[rows] + np.sin(angle)[:, None] * v[rows]
    u[rows] = turned
    v[rows] = np.cross(normal[rows], turned)


def transported_frames(normal: np.ndarray, closed: bool, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """In-plane unit axes u, v (K, 3) of the K rings of one surface at parameters t (K,): the
    rows of a single surface."""
    u, v = transported_axes(normal, np.arange(len(normal)))
    if closed:
        close_loops(u, v, normal, t, np.array([0]), np.array([len(normal)]))
    return u, v
