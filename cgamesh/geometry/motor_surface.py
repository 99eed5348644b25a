"""Motor surfaces: the union of the circles C(t) = Z(t) C_unit ~Z(t) carried by a splined similarity motion.

``MotorSurface`` answers what an ``EvolvedSurface`` answers (``sample`` gives circles as
normalised 3-blades with their d/dt, ``check_projection_exists`` refuses where the curve has
no circle), so the TRS mesher, the tolerance meshing, the deviation measure, the viewer and the
ray tracer all take it as they take a blade surface. Every C(t) is a circle by construction:
there is no projection, no Sigma to vanish, and C(i) is control i itself.

The blade is the dual of S ^ P, with S = up(c) - r^2 n_inf / 2 the circle's great sphere and
P = n + (n . c) n_inf its plane, normalised to C^2 = 1: the same blade, sign included, as the
scene format's A ^ B ^ D through c + r u, c + r v, c - r u with (u, v, n) right-handed (a test
checks it against the TRS versor's image of the unit circle). Its t-derivative is exact:
S' = c' + (c . c' - r r') n_inf, P' = n' + (n' . c + n . c') n_inf, (S ^ P)' = S' ^ P + S ^ P',
and the normalisation's derivative follows from d(C^2)/dt = 2 <C C'>_0. C C' is then the
bivector of eq. 19 and X . (C C') a velocity that keeps points on C(t), as for blade surfaces.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar

import numpy as np

from cgamesh.geometry.algebra import products
from cgamesh.geometry.algebra.conformal import N_INF, up, vector
from cgamesh.geometry.frame import LocalFrame
from cgamesh.geometry.motors import MotionSpline, MotionState
from cgamesh.geometry.objects import CIRCLE_GRADE, square

# Samples per segment on which the normal spline is checked (as the blade surfaces' scan).
SCAN_SAMPLES_PER_SEGMENT = 128


def _dual_circles(state: MotionState) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Sphere S = up(c) - r^2 n_inf / 2 and plane P = n + (n . c) n_inf of each circle, with d/dt."""
    c, n, r = state.centre, state.normal, state.radius
    dc, dn, dr = state.d_centre, state.d_normal, state.d_radius
    sphere = up(c) - (0.5 * r * r)[:, None] * N_INF
    d_sphere = vector(dc) + (np.einsum("ai,ai->a", c, dc) - r * dr)[:, None] * N_INF
    plane = vector(n) + np.einsum("ai,ai->a", n, c)[:, None] * N_INF
    d_plane = vector(dn) + (np.einsum("ai,ai->a", dn, c) + np.einsum("ai,ai->a", n, dc))[:, None] * N_INF
    return sphere, d_sphere, plane, d_plane


def circle_blades(state: MotionState) -> np.ndarray:
    """Normalised circles C (A, 32) of the states: the dual of S ^ P, normalised (it equals
    A ^ B ^ D / |A ^ B ^ D| of the scene format's construction, sign included)."""
    sphere, _, plane, _ = _dual_circles(state)
    raw = products.dual(products.outer(sphere, plane, (1,), (1,)))
    return raw / np.sqrt(square(raw, CIRCLE_GRADE))[:, None]


def circle_blade_rates(state: MotionState) -> np.ndarray:
    """dC/dt (A, 32) of the normalised circles: (S ^ P)' = S' ^ P + S ^ P' (S, P as in
    ``circle_blades``), dualised, and the normalisation's derivative from d(C^2) = 2 <C C'>_0."""
    return circle_blades_and_rates(state)[1]


def circle_blades_and_rates(state: MotionState) -> tuple[np.ndarray, np.ndarray]:
    """``circle_blades`` and ``circle_blade_rates`` of the same states, the blade S ^ P and its
    size computed once for both (the same bits as the two calls)."""
    sphere, d_sphere, plane, d_plane = _dual_circles(state)
    one = (1,)
    raw = products.dual(products.outer(sphere, plane, one, one))
    d_raw = products.dual(products.outer(d_sphere, plane, one, one) + products.outer(sphere, d_plane, one, one))
    size_sq = square(raw, CIRCLE_GRADE)
    size = np.sqrt(size_sq)
    half_d_size_sq = products.geometric(raw, d_raw, (3,), (3,), (0,))[..., 0]
    return raw / size[:, None], d_raw / size[:, None] - raw * (half_d_size_sq / (size_sq * size))[:, None]


class MotorSample:
    """What ``sample`` returns (as a blade surface's Projection): blades (A, 32), margin (A,)
    = |H| of the normal spline, and derivatives (A, 32) dC/dt, computed when first asked for
    (the tolerance measure reads only blades)."""

    def __init__(self, state: MotionState):
        self.state = state
        self.blades = circle_blades(state)
        self.margin = state.normal_length

    @cached_property
    def derivatives(self) -> np.ndarray:
        return circle_blade_rates(self.state)


@dataclass(frozen=True)
class MotorSurface:
    """name: for messages; path: the splined motion in ``frame`` (local units)."""

    name: str
    path: MotionSpline
    frame: LocalFrame
    grade: ClassVar[int] = CIRCLE_GRADE
    interpolation: ClassVar[str] = "motor"

    @property
    def segment_count(self) -> int:
        return self.path.segment_count

    def sample(self, t: np.ndarray) -> MotorSample:
        """Circles C(t) (A, 32) and dC/dt, local frame; ``margin`` holds |H| of the normal spline."""
        return MotorSample(self.path.evaluate(np.atleast_1d(np.asarray(t, dtype=np.float64))))

    def sample_blades(self, t: np.ndarray) -> np.ndarray:
        """The circles (A, 32) of ``sample(t)`` (as a blade surface's ``sample_blades``)."""
        return self.sample(t).blades

    def check_projection_exists(self, sampled: np.ndarray | None = None) -> None:
        """Raise where the normal spline nearly vanishes (the only way a motor curve loses its circle)."""
        self._normals_checked

    @cached_property
    def _normals_checked(self) -> bool:
        """The scan of ``check_projection_exists``, done once per surface (a tolerance run checks
        before planning and the mesher again on the planned rings: the scan does not depend on them)."""
        self.path.check_normals(self.name, SCAN_SAMPLES_PER_SEGMENT)
        return True

    def circles(self, t: np.ndarray) -> MotionState:
        """Circles and their rates at t, in world units (centre, radius and their rates scaled)."""
        state = self.path.evaluate(np.atleast_1d(np.asarray(t, dtype=np.float64)))
        scale = self.frame.scale
        return MotionState(self.frame.to_world(state.centre), state.normal, scale * state.radius,
                           scale * state.d_centre, state.d_normal, scale * state.d_radius, state.normal_length)
