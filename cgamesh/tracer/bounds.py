"""Bounding spheres of evolved surfaces (paper section 5.1.1) and ray-sphere spans.

Each intermediate object has a sphere: for a circle C the sphere S = I5 C (C ^ n_inf) of which
C is a great circle, for a point pair P the sphere with P as a diameter, whose dual is
P (P ^ n_inf) (a vector). The spheres are merged one after another by the two-sphere
algorithm of the paper (after [18]), written here with dual spheres sigma (sigma . n_inf = -1,
X inside iff X . sigma > 0):

1. L = sigma_1 ^ sigma_2 ^ n_inf, the line from centre 1 to centre 2;
2. A_1: the first point of L v S_1 (eq. 5), on S_1 away from S_2; B_2: the second point of
   L v S_2, on S_2 away from S_1;
3. if B_2 is inside S_1, S_1 encloses S_2; if A_1 is inside S_2, S_2 encloses S_1;
4. else the sphere with diameter A_1 B_2: sigma = (A_1 + B_2 + (A_1 . B_2) n_inf) / 2.
   (The paper writes (A_1 + B_2) I5 / 2; with these sign conventions that vector squares to
   -r^2, the imaginary sphere of the same centre and radius; the n_inf term makes it real.)

Concentric spheres have no line through their centres; the larger one encloses the other.
The sampled objects only bound the surface at the samples; the result is grown by the
largest movement of the objects between neighbouring samples.
"""

from __future__ import annotations

import numpy as np

from cgamesh.geometry.algebra.conformal import N_INF, up, weight
from cgamesh.tracer import cga
from cgamesh.tracer.rays import Rays


def object_duals(blades: np.ndarray, grade: int) -> np.ndarray:
    """Dual spheres (K, 32), normalised to sigma . n_inf = -1, through circles or point pairs (K, 32).

    Circles: the dual of I5 C (C ^ n_inf), i.e. -C (C ^ n_inf); point pairs: P (P ^ n_inf).
    Both are vectors; the sign is fixed by the normalisation.
    """
    carrier = cga.outer(blades, N_INF, (grade,), (1,))
    sigma = cga.product(blades, carrier, (grade,), (grade + 1,), (1,))
    return sigma / weight(sigma)[..., None]


def _points_of(line: np.ndarray, sigma: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """First and second points (3,) of the line meeting the sphere with dual sigma."""
    s = cga.product(sigma, cga.I5, (1,), (5,), (4,))
    a, b, _ = cga.split_point_pair(cga.meet(line, cga.normalise_sphere(s), 3, 4))
    return a, b


def enclose_two(sigma_1: np.ndarray, sigma_2: np.ndarray) -> np.ndarray:
    """The two-sphere bounding algorithm on dual spheres (32,) normalised to sigma . n_inf = -1."""
    c1, r1 = cga.sphere_centre_radius(cga.product(sigma_1, cga.I5, (1,), (5,), (4,)))
    c2, r2 = cga.sphere_centre_radius(cga.product(sigma_2, cga.I5, (1,), (5,), (4,)))
    gap = np.linalg.norm(c2 - c1)
    if gap <= 1e-12 * max(r1, r2, 1e-300):
        return sigma_1 if r1 >= r2 else sigma_2
    line = cga.line_through(sigma_1, sigma_2)  # the n_inf parts of sigma vanish against n_inf
    a1, _ = _points_of(line, sigma_1)
    _, b2 = _points_of(line, sigma_2)
    big_a1, big_b2 = up(a1), up(b2)
    if cga.scalar_product(big_b2, sigma_1, 1) >= 0.0:
        return sigma_1
    if cga.scalar_product(big_a1, sigma_2, 1) >= 0.0:
        return sigma_2
    return 0.5 * (big_a1 + big_b2 + cga.scalar_product(big_a1, big_b2, 1) * N_INF)


def enclose(sigmas: np.ndarray) -> np.ndarray:
    """A dual sphere (32,) enclosing all the dual spheres (K, 32), by successive two-sphere steps."""
    result = sigmas[0]
    for sigma in sigmas[1:]:
        result = enclose_two(result, sigma)
    return result


def dual_centre_radius(sigma: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centre (..., 3) and radius (...) of normalised dual spheres."""
    s = cga.product(sigma, cga.I5, (1,), (5,), (4,))
    return cga.sphere_centre_radius(s)


def meets_sphere(rays: Rays, centre: np.ndarray, radius: float) -> np.ndarray:
    """Whether each ray's line meets the sphere: (L v S)^2 >= 0 (eq. 3, section 4.1.2), (N,) bool."""
    meet = cga.meet(rays.lines, cga.sphere(np.asarray(centre, dtype=np.float64), radius), 3, 4)
    return cga.square(meet, 2) >= 0.0


def spans(rays: Rays, centres: np.ndarray, radii: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Entry and exit distances (N, P) of the rays through P spheres (NaN where a line misses).

    The Euclidean form of the same intersection (the chord about the centre's projection
    onto the ray), for culling many spheres at once: cheaper than P meets and point-pair
    read-outs, and only ever used to skip work.
    """
    offset = centres[None, :, :] - rays.origins[:, None, :]
    along = np.einsum("npi,ni->np", offset, rays.directions)
    gap = np.einsum("npi,npi->np", offset, offset) - along * along
    with np.errstate(invalid="ignore"):
        half = np.sqrt(radii[None, :] ** 2 - gap)
    return along - half, along + half
