"""Scene specs to evolved surfaces: control objects in their working frame, and the curve.

Both the mesher (cgamesh.pipeline) and the ray tracer (cgamesh.tracer) start here, so a
surface means the same thing to both.
"""

from __future__ import annotations

import numpy as np

from cgamesh.geometry import objects
from cgamesh.geometry.curves.bezier import Bezier, RationalBezier
from cgamesh.geometry.curves.kochanek_bartels import KochanekBartels
from cgamesh.geometry.curves.linear import Linear
from cgamesh.errors import CgameshError, InvalidInputError
from cgamesh.geometry.frame import LocalFrame
from cgamesh.geometry.motor_surface import MotorSurface
from cgamesh.geometry.motors import MotionSpline
from cgamesh.inputs.scene import SurfaceSpec
from cgamesh.geometry.surface import EvolvedSurface


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
            points.extend(control.through)
            reach.extend([0.0, 0.0, 0.0])
        else:
            points.append(control.center)
            reach.append(control.radius)
    return np.array(points, dtype=np.float64), np.array(reach)


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
    return EvolvedSurface(spec.name, grade, blades, make_curve(spec), frame)


def _circle_blade(control, frame: LocalFrame) -> np.ndarray:
    if control.through is not None:
        a, b, d = (frame.to_local(np.array(p, dtype=np.float64)) for p in control.through)
        return objects.circle_through(a, b, d)
    return objects.circle_from_center_normal_radius(
        frame.to_local(np.array(control.center, dtype=np.float64)),
        np.array(control.normal, dtype=np.float64),
        control.radius / frame.scale,
    )


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
