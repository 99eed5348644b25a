"""Scene specs to evolved surfaces: control objects in their working frame, and the curve.

Both the mesher (cgamesh.pipelines.scene) and the ray tracer (cgamesh.tracer) start here, so a
surface means the same thing to both.
"""

from __future__ import annotations

import numpy as np

from cgamesh.geometry import objects
from cgamesh.geometry.curves.bezier import Bezier, RationalBezier
from cgamesh.geometry.curves.kochanek_bartels import KochanekBartels
from cgamesh.geometry.curves.linear import Linear
from cgamesh.errors import CgameshError, DegenerateGeometryError, InvalidInputError
from cgamesh.geometry.frame import LocalFrame
from cgamesh.geometry.motor_surface import MotorSurface
from cgamesh.geometry.motors import MotionSpline
from cgamesh.inputs.scene import SurfaceSpec
from cgamesh.geometry.surface import EvolvedSurface

# Consecutive normalised control blades closer than this (relative) are the same object.
SAME_CONTROL_RTOL = 1e-12


def make_curve(spec: SurfaceSpec):
    """The curve of a surface spec, over its controls."""
    n = len(spec.controls)
    if spec.curve == "linear":
        return Linear(n)
    if spec.curve == "bezier":
        return Bezier(n)
    if spec.curve == "rational_bezier":
        return RationalBezier(tuple(c.weight for c in spec.controls))
    if spec.curve == "kb":
        return KochanekBartels(n, spec.tension, spec.bias, spec.continuity, spec.closed)
    if spec.curve == "catmull_rom":
        return KochanekBartels(n, closed=spec.closed)
    raise InvalidInputError(f"{spec.location}.curve: unknown curve kind {spec.curve!r}")


def _circle_points(spec: SurfaceSpec) -> tuple[np.ndarray, np.ndarray]:
    """Points (n, 3) that fix each circle control and how far the circle reaches past them (n,)."""
    points, reach = [], []
    for control in spec.controls:
        if control.through is not None:
            # The circle may reach far past its three points (when they are nearly on one line):
            # its own centre and radius go into the frame, so the whole circle fits the unit ball.
            centre, _, radius = circumcircle(control.through)
            points.extend([*control.through, centre])
            reach.extend([0.0, 0.0, 0.0, radius])
        else:
            points.append(control.center)
            reach.append(control.radius)
    return np.array(points, dtype=np.float64), np.array(reach)


def circumcircle(through) -> tuple[np.ndarray, np.ndarray, float]:
    """Centre (3,), unit normal (3,) and radius of the circle through three non-collinear points
    A, B, D, the normal oriented so that A -> B -> D runs counter-clockwise about it.

    centre = A + ((|u|^2 v - |v|^2 u) x (u x v)) / (2 |u x v|^2) for u = B - A, v = D - A, on the
    points divided by their spread (nothing overflows or underflows). Its relative error is about
    float64's epsilon over the sine of the triangle's angle at A, where A ^ B ^ D computed from
    up(A), up(B), up(D) loses precision with the square of that sine's inverse.
    """
    a, b, d = (np.array(p, dtype=np.float64) for p in through)
    spread = max(float(np.abs(b - a).max()), float(np.abs(d - a).max()))
    u, v = (b - a) / spread, (d - a) / spread
    normal = np.cross(u, v)
    offset = np.cross(np.dot(u, u) * v - np.dot(v, v) * u, normal) / (2.0 * np.dot(normal, normal))
    return a + spread * offset, normal / np.linalg.norm(normal), spread * float(np.linalg.norm(offset))


def build_surface(spec: SurfaceSpec) -> EvolvedSurface | MotorSurface:
    """Normalised (and, with ``align``, aligned) control blades in a local frame, with the curve;
    for ``interpolation: motor``, the similarity motion through the control circles instead."""
    if spec.type == "circles" and spec.interpolation == "motor":
        return build_motor_surface(spec)
    try:
        if spec.type == "circles":
            frame = LocalFrame.enclosing(*_circle_points(spec))
            blades = np.stack([_circle_blade(control, frame) for control in spec.controls])
            grade = objects.CIRCLE_GRADE
        else:
            ends = np.array([p for c in spec.controls for p in (c.a, c.b)], dtype=np.float64)
            frame = LocalFrame.enclosing(ends)
            a = frame.to_local(np.array([c.a for c in spec.controls], dtype=np.float64))
            b = frame.to_local(np.array([c.b for c in spec.controls], dtype=np.float64))
            blades = objects.point_pair(a, b)
            grade = objects.POINT_PAIR_GRADE
    except CgameshError as error:  # degenerate or non-finite controls, named with their surface
        raise type(error)(f"{spec.location}: {error}") from None
    if spec.align:
        blades = objects.align_orientations(blades, grade)
    curve = make_curve(spec)
    same = _same_as_previous(blades)
    if same.all():
        kind = "circle" if grade == objects.CIRCLE_GRADE else "point pair"
        raise DegenerateGeometryError(f"{spec.location}.controls: every control is the same {kind}, "
                                      "so the surface has no area")
    if grade == objects.POINT_PAIR_GRADE:
        _refuse_one_line(a, b, spec)
    if spec.curve == "linear" and same.any():
        # A linear segment between two equal controls is that one object: dropping the repeat
        # leaves the same surface, and no ring of the mesh is spent on a segment of no area.
        blades = blades[np.concatenate([[True], ~same])]
        curve = Linear(len(blades))
    return EvolvedSurface(spec.name, grade, blades, curve, frame)


