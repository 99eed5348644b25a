"""Conformal versors for TRS (translation, rotation, scaling) maps, batched as (..., 32) arrays.

A TRS rotor Z = T D R takes the unit circle in the e1e2 plane to any circle (paper section
11): R turns e3 into the circle's normal, D scales by its radius, T moves the origin to its
centre. Sandwiching a point, Z up(x) ~Z is up(c + r R x ~R) up to weight, so a TRS versor
acting on points is a similarity x -> c + r Rot x; ``versor_matrix`` gives it as the 5x5
matrix it is on vectors.
"""

from __future__ import annotations

import numpy as np

from cgamesh.geometry.algebra import products
from cgamesh.geometry.algebra.conformal import EUCLIDEAN, N_0, N_INF, vector
from cgamesh.geometry.algebra.layout import BLADE_COUNT, blade_index, grade_indices

_E12, _E13, _E23 = blade_index("e12"), blade_index("e13"), blade_index("e23")
_VECTORS = grade_indices(1)
_ROTOR_GRADES = (0, 2, 4)
# A rotation of Euclidean space has only these blades: products of such rotors stay in them.
EUCLIDEAN_ROTOR_BLADES = products.Blades(blade_index(name) for name in ("1", "e12", "e13", "e23"))
_E0 = products.outer(N_INF, N_0, (1,), (1,))  # n_inf ^ n_0 (= e4 e5 = e45)


def _scalar(values: np.ndarray) -> np.ndarray:
    out = np.zeros(np.shape(values) + (BLADE_COUNT,))
    out[..., 0] = values
    return out


def rotation_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotation rotor taking unit vectors a to b, each (..., 3) -> (..., 32).

    R = (1 + b a) / |1 + b a|. For b = -a any half turn works; the axis is then a unit
    vector perpendicular to a, chosen deterministically. a and b broadcast against each other
    (one fixed vector against a batch, as the first ring of a tube is carried from e3).
    """
    a, b = np.broadcast_arrays(np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64))
    shape = a.shape[:-1]
    a, b = a.reshape(-1, 3), b.reshape(-1, 3)  # one vector alone too: the half turns are set by mask
    rotor = _scalar(np.ones(a.shape[:-1])) + products.geometric(vector(b), vector(a), (1,), (1,), (0, 2))
    norm = np.sqrt(rotor[..., 0] ** 2 + rotor[..., _E12] ** 2 + rotor[..., _E13] ** 2 + rotor[..., _E23] ** 2)
    opposite = norm < 1e-8
    if np.any(opposite):
        from cgamesh.geometry.objects import perpendicular_unit

        axis = perpendicular_unit(a[opposite])
        # A half turn about an axis k is the rotor -I3 k = the bivector dual to k in 3D.
        half_turn = np.zeros(axis.shape[:-1] + (BLADE_COUNT,))
        half_turn[..., _E23] = -axis[..., 0]
        half_turn[..., _E13] = axis[..., 1]
        half_turn[..., _E12] = -axis[..., 2]
        rotor[opposite] = half_turn
        norm[opposite] = 1.0
    return (rotor / norm[..., None]).reshape(shape + (BLADE_COUNT,))


def translator(t: np.ndarray) -> np.ndarray:
    """T = 1 + n_inf t / 2, moving points by t (..., 3)."""
    t = np.asarray(t, dtype=np.float64)
    return _scalar(np.ones(t.shape[:-1])) + 0.5 * products.geometric(N_INF, vector(t), (1,), (1,), (2,))


def dilator(scale: np.ndarray) -> np.ndarray:
    """D = cosh(l/2) - sinh(l/2) n_inf ^ n_0 with l = ln(scale): x -> scale x about the origin.

    Built from the logarithm of the scale, so a scale change of 1e-12 is still a scale
    change (a generator that treats small changes as none lets rings drift off their circles).
    """
    half_log = 0.5 * np.log(np.asarray(scale, dtype=np.float64))
    return _scalar(np.cosh(half_log)) - np.sinh(half_log)[..., None] * _E0


def trs_versor(centre: np.ndarray, rotor: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """Z = T(centre) D(scale) R: the unit-circle-to-circle map of paper section 11."""
    dilated = products.geometric(dilator(scale), rotor, (0, 2), _ROTOR_GRADES, _ROTOR_GRADES)
    return products.geometric(translator(centre), dilated, (0, 2), _ROTOR_GRADES, _ROTOR_GRADES)


def renormalise(rotor: np.ndarray, grades: tuple[int, ...] = _ROTOR_GRADES) -> np.ndarray:
    """R / sqrt(<R ~R>_0), removing the rounding that products accumulate."""
    norm_sq = products.geometric(rotor, products.reverse(rotor), grades, grades, (0,))[..., 0]
    return rotor / np.sqrt(norm_sq)[..., None]


def prefix_products(rotors: np.ndarray, grades: tuple[int, ...] = _ROTOR_GRADES, unit: bool = False) -> np.ndarray:
    """Inclusive products P_k = R_k R_{k-1} ... R_0 of rotors (K, 32), later factors on the left.

    A log-depth scan (Hillis-Steele): about log2(K) batched products instead of K sequential
    ones, and each result carries the rounding of only log2(K) products. ``grades``: the
    grades (or ``products.Blades``) the rotors and their products carry
    (``EUCLIDEAN_ROTOR_BLADES`` for rotations of Euclidean space). Products of versors that
    scale are renormalised at every level, so their size stays bounded; ``unit`` rotors
    (R ~R = 1) stay unit to rounding and are renormalised once, at the end.
    """
    acc = np.array(rotors, dtype=np.float64)
    shift = 1
    while shift < len(acc):
        acc[shift:] = products.geometric(acc[shift:], acc[:-shift], grades, grades, grades)
        if not unit:
            acc = renormalise(acc, grades)
        shift *= 2
    return renormalise(acc, grades) if unit else acc


def apply_to_euclidean(rotor: np.ndarray, x: np.ndarray) -> np.ndarray:
    """R x ~R for Euclidean rotation rotors (..., 32) (grades 0, 2) and vectors (..., 3)."""
    moved = products.geometric(
        products.geometric(rotor, vector(x), EUCLIDEAN_ROTOR_BLADES, (1,), (1, 3)), products.reverse(rotor),
        (1, 3), EUCLIDEAN_ROTOR_BLADES, (1,),
    )
    return moved[..., EUCLIDEAN]


def versor_matrix(versor: np.ndarray) -> np.ndarray:
    """(..., 5, 5) matrix M with (V X ~V)_i = sum_j M_ij X_j on the vector coefficients."""
    basis = np.eye(BLADE_COUNT)[_VECTORS]  # (5, 32)
    images = products.geometric(
        products.geometric(versor[..., None, :], basis, _ROTOR_GRADES, (1,), (1, 3, 5)),
        products.reverse(versor)[..., None, :], (1, 3, 5), _ROTOR_GRADES, (1,),
    )
    return np.swapaxes(images[..., _VECTORS], -1, -2)
