"""Motor surfaces: the union of the circles C(t) = Z(t) C_unit ~Z(t) carried by a splined similarity motion.

``MotorSurface`` answers what an ``EvolvedSurface`` answers (``sample`` gives circles as
normalised 3-blades with their d/dt, ``check_projection_exists`` refuses where the curve has
no circle), so the TRS mesher, the tolerance meshing, the deviation measure, the viewer and the
ray tracer all take it as they take a blade surface. Every C(t) is a circle by construction:
there is no projection, no Sigma to vanish, and C(i) is control i itself.

The blade is built as the scene format builds a circle, C = A ^ B ^ D / |A ^ B ^ D| with
A, B, D = up(c + r u), up(c + r v), up(c - r u) and (u, v, n) right-handed, and differentiated
exactly: the three points move with the motion's point velocity x' = c' + omega x (x - c)
+ (r' / r)(x - c) (``MotionState.velocity``), up(x)' = x' + (x . x') n_inf, the product rule
gives (A ^ B ^ D)', and the normalisation's derivative follows from d(C^2)/dt = 2 <C C'>_0.
The points' own drift along the circle (u is chosen per t) is tangent to it and leaves C
unchanged, so C' is the circle's true rate. C C' is then the bivector of eq. 19 and X . (C C')
a velocity that keeps points on C(t), as for blade surfaces.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from cgamesh.geometry.algebra import products
from cgamesh.geometry.algebra.conformal import N_INF, up, vector
from cgamesh.geometry.frame import LocalFrame
from cgamesh.geometry.motors import MotionSpline, MotionState
from cgamesh.geometry.objects import CIRCLE_GRADE, perpendicular_unit, square
from cgamesh.geometry.projection import Projection

# Samples per segment on which the normal spline is checked (as the blade surfaces' scan).
SCAN_SAMPLES_PER_SEGMENT = 128


def circle_blades(state: MotionState) -> tuple[np.ndarray, np.ndarray]:
    """Normalised circles C (A, 32) of the states and their d/dt (A, 32)."""
    n = state.normal
    u = perpendicular_unit(n)
    v = np.cross(n, u)
    r = state.radius[:, None]
    points = np.stack([state.centre + r * u, state.centre + r * v, state.centre - r * u], axis=1)  # (A, 3, 3)
    rates = state.velocity(points)
    lifted = up(points)
    lifted_rates = vector(rates) + np.einsum("api,api->ap", points, rates)[..., None] * N_INF
    a, b, d = (lifted[:, k] for k in range(3))
    da, db, dd = (lifted_rates[:, k] for k in range(3))
    one = (1,)
    ab = products.outer(a, b, one, one)
    raw = products.outer(ab, d, (2,), one)
    d_raw = (products.outer(products.outer(da, b, one, one), d, (2,), one)
             + products.outer(products.outer(a, db, one, one), d, (2,), one)
             + products.outer(ab, dd, (2,), one))
    size_sq = square(raw, CIRCLE_GRADE)
    size = np.sqrt(size_sq)
    half_d_size_sq = products.geometric(raw, d_raw, (3,), (3,), (0,))[..., 0]
    blades = raw / size[:, None]
    derivatives = d_raw / size[:, None] - raw * (half_d_size_sq / (size_sq * size))[:, None]
    return blades, derivatives


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

    def sample(self, t: np.ndarray) -> Projection:
        """Circles C(t) (A, 32) and dC/dt, local frame; ``margin`` holds |H| of the normal spline."""
        state = self.path.evaluate(np.atleast_1d(np.asarray(t, dtype=np.float64)))
        blades, derivatives = circle_blades(state)
        return Projection(blades, derivatives, state.normal_length)

    def check_projection_exists(self, sampled: np.ndarray | None = None) -> None:
        """Raise where the normal spline nearly vanishes (the only way a motor curve loses its circle)."""
        self.path.check_normals(self.name, SCAN_SAMPLES_PER_SEGMENT)

    def circles(self, t: np.ndarray) -> MotionState:
        """Circles and their rates at t, in world units (centre, radius and their rates scaled)."""
        state = self.path.evaluate(np.atleast_1d(np.asarray(t, dtype=np.float64)))
        scale = self.frame.scale
        return MotionState(self.frame.to_world(state.centre), state.normal, scale * state.radius,
                           scale * state.d_centre, state.d_normal, scale * state.d_radius, state.normal_length)
