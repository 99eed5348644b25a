"""The CGA constructions of the tracer, batched over (..., 32) arrays (paper sections 2-4).

Conventions (those of the scene format and clifford.g3c): n_inf = e4 + e5, n_0 = (e5 - e4)/2,
I5 = e12345 with I5^2 = -1, and the dual is X* = X I5^-1.

- A line through points a, b is up(a) ^ up(b) ^ n_inf = (a ^ d) ^ n_inf + d ^ e45 with
  d = b - a; normalised (L^2 = 1) its e145, e245, e345 coefficients are its unit direction.
  Two normalised lines through one point have <L1 L2>_0 = cos of the angle between them.
- A sphere of centre c and radius r has the dual sigma = up(c) - r^2 n_inf / 2 (sigma^2 = r^2,
  sigma . n_inf = -1) and is the 4-blade S = sigma I5, normalised as in eq. 6 (S* . n_inf = -1).
  A point X is inside when X . sigma > 0.
- A plane of unit normal n through p has the dual pi = n + (n . p) n_inf; Phi = pi I5 has
  Phi^2 = -1, the normalisation under which Phi L Phi reflects a line (section 4.2).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from cgamesh.geometry.algebra import products
from cgamesh.geometry.algebra.conformal import EUCLIDEAN, N_INF, down, up, weight
from cgamesh.geometry.algebra.layout import BLADE_COUNT, GRADES, blade_index

I5 = products.PSEUDOSCALAR
SCALAR = np.zeros(BLADE_COUNT)
SCALAR[0] = 1.0
DIMENSION = 5
# Unit direction of a normalised line, and the coefficients of (a ^ d) ^ n_inf.
LINE_DIRECTION = np.array([blade_index(f"e{i}45") for i in (1, 2, 3)])
_PAIRS = ((0, 1), (0, 2), (1, 2))
_LINE_MOMENT_4 = np.array([blade_index(f"e{i + 1}{j + 1}4") for i, j in _PAIRS])
_LINE_MOMENT_5 = np.array([blade_index(f"e{i + 1}{j + 1}5") for i, j in _PAIRS])
# Plane meets (eq. 4): x ^ n_inf - n_inf ^ n_0 scaled by lambda.
_FLAT_POINT_X = np.array([blade_index(f"e{i}4") for i in (1, 2, 3)])
_FLAT_POINT_W = blade_index("e45")
# Where the blades of one grade sit, for scalar products of k-vectors without products.
GRADE_BLADES = {g: np.flatnonzero(GRADES == g) for g in range(DIMENSION + 1)}


_KINDS = {"geometric": products.geometric, "outer": products.outer, "inner": products.inner}


@lru_cache(maxsize=None)
def _tensor(kind: str, grades_a: tuple, grades_b: tuple, grades_out: tuple):
    """Blades of each operand and of the result, and the product as a (ka, kb, ko) tensor."""
    basis = np.eye(BLADE_COUNT)
    blades_a = np.flatnonzero(np.isin(GRADES, grades_a))
    blades_b = np.flatnonzero(np.isin(GRADES, grades_b))
    if kind == "geometric":
        table = products.geometric(basis[blades_a][:, None, :], basis[blades_b][None, :, :], grades_a, grades_b,
                                   grades_out)
    else:
        table = _KINDS[kind](basis[blades_a][:, None, :], basis[blades_b][None, :, :], grades_a, grades_b)
        table = np.where(np.isin(GRADES, grades_out), table, 0.0)
    blades_out = np.flatnonzero(np.any(table != 0.0, axis=(0, 1)))
    return blades_a, blades_b, blades_out, np.ascontiguousarray(table[..., blades_out])


def product(a: np.ndarray, b: np.ndarray, grades_a, grades_b, grades_out=(0, 1, 2, 3, 4, 5),
            kind: str = "geometric") -> np.ndarray:
    """The same product as ``cgamesh.geometry.algebra.products`` (kind geometric, outer or inner), faster
    on large batches: one operand times the product tensor is a matrix product, then the other
    operand is contracted in. a, b: (N, 32) or (32,)."""
    blades_a, blades_b, blades_out, tensor = _tensor(kind, tuple(sorted(grades_a)), tuple(sorted(grades_b)),
                                                     tuple(sorted(grades_out)))
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    ka, kb, ko = tensor.shape
    if ko == 0:
        return np.zeros(np.broadcast_shapes(a.shape[:-1], b.shape[:-1]) + (BLADE_COUNT,))
    if a.ndim == 1 and b.ndim == 1:
        values = np.einsum("i,j,ijo->o", a[blades_a], b[blades_b], tensor)
    elif b.ndim == 1:
        values = a[..., blades_a] @ np.einsum("ijo,j->io", tensor, b[blades_b])
    elif a.ndim == 1:
        values = b[..., blades_b] @ np.einsum("ijo,i->jo", tensor, a[blades_a])
    else:
        shape = np.broadcast_shapes(a.shape[:-1], b.shape[:-1])
        left = np.broadcast_to(a[..., blades_a], shape + (ka,)).reshape(-1, ka)
        right = np.broadcast_to(b[..., blades_b], shape + (kb,)).reshape(-1, kb)
        partial = (left @ tensor.reshape(ka, kb * ko)).reshape(-1, kb, ko)
        values = np.einsum("njo,nj->no", partial, right).reshape(shape + (ko,))
    out = np.zeros(values.shape[:-1] + (BLADE_COUNT,))
    out[..., blades_out] = values
    return out


def outer(a: np.ndarray, b: np.ndarray, grades_a, grades_b) -> np.ndarray:
    """a ^ b, as ``products.outer``."""
    return product(a, b, grades_a, grades_b, (0, 1, 2, 3, 4, 5), "outer")


def inner(a: np.ndarray, b: np.ndarray, grades_a, grades_b) -> np.ndarray:
    """a . b (Hestenes), as ``products.inner``."""
    return product(a, b, grades_a, grades_b, (0, 1, 2, 3, 4, 5), "inner")


def meet(x: np.ndarray, y: np.ndarray, grade_x: int, grade_y: int) -> np.ndarray:
    """X v Y = <X Y>_{2n - r - s} I5 over the whole 5D space (eq. 3)."""
    g = 2 * DIMENSION - grade_x - grade_y
    return product(product(x, y, (grade_x,), (grade_y,), (g,)), I5, (g,), (5,), (DIMENSION - g,))


def metric_square(x: np.ndarray, grade: int) -> np.ndarray:
    """x^2 (...) for vectors or 4-vectors x (..., 32), whose squares are scalars in G(4,1)."""
    return scalar_product(x, x, grade)


def square(x: np.ndarray, grade: int) -> np.ndarray:
    """The scalar part of x x for a k-vector x (...)."""
    return scalar_product(x, x, grade)


@lru_cache(maxsize=None)
def scalar_signs(grade: int) -> np.ndarray:
    """<e_I e_J>_0 is zero unless I = J: the signs of the squares of one grade's blades."""
    basis = np.eye(BLADE_COUNT)[GRADE_BLADES[grade]]
    return products.geometric(basis, basis, (grade,), (grade,), (0,))[:, 0]


