"""The tolerance bound of a circle surface's quad counting only the error normal to the surface.

A mesh point y of a quad is within |e| of the polygon surface P (docs/tolerance.md, "The bound
for a quad"), but moving a point along the surface does not take it off the surface: only
the part of e normal to the surface at a nearby surface point x0 counts in full, and its
tangential part w_T costs only the surface's curvature over the step that absorbs it,

    dist(y, S) <= sag + |N . e| + 1/2 (A dt^2 + 2 B |dt dtheta| + r dtheta^2),

where (dt, dtheta) solves J (dt, dtheta) = w_T for the surface's tangent vectors J = [x_t, x_theta]
at x0 (docs/tolerance.md, "The error normal to the surface", proves it and the bounds below).
For a tube whose circles are about perpendicular to its path, the quad's twist P_t theta lies
along the path, tangent to the surface: |N . P_t theta| is a small fraction of |P_t theta|, and
the twist term that took a quarter to a third of the tolerance almost vanishes.

The step dt moves along t: the maxima of A, B and r must hold over the t it reaches, so the
bound is used only where dt stays within ``margin`` of the interval, inside its segment (the
members are not twice differentiable across a joint); elsewhere the other bounds apply.
"""

from __future__ import annotations

import numpy as np


def spin_bounds(n1, n2, turned, rate):
    """(|psi'|, |psi''|): the mesh frame's spin about n relative to transport, where ``turned``
    bounds |n(t) - n(t_k)| (docs/tolerance.md, "A and B for circles")."""
    q = 2.0 - 0.5 * turned * turned  # <= 1 + n(t_k) . n(t)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        transport = turned * n1 / q  # the spin from the plane's turning alone
        return transport + rate, turned * n2 / q + transport ** 2


def full_second_derivatives(terms: dict, spin, spin_rate, prefix: str = ""):
    """(a >= |x_tt|, b >= |x_t theta|) in the mesh frame: the sampled transport's bounds plus the
    spin's (x = x_G(t, theta + psi(t)))."""
    rm, big_a, big_b = terms[prefix + "Rm"], terms[prefix + "A"], terms[prefix + "B"]
    with np.errstate(invalid="ignore", over="ignore"):
        a = big_a + 2.0 * big_b * spin + rm * (spin * spin + spin_rate)
        b = big_b + rm * spin
    return a, b


def tilt_bound(terms: dict):
    """(axial, tilt): a lower bound of |n . x_t| and an upper bound of |N . n|, the surface normal's
    component along the circle's axis: |x_t . rho| / sqrt((x_t . n)^2 + (x_t . rho)^2), which grows
    with |x_t . rho| <= |n x c'| + |r'| and falls with |x_t . n| >= axial."""
    axial = -terms["negCn"] - terms["Rm"] * terms["N1"]
    radial = terms["Cx"] + terms["R1"]
    with np.errstate(divide="ignore", invalid="ignore"):
        tilt = np.where(axial > 0.0, radial / np.sqrt(radial * radial + axial * axial), 1.0)
    return axial, np.fmin(tilt, 1.0)  # NaN (radial infinite) -> 1; radial >= 0, so tilt is never -inf


def normal_twist(terms: dict, h, around, spin, tilt):
    """An upper bound of |N(x0) . P_t theta| / |L'| over the quad: of the twist
    r' l - r (n' . l) n + r psi' n x l only its normal components, each moved by at most h times
    the rate its direction turns at between x0's t and the Hessian's."""
    rm, n1, r1 = terms["Rm"], terms["N1"], terms["R1"]
    return (r1 * (np.sin(np.pi / around) + h * (n1 + spin)) + rm * n1 * (tilt + h * n1) + rm * spin)


def curvature_term(terms: dict, wide: dict, tangential, axial, spin, wide_spin, wide_spin_rate):
    """(rem, dt): the bound of the step's second-order remainder that absorbs a tangential error of
    length ``tangential``, and the step's bound along t (which ``wide`` must cover)."""
    a, b = full_second_derivatives(wide, wide_spin, wide_spin_rate)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        dt = tangential / axial  # |dt| |x_t - (x_t . e_theta) e_theta| <= |w_T|, and that part >= axial
        dtheta = (tangential + dt * (terms["Cx"] + terms["Rm"] * spin)) / -terms["negRmin"]
        rem = 0.5 * (a * dt * dt + 2.0 * b * dt * dtheta + wide["Rm"] * dtheta * dtheta)
    return rem, dt


def normal_projection_error(terms: dict, wide: dict, h, around, rate: float, frame: tuple | None = None):
    """E of every interval by the normal projection (inf where it does not apply): ``terms`` the
    maxima over the cells the interval touches, ``wide`` those over the interval widened by
    ``wide['margin']`` on each side within its segment. ``frame``: (spin, spin_rate, a, b) of
    ``spin_bounds`` and ``full_second_derivatives`` on these intervals, when the caller has them."""
    n1, n2, rm = terms["N1"], terms["N2"], terms["Rm"]
    if frame is None:
        spin, spin_rate = spin_bounds(n1, n2, h * n1, rate)
        a, b = full_second_derivatives(terms, spin, spin_rate)
    else:
        spin, spin_rate, a, b = frame
    margin = wide["margin"]
    wide_turned = (h + 2.0 * margin) * wide["N1"]  # |n(t) - n(t_k)| on the widened interval
    wide_spin, wide_spin_rate = spin_bounds(wide["N1"], wide["N2"], wide_turned, rate)
    half = np.pi / around
    sag = rm * (1.0 - np.cos(half))
    axial, tilt = tilt_bound(terms)
    with np.errstate(invalid="ignore", over="ignore"):
        along = a * h * h / 8.0
        normal = along + normal_twist(terms, h, around, spin, tilt) * h * np.sin(half) / 2.0
        tangential = along + b * h * np.sin(half) / 2.0 + sag * tilt  # >= |w_T|
    rem, dt = curvature_term(terms, wide, tangential, axial, spin, wide_spin, wide_spin_rate)
    error = sag + normal + rem
    valid = (axial > 0.0) & (dt <= margin) & (wide_turned < 1.0) & (-terms["negRmin"] > 0.0) & np.isfinite(error)
    return np.where(valid, error, np.inf)


def normal_projection_spacing(terms: dict, around, tolerance: float, rate: float, root):
    """Per cell the spacing h meeting the tolerance with the normal projection's leading terms
    (the step's remainder estimated for a tangential error of the tolerance itself); the rings'
    bounds are then checked with every term."""
    rm = terms["Rm"]
    a, b = full_second_derivatives(terms, rate, 0.0)
    half = np.pi / around
    sag = rm * (1.0 - np.cos(half))
    axial, tilt = tilt_bound(terms)
    rem, _ = curvature_term(terms, terms, tolerance, axial, rate, rate, 0.0)
    twist = normal_twist(terms, 0.0, around, rate, tilt)
    c = tolerance - sag - rem
    valid = (axial > 0.0) & (-terms["negRmin"] > 0.0) & np.isfinite(c)
    spacing = root(a / 8.0, twist * np.sin(half) / 2.0, np.where(valid, c, 0.0))
    return np.where(valid, spacing, 0.0)
