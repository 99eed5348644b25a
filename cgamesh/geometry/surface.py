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

from cgamesh.geometry import flatness
from cgamesh.geometry.algebra import products
from cgamesh.geometry.algebra.conformal import E1, E2, E3, E4, E5
from cgamesh.geometry.algebra.layout import grade_indices
from cgamesh.geometry.curves import CurveBasis
from cgamesh.errors import DegenerateGeometryError
from cgamesh.geometry.frame import LocalFrame
from cgamesh.geometry.objects import circle_euclidean, point_pair_endpoints
from cgamesh.geometry.projection import (Projection, four_vector_free, margin, project, project_blades,
                                        project_scalar, project_without_derivatives)

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
        if self.grade == 2:
            self._refuse_ends_at_infinity(t, projection.blades)
        return projection

    def sample_blades(self, t: np.ndarray) -> np.ndarray:
        """The projected objects (A, 32) of ``sample(t)``, bit for bit, refused where it refuses,
        without their derivatives (about a third of the work)."""
        return self._blades_and_ends(t)[0]

    def sample_pair_ends(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The end points (a, b) (A, 3) of the point pairs ``sample_blades(t)``, refused where it
        refuses: the ones its check for end points at infinity finds, not found again."""
        return self._blades_and_ends(t)[1]

    def _blades_and_ends(self, t: np.ndarray):
        t = np.asarray(t, dtype=np.float64)
        basis = self.curve.basis(t)
        blades, margin_ = project_without_derivatives(basis.value(self.controls), self.grade, basis.weight_sum(),
                                                      self.four_vector_free)
        self._refuse_small_margin(t, margin_)
        return blades, (self._refuse_ends_at_infinity(t, blades) if self.grade == 2 else None)

    def _refuse_ends_at_infinity(self, t: np.ndarray, pairs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """A projected point pair can be real and still have an end point at infinity (the
        interpolant of two parallel, translated segments can be a flat point there). Returns
        the end points (a, b) when they are all finite."""
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            a, b = point_pair_endpoints(pairs)
        bad = ~(np.isfinite(a).all(axis=-1) & np.isfinite(b).all(axis=-1))
        if not bad.any():
            return a, b
        worst = int(np.argmax(bad))
        segment = min(int(t[worst]), self.segment_count - 1)
        raise DegenerateGeometryError(
            f"surface '{self.name}': the interpolated point pair has an end point at infinity at "
            f"segment {segment}, alpha = {t[worst] - segment:.6g} (the ribbon is unbounded there)"
        )

    def check_projection_exists(self, sampled: np.ndarray | None = None) -> None:
        """Scan the whole curve densely and raise where the projection vanishes, or where the
        projected object turns into a line or a flat point (geometry/flatness.py).

        sampled: increasing parameters that the caller passes to ``sample`` (which refuses
        them itself) from 0 to the end; where no step between them is longer than the scan's,
        the scan would see nothing they do not, and runs on them instead.
        """
        step = 1.0 / SCAN_SAMPLES_PER_SEGMENT
        if (sampled is not None and len(sampled) > 1 and sampled[0] <= 0.0
                and sampled[-1] >= self.segment_count and np.max(np.diff(sampled)) <= step):
            t = np.asarray(sampled, dtype=np.float64)
            if np.all(self._margins(t) >= MIN_MARGIN):  # otherwise ``sample`` refuses them
                self._refuse_lines(t)
            return
        self._dense_scan

    @cached_property
    def _dense_scan(self) -> bool:
        """The scan of ``check_projection_exists`` on its own grid, done once per surface."""
        t = np.linspace(0.0, self.segment_count, SCAN_SAMPLES_PER_SEGMENT * self.segment_count + 1)
        self._refuse_small_margin(t, self._margins(t))
        self._refuse_lines(t)
        return True

    def _margins(self, t: np.ndarray) -> np.ndarray:
        basis = self.curve.basis(t)
        return margin(basis.value(self.controls), self.grade, basis.weight_sum(), scalar=self.four_vector_free)

    def _refuse_lines(self, t: np.ndarray) -> None:
        """DegenerateGeometryError naming the parameter interval where the interpolated object
        turns into a line (circles) or a flat point (point pairs), and what avoids it. The
        projection exists at t (the margins were checked); between them the refinement may
        meet places where it does not, which count as no line (their blades are NaN)."""
        def blades_at(at: np.ndarray) -> np.ndarray:
            return project_blades(self.curve.basis(at).value(self.controls), self.grade, self.four_vector_free)

        found = flatness.find_line(t, blades_at(t), self.grade, blades_at)
        if found is None:
            return
        before, after, where, reach = found
        segment = min(int(before), self.segment_count - 1)
        interval = (f"between segment {segment}, alpha = {before - segment:.6g} and alpha = {after - segment:.6g} "
                    f"(closest at alpha = {where - segment:.6g}")
        size = "unbounded" if not reach < flatness.UNBOUNDED_REACH else f"{reach * self.frame.scale:.3g}"
        kind = ("circle turns into a line (a circle through infinity)" if self.grade == 3
                else "point pair has an end point at infinity (a flat point)")
        raise DegenerateGeometryError(f"surface '{self.name}': the interpolated {kind} {interval}, "
                                      f"{'radius' if self.grade == 3 else 'length'} {size}); {self._line_advice()}")

    def _line_advice(self) -> str:
        """What avoids a line: aligned controls where consecutive ones are opposite, else a motor
        interpolation (circles) or a control in between."""
        agreement = products.geometric(self.controls[:-1], self.controls[1:], (self.grade,), (self.grade,),
                                       (0,))[:, 0]
        opposite = np.flatnonzero(agreement < 0.0)
        motor = ", or interpolation: motor" if self.grade == 3 else ""
        if opposite.size:
            return (f"controls {opposite[0]} and {opposite[0] + 1} have opposite orientations (align: false); "
                    f"set align: true{motor}")
        return "add a control in between" + (motor if self.grade == 3 else "")

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
        """World velocity d x / d t (K, S, 3) of world points (K, S, 3) on the circles."""
        omega = np.moveaxis(self.omega[..., grade_indices(2)], -1, 0)
        return self.frame.scale * carried_velocity(omega, self.frame.to_local(points))


def carried_velocity(omega: np.ndarray, local: np.ndarray) -> np.ndarray:
    """Velocity (K, S, 3) of points local (K, S, 3) carried by the bivectors Omega, given as
    rows (10, K) of their grade-2 coefficients (layout order).

    X' = X . Omega (eq. 20) moves the conformal point X = up(x) without leaving C(t); its
    weight changes at the rate w' = -X' . n_inf, so the Euclidean velocity is x' = X'_E - w' x.
    X . Omega is summed from its twenty non-zero terms (four per vector blade of the result),
    each a product of a coefficient of up(x) and one of Omega, over every point at once; a
    5 x 5 matrix per ring applied by a stacked matrix product costs a BLAS call per ring.
    """
    _, _, blades_out, terms = products.product_terms("inner", (1,), (2,), (1,))
    x = [local[..., axis] for axis in range(3)]
    half_square = 0.5 * (x[0] * x[0] + x[1] * x[1] + x[2] * x[2])
    vector = [*x, half_square - 0.5, half_square + 0.5]  # e1..e5 of up(x) (conformal.up)
    bivector = omega[..., None]  # (10, K, 1) against the (K, S) coefficients
    # each blade's terms summed into its own buffer (first term negated in place, the rest
    # added or subtracted through one scratch): the same operations as forming each term anew.
    # Buffers laid out as the points are (``empty_like`` keeps their axis order), so that
    # numpy's loops run along the same axis as they would for fresh results.
    moved = [np.empty_like(half_square) for _ in terms]
    scratch = np.empty_like(half_square)
    for total, blade_terms in zip(moved, terms):
        (j, b, positive), rest = blade_terms[0], blade_terms[1:]
        np.multiply(vector[j], bivector[b], out=total)
        if not positive:
            np.negative(total, out=total)
        for j, b, positive in rest:
            np.multiply(vector[j], bivector[b], out=scratch)
            (np.add if positive else np.subtract)(total, scratch, out=total)
    assert tuple(blades_out) == (E1, E2, E3, E4, E5)
    rate = np.subtract(moved[4], moved[3], out=moved[4])  # -X' . n_inf (conformal.weight)
    out = np.empty(local.shape)
    for axis in range(3):
        np.multiply(rate, x[axis], out=scratch)
        np.subtract(moved[axis], scratch, out=out[..., axis])
    return out
