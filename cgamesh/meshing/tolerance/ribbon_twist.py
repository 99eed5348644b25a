"""The tolerance bound of a ribbon's quad without the tangential part of its twist.

A ribbon x(t, s) = a(t) + s d(t), d = b - a, is meshed on its (t, s) grid; over a quad of
sides h (along t) and kappa = 1 / (N - 1) (across) every point of both triangles lies within
A h^2 / 8 + B h kappa / 4 of the surface (docs/tolerance.md, "The bound for a quad"), where
B >= |x_ts| = |d'| is the twist. The triangles cut across a twisted quad by that much, but
only the twist's part normal to the surface moves them off it: a ruling that stretches
(d' along d) or slides along the path (d' along x_t) shears the quad within its tangent plane.
As for circles (docs/tolerance.md, "The twist's normal part"), each triangle is
reparametrised by the bubble of its diagonal, Phi(p) = p + h kappa gamma beta(p), which keeps
its vertices and stays within its quad while kappa |gamma_t| <= 1 and h |gamma_s| <= 1; the
map g = x(Phi) has the twist x_ts - gamma_t x_t - gamma_s x_s, and with gamma the tangential
part of d' at the quad's middle q0 (d'_T = gamma_t x_t + gamma_s d) what is left there is the
normal part,

    |N . d'| = |det(a', d, d')| / |x_t x d|,

which is zero on a flat ribbon (fig. 12's chords). Its change over the quad:
d/dt (d' - gamma_t x_t - gamma_s d) = d'' - gamma_t x_tt - gamma_s d' and
d/ds (...) = -gamma_t d' (x_ss = 0). The bounds of gamma: the component of d' along
u = x_t minus its part along d, |u| = |x_t x d| / |d|, gives |gamma_t| <= |d'| |d| / |x_t x d|;
along d, |gamma_s| <= (|d'| + |gamma_t| |x_t|) / |d|.

Per cell of the derivative sampling (cgamesh.meshing.tolerance.derivative_bounds) this needs a lower
bound of |x_t x d| over the cell and s in [0, 1] (zero where the ribbon folds: the bound is then
not used), an upper bound of |det(a', d, d')|, of |d''|, of |x_t| and a lower bound of |d|.
"""

from __future__ import annotations

import numpy as np

from cgamesh.meshing.tolerance.derivative_bounds import CellDerivatives, lengths