def _refuse_one_line(a: np.ndarray, b: np.ndarray, spec: SurfaceSpec) -> None:
    """Point pairs whose end points (local, (n, 3) each) all lie on one line span no area: the
    interpolation only slides them along it (and can pass through a flat point doing so)."""
    direction = (b[0] - a[0]) / np.linalg.norm(b[0] - a[0])
    offsets = np.concatenate([a, b]) - a[0]
    across = offsets - np.outer(offsets @ direction, direction)
    if np.abs(across).max() <= SAME_CONTROL_RTOL:  # the controls lie in the unit ball
        raise DegenerateGeometryError(f"{spec.location}.controls: every point pair lies on one line, "
                                      "so the ribbon has no area")


def _same_as_previous(blades: np.ndarray) -> np.ndarray:
    """(n - 1,) bool: control i + 1 equals control i to rounding (normalised blades (n, 32))."""
    size = np.maximum(np.abs(blades[1:]).max(axis=1), np.abs(blades[:-1]).max(axis=1))
    return np.abs(blades[1:] - blades[:-1]).max(axis=1) <= SAME_CONTROL_RTOL * size


def _circle_blade(control, frame: LocalFrame) -> np.ndarray:
    if control.through is not None:
        # The same circle and orientation as up(A) ^ up(B) ^ up(D) (the scene format's
        # definition), built from its centre, normal and radius: accurate for any three points
        # the scene loader accepts, nearly collinear ones included.
        centre, normal, radius = circumcircle(control.through)
        return objects.circle_from_center_normal_radius(frame.to_local(centre), normal, radius / frame.scale)
    return objects.circle_from_center_normal_radius(
        frame.to_local(np.array(control.center, dtype=np.float64)),
        np.array(control.normal, dtype=np.float64),
        control.radius / frame.scale,
    )


# Motor controls whose centre, normal and radius (local units: the controls fill the unit ball)
# differ by no more than this are the same circle.
SAME_CIRCLE = 1e-14


def build_motor_surface(spec: SurfaceSpec) -> MotorSurface:
    """The splined similarity motion through a circle surface's controls (docs/interpolation.md).

    Controls are read exactly as for blade surfaces (a ``through`` circle is the circle A ^ B ^ D,
    its normal right-handed about A -> B -> D), then taken as centre, normal and radius.
    """
    try:
        frame = LocalFrame.enclosing(*_circle_points(spec))
        read = [_circle_parameters(control, frame) for control in spec.controls]
        centre, normal, radius = (np.array(part, dtype=np.float64) for part in zip(*read))
    except CgameshError as error:
        raise type(error)(f"{spec.location}: {error}") from None
    weights = tuple(c.weight for c in spec.controls) if spec.curve == "rational_bezier" else None
    if spec.curve == "linear" and len(centre) > 2:
        # As for blade surfaces: a linear span between two equal circles is that one circle, so
        # the repeat is dropped (the same surface, and no ring spent on a span of no area)
        same = np.all(np.abs(np.diff(np.hstack([centre, normal, radius[:, None]]), axis=0)) <= SAME_CIRCLE, axis=1)
        if not same.all():
            keep = np.concatenate([[True], ~same])
            centre, normal, radius = centre[keep], normal[keep], radius[keep]
    path = MotionSpline.through(centre, normal, radius, spec.curve, spec.closed, spec.tension, spec.bias,
                                spec.continuity, weights, spec.align)
    return MotorSurface(spec.name, path, frame)


def _circle_parameters(control, frame: LocalFrame) -> tuple[np.ndarray, np.ndarray, float]:
    """Local centre, unit normal and radius of a circle control (given ones kept exactly)."""
    if control.through is not None:
        centre, normal, radius = objects.circle_euclidean(_circle_blade(control, frame))
        return centre, normal, float(radius)
    normal = np.array(control.normal, dtype=np.float64)
    return frame.to_local(np.array(control.center, dtype=np.float64)), normal / np.linalg.norm(normal), \
        control.radius / frame.scale