def scalar_product(x: np.ndarray, y: np.ndarray, grade: int) -> np.ndarray:
    """<x y>_0 (...) of two k-vectors: sum_I sign_I x_I y_I."""
    blades = GRADE_BLADES[grade]
    return np.einsum("...i,...i,i->...", x[..., blades], y[..., blades], scalar_signs(grade))


# --- lines ---------------------------------------------------------------------------------------

def line(origin: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """Normalised lines up(o) ^ up(o + d) ^ n_inf (..., 32) for origins and unit directions (..., 3).

    Written out as (o ^ d) ^ n_inf + d ^ e45, the same blade as the wedge of the two points.
    """
    o = np.asarray(origin, dtype=np.float64)
    d = np.asarray(direction, dtype=np.float64)
    shape = np.broadcast_shapes(o.shape, d.shape)
    out = np.zeros(shape[:-1] + (BLADE_COUNT,))
    for k, (i, j) in enumerate(_PAIRS):
        moment = o[..., i] * d[..., j] - o[..., j] * d[..., i]
        out[..., _LINE_MOMENT_4[k]] = moment
        out[..., _LINE_MOMENT_5[k]] = moment
    out[..., LINE_DIRECTION] = d
    return out


def line_through(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """X ^ Y ^ n_inf for conformal points (..., 32), oriented from X to Y, not normalised."""
    return outer(outer(x, y, (1,), (1,)), N_INF, (2,), (1,))


def normalise_line(lines: np.ndarray) -> np.ndarray:
    """L / sqrt(L^2); lines of zero size stay zero."""
    size = np.sqrt(np.maximum(square(lines, 3), 0.0))
    return lines / np.where(size > 0.0, size, 1.0)[..., None]


def line_direction(lines: np.ndarray) -> np.ndarray:
    """Unit Euclidean directions (..., 3) of lines (..., 32), any normalisation."""
    d = np.asarray(lines)[..., LINE_DIRECTION]
    size = np.linalg.norm(d, axis=-1, keepdims=True)
    return d / np.where(size > 0.0, size, 1.0)


# --- spheres and planes --------------------------------------------------------------------------

def dual_sphere(centre: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """sigma = up(c) - r^2 n_inf / 2 (..., 32)."""
    r = np.asarray(radius, dtype=np.float64)
    return up(centre) - 0.5 * (r * r)[..., None] * N_INF


def sphere(centre: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """Spheres S = sigma I5 (..., 32), normalised as in eq. 6."""
    return normalise_sphere(product(dual_sphere(centre, radius), I5, (1,), (5,), (4,)))


def sphere_dual(spheres: np.ndarray) -> np.ndarray:
    """S* = S I5^-1 (vectors), the dual sphere of 4-blade spheres."""
    return product(spheres, products.PSEUDOSCALAR_INVERSE, (4,), (5,), (1,))


def normalise_sphere(spheres: np.ndarray) -> np.ndarray:
    """S -> -S / (S* . n_inf) (eq. 6), so that S* . n_inf = -1."""
    return spheres / weight(sphere_dual(spheres))[..., None]


def sphere_centre_radius(spheres: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centre (..., 3) and radius (...) of real 4-blade spheres."""
    sigma = sphere_dual(spheres)
    sigma = sigma / weight(sigma)[..., None]
    return down(sigma), np.sqrt(np.maximum(metric_square(sigma, 1), 0.0))


def plane(point: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Planes Phi = pi I5 (..., 32), pi = n + (n . p) n_inf with n the unit normal; Phi^2 = -1."""
    n = np.asarray(normal, dtype=np.float64)
    n = n / np.linalg.norm(n, axis=-1, keepdims=True)
    pi = np.zeros(n.shape[:-1] + (BLADE_COUNT,))
    pi[..., EUCLIDEAN] = n
    pi = pi + np.einsum("...i,...i->...", n, np.asarray(point, dtype=np.float64))[..., None] * N_INF
    return product(pi, I5, (1,), (5,), (4,))


def normalise_plane(planes: np.ndarray) -> np.ndarray:
    """Phi / sqrt(-Phi^2), so that Phi^2 = -1."""
    return planes / np.sqrt(-square(planes, 4))[..., None]


def plane_point(flat_points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The point x (..., 3) of L v Phi = lambda (x ^ n_inf - n_inf ^ n_0), and lambda (...) (eq. 4).

    lambda is zero where the line is parallel to the plane; x is then NaN.
    """
    lam = -flat_points[..., _FLAT_POINT_W]
    with np.errstate(divide="ignore", invalid="ignore"):
        return flat_points[..., _FLAT_POINT_X] / lam[..., None], lam


def reflect_in_plane(lines: np.ndarray, planes: np.ndarray) -> np.ndarray:
    """Phi L Phi for planes with Phi^2 = -1: the reflected line, correctly oriented (section 4.2)."""
    return product(product(planes, lines, (4,), (3,), (1, 3, 5)), planes,
                              (1, 3, 5), (4,), (3,))


# --- point pairs ---------------------------------------------------------------------------------

def split_point_pair(pairs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The points A, B (..., 3) of real point pairs F = A ^ B (eq. 5), and F^2 (...).

    A ~ (1 - F / sqrt(F^2)) (F . n_inf), B ~ (1 + F / sqrt(F^2)) (F . n_inf). Where F^2 < 0 (no
    real points) A and B are NaN; where F^2 = 0 they coincide.
    """
    f2 = square(pairs, 2)
    root = np.sqrt(np.maximum(f2, 0.0))
    unit = pairs / np.where(root > 0.0, root, np.inf)[..., None]  # tangent: A = B = F . n_inf
    direction = inner(pairs, N_INF, (2,), (1,))
    a = product(SCALAR - unit, direction, (0, 2), (1,), (1,))
    b = product(SCALAR + unit, direction, (0, 2), (1,), (1,))
    with np.errstate(divide="ignore", invalid="ignore"):
        xa, xb = down(a), down(b)
    missing = ~(f2 >= 0.0)
    xa[missing] = np.nan
    xb[missing] = np.nan
    return xa, xb, f2