def ribbon_twist_terms(a: CellDerivatives, b: CellDerivatives, d: CellDerivatives, d_values: np.ndarray,
                       scale: float) -> dict:
    """Per cell (segments, cells): Nt >= |N . d'| at any point of the cell's quads (world units
    per unit t), Gt >= |gamma_t| and Gs >= |gamma_s| (per unit t) for gamma chosen at any such
    point, D2 >= |d''| (world units); inf where |x_t x d| may vanish. d_values: d at the samples
    (segments, cells + 1, 3), in the surface's frame units (world / scale), as a, b and d."""
    cells = d_values.shape[1] - 1
    delta = 1.0 / cells
    _, _, d2 = d.norms()
    # d in the cell is within rho of the middle of its two end samples: their half difference plus
    # the linear interpolation's error, (delta^2 / 8) max |d''| (the kernel is non-negative).
    centre = 0.5 * (d_values[:, :-1] + d_values[:, 1:])
    rho = 0.5 * lengths(d_values[:, 1:] - d_values[:, :-1]) + delta * delta / 8.0 * d2
    middle = lengths(centre)  # (each length and cross product below is formed once and reused)
    longest = middle + rho  # >= |d|
    shortest = np.maximum(middle - rho, 0.0)  # <= |d|
    a1, ra = a.first, lengths(a.first_radius)  # a' within ra of a1 over the cell (componentwise radii)
    e1, re = d.first, lengths(d.first_radius)
    a1_length, e1_length = lengths(a1), lengths(e1)
    speed = e1_length + re  # >= |d'|
    # x_t x d = (a' + s d') x d: at the estimates P + s Q, off by at most epsilon for s in [0, 1];
    # the least |P + s Q| over [0, 1] at the clipped foot of the perpendicular.
    p, q = np.cross(a1, centre), np.cross(e1, centre)
    epsilon = (ra + re) * longest + (a1_length + e1_length) * rho
    qq = np.sum(q * q, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.clip(np.where(qq > 0.0, -np.sum(p * q, axis=-1) / qq, 0.0), 0.0, 1.0)
    least = np.maximum(lengths(p + s[..., None] * q) - epsilon, 0.0)  # <= |x_t x d|
    # det(a', d, d') = a' . (d x d'), at the estimates a1 . (centre x e1), off by at most the rest.
    stretched = np.cross(centre, e1)
    det = (np.abs(np.sum(a1 * stretched, axis=-1))
           + ra * longest * speed + a1_length * rho * speed + a1_length * middle * re)
    _, a_first, _ = a.norms()
    _, b_first, _ = b.norms()
    along = np.maximum(a_first, b_first)  # >= |x_t| = |(1 - s) a' + s b'|
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        fold = least <= 0.0
        normal = np.where(fold, np.inf, det / least)
        gamma_t = np.where(fold, np.inf, speed * longest / least)
        gamma_s = np.where(fold | (shortest <= 0.0), np.inf, (speed + gamma_t * along) / shortest)
        # gamma = (0, d' . d / |d|^2) removes only the rulings' stretching: no fold condition, and
        # what is left, d' across d, is |d x d'| / |d|.
        across_d = lengths(stretched) + rho * speed + middle * re  # >= |d x d'|
        across = np.where(shortest > 0.0, across_d / shortest, np.inf)
        stretch = np.where(shortest > 0.0, speed / shortest, np.inf)
    return dict(Nt=scale * normal, Gt=gamma_t, Gs=gamma_s, D2=scale * d2, Nx=scale * across, Gx=stretch)


def ribbon_twist_error(terms: dict, h, across):
    """The bound of each quad's error by the bubble reparametrisation (inf where it does not apply:
    a possible fold, kappa |gamma_t| > 1 or h |gamma_s| > 1). terms: maxima over the quad's cells of
    A >= |x_tt|, B >= |d'| and those of ``ribbon_twist_terms``."""
    error = np.inf
    for stretch_only in (False, True):
        square, linear, valid = ribbon_twist_quadratic(terms, across, stretch_only)
        with np.errstate(invalid="ignore", over="ignore"):
            valid = valid & (h * (terms["Gx"] if stretch_only else terms["Gs"]) <= 1.0)
            error = np.minimum(error, np.where(valid, square * h * h + linear * h, np.inf))
    return error


def ribbon_twist_quadratic(terms: dict, across, stretch_only: bool = False):
    """(square, linear, valid): A^ h^2 / 8 + B^ h kappa / 4 + C^ kappa^2 / 8 = square h^2 + linear h
    for g = x(Phi) (docs/tolerance.md, "The twist of ribbons"), valid where kappa |gamma_t| <= 1.
    stretch_only: gamma_t = 0, removing only the twist's part along the rulings."""
    kappa = 1.0 / (np.asarray(across, dtype=float) - 1.0)
    a, b = terms["A"], terms["B"]
    if stretch_only:
        gt, gs, left = np.zeros_like(terms["Gx"]), terms["Gx"], terms["Nx"]
    else:
        gt, gs, left = terms["Gt"], terms["Gs"], terms["Nt"]
    with np.errstate(invalid="ignore", over="ignore"):
        reach = kappa * gt  # kappa |gamma_t|, computed once (the same bits as in each term)
        lift = 1.0 + reach
        a_hat = lift ** 2 * a + 2.0 * lift * kappa * gs * b
        # B^ = b0 + h b1: the normal twist at q0 and the residual's change over the quad (half the
        # quad each way), plus what Phi's slopes add; C^ = h c1 + h^2 c2.
        b0 = left + 1.5 * kappa * gt * b
        b1 = (0.5 * terms["D2"] + 0.5 * gt * a + 1.5 * gs * b + 2.0 * kappa * gt * gs * b + lift * gt * a)
        c1 = 2.0 * gt * b
        c2 = gt * gt * a + 2.0 * gt * gs * b
        square = a_hat / 8.0 + kappa / 4.0 * b1 + kappa * kappa / 8.0 * c2
        linear = kappa / 4.0 * b0 + kappa * kappa / 8.0 * c1
        valid = (reach <= 1.0) & np.isfinite(square) & np.isfinite(linear)
    return np.where(valid, square, 0.0), np.where(valid, linear, 0.0), valid


def ribbon_twist_spacing(terms: dict, across, tolerance, root):
    """Per cell the largest spacing h at which a bubble's bound meets the tolerance (0 where
    neither applies); root(a, b, c) solves a h^2 + b h = c."""
    spacing = 0.0
    for stretch_only in (False, True):
        square, linear, valid = ribbon_twist_quadratic(terms, across, stretch_only)
        with np.errstate(divide="ignore"):
            longest = 1.0 / terms["Gx" if stretch_only else "Gs"]  # the condition h |gamma_s| <= 1
        h = root(np.where(valid, square, 1.0), np.where(valid, linear, 1.0), tolerance)
        spacing = np.maximum(spacing, np.where(valid, np.minimum(h, longest), 0.0))
    return spacing
