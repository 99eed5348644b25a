"""Evolved surfaces: the union of the projected objects C(t) = S C'(t) along a curve (paper eq. 12).

An ``EvolvedSurface`` holds normalised, aligned control blades in a LocalFrame and a curve;
``sample`` gives the projected objects and their derivatives at parameters t, refusing any
place where the projection does not exist. ``CircleRings`` reads circles out as Euclidean
centre, normal and radius in world coordinates, together with the velocity field
dX/dt = X . (C dC/dt) of points carried along by the evolution (paper eqs. 19-20).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar, Protocol

import numpy as np

from cgamesh.geometry.algebra import products
from cgamesh.geometry.algebra.conformal import EUCLIDEAN, up, weight
from cgamesh.geometry.algebra.layout import grade_indices
from cgamesh.geometry.curves import CurveBasis
from cgamesh.errors import DegenerateGeometryError
from cgamesh.geometry.frame import LocalFrame
from cgamesh.geometry.objects import circle_euclidean
from cgamesh.geometry.projection import Projection, four_vector_free, margin, project, project_scalar

# The projection is refused where min(beta, g) falls below this fraction of |C'|^2: there
# S grows like 1/sqrt(margin) and the object heads for a line, a point or nothing at all.
MIN_MARGIN = 1e-8
# Samples per segment used to look for a vanishing projection between the mesh's rings.
SCAN_SAMPLES_PER_SEGMENT = 128


class Curve(Protocol):
    segment_count: int

    def basis(self, t: np.ndarray) -> CurveBasis: ...


@dataclass(frozen=True)
class EvolvedSurface:
    """name: for messages; grade: 3 (circles) or 2 (point pairs); controls: (n, 32) in ``frame``."""

    name: str
    grade: int
    controls: np.ndarray
    curve: Curve
    frame: LocalFrame
    # how circles are interpolated (a motor surface, geometry/motor_surface.py, says "motor")
    interpolation: ClassVar[str] = "blade"

    @property
    def segment_count(self) -> int:
        return self.curve.segment_count

    @cached_property
    def four_vector_free(self) -> bool:
        """Whether every interpolant's Sigma is a scalar (co-circular point pairs, paper section 7.3)."""
        return four_vector_free(self.controls, self.grade)

    def _project(self, t: np.ndarray) -> Projection:
        basis = self.curve.basis(t)
        interpolant, derivative = basis.evaluate(self.controls)
        projector = project_scalar if self.four_vector_free else project
        return projector(interpolant, derivative, self.grade, basis.weight_sum())

    def sample(self, t: np.ndarray) -> Projection:
        """Projected objects and d/d alpha at parameters t (A,) in [0, segment_count]."""
        t = np.asarray(t, dtype=np.float64)
        projection = self._project(t)
        self._refuse_small_margin(t, projection.margin)
        return projection

    def check_projection_exists(self, sampled: np.ndarray | None = None) -> None:
        """Scan the whole curve densely and raise where the projection vanishes.

        sampled: increasing parameters that the caller passes to ``sample`` (which refuses
        them itself) from 0 to the end; where no step between them is longer than the scan's,
        the scan would see nothing they do not, and is skipped.
        """
        step = 1.0 / SCAN_SAMPLES_PER_SEGMENT
        if (sampled is not None and len(sampled) > 1 and sampled[0] <= 0.0
                and sampled[-1] >= self.segment_count and np.max(np.diff(sampled)) <= step):
            return
        t = np.linspace(0.0, self.segment_count, SCAN_SAMPLES_PER_SEGMENT * self.segment_count + 1)
        basis = self.curve.basis(t)
        margins = margin(basis.value(self.controls), self.grade, basis.weight_sum(), scalar=self.four_vector_free)
        self._refuse_small_margin(t, margins)

    def _refuse_small_margin(self, t: np.ndarray, margin: np.ndarray) -> None:
        bad = ~(margin >= MIN_MARGIN)
        if not bad.any():
            return
        worst = int(np.argmin(np.where(np.isnan(margin), -np.inf, margin)))
        segment = min(int(t[worst]), self.segment_count - 1)
        alpha = t[worst] - segment
        raise DegenerateGeometryError(
            f"surface '{self.name}': the interpolated object has no blade projection at "
            f"segment {segment}, alpha = {alpha:.6g} (<Sigma>_0 + [[Sigma]] or [[Sigma]] reaches 0; "
            "controls of opposite orientation, or an interpolant through a non-real object)"
        )


@dataclass(frozen=True)
class CircleRings:
    """Circles C(t_k) read out in world coordinates.

    centre (K, 3), normal (K, 3) unit, radius (K,), and omega (K, 32) = C dC/dt, the
    angular-velocity bivector (eq. 19) in the local frame.
    """

    centre: np.ndarray
    normal: np.ndarray
    radius: np.ndarray
    omega: np.ndarray
    frame: LocalFrame

    @classmethod
    def from_projection(cls, projection: Projection, frame: LocalFrame) -> "CircleRings":
        centre, normal, radius = circle_euclidean(projection.blades)
        omega = products.geometric(projection.blades, projection.derivatives, (3,), (3,), (2,))
        return cls(frame.to_world(centre), normal, frame.scale * radius, omega, frame)

    def velocity(self, points: np.ndarray) -> np.ndarray:
        """World velocity d x / d t (K, S, 3) of world points (K, S, 3) on the circles.

        X' = X . Omega (eq. 20) moves the conformal point X = up(x) without leaving C(t); its
        weight changes at the rate w' = -X' . n_inf, so the Euclidean velocity is
        x' = X'_E - w' x (in the local frame, then scaled to world lengths). X . Omega is
        linear in X: each ring's 5 x 5 matrix is built once and applied to its S points.
        """
        local = self.frame.to_local(points)
        moved = up(local)[..., _VECTORS] @ self._vector_map
        local_velocity = moved[..., EUCLIDEAN] - weight(moved)[..., None] * local
        return self.frame.scale * local_velocity

    @cached_property
    def _vector_map(self) -> np.ndarray:
        """(K, 5, 32): row j is e_j . Omega_k (a vector), for the vector blades e1..e5."""
        return products.right_operator("inner", self.omega, (1,), (2,), (1,))[1]


_VECTORS = grade_indices(1)  # e1, e2, e3 (Euclidean), e4, e5
