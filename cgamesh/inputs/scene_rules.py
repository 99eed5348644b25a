"""What a valid scene file is: its keys, choices, defaults and limits, and its geometry checks.

One table of the rules both scene readers apply: the careful reader (cgamesh.inputs.scene),
which walks the YAML node tree to name the line of a mistake, and the fast path
(cgamesh.inputs.scene_fast), which checks plain data over whole lists and steps aside when
anything is off. The format itself is docs/scene-files.md.
"""

from __future__ import annotations

import math

from cgamesh.inputs.scene_rendering import RENDERING_KEYS
from cgamesh.inputs.scene_specs import Vec3

SUPPORTED_VERSIONS = (1,)
METERS_PER_UNIT = {"m": 1.0, "cm": 0.01, "mm": 0.001}
UP_AXES = ("z", "y")
SURFACE_TYPES = ("circles", "point_pairs")
CURVES = ("linear", "bezier", "rational_bezier", "kb", "catmull_rom")
CLOSABLE_CURVES = ("kb", "catmull_rom")
DEFAULT_AROUND = 64
DEFAULT_ALONG = 128
MAX_RESOLUTION = 1_000_000
# Coordinates and radii: float32 (every output file's positions) reaches 3.4e38; the margin
# leaves room for surfaces that bulge past their controls.
MAX_LENGTH = 1e30
MAX_WEIGHT_RATIO = 1e12  # largest / smallest rational Bezier weight of one surface
NAME_PATTERN = "[A-Za-z_][A-Za-z0-9_]*"

TOP_KEYS = ("cgamesh", "units", "up", "surfaces") + RENDERING_KEYS
SURFACE_KEYS = ("name", "type", "curve", "tension", "bias", "continuity", "closed", "align",
                "controls", "resolution", "tolerance", "caps", "material", "uv", "uv_scale",
                "interpolation")
INTERPOLATIONS = ("blade", "motor")
UV_MODES = ("natural", "xatlas", "none")
CIRCLE_KEYS = ("center", "normal", "radius", "through", "weight")
POINT_PAIR_KEYS = ("a", "b", "weight")
CIRCLE_FORMS = "a circle is {center, normal, radius} or {through: [A, B, D]}"
# Relative tolerance of the degeneracy tests; they are scale-free, so any unit works.
DEGENERATE_RTOL = 1e-12

# --- geometry checks (scale-free, so they hold in any unit) ------------------------------------

def _scaled(*points: Vec3) -> tuple[Vec3, ...]:
    """The points over their largest |coordinate|: no overflow below, and the tests are relative."""
    scale = max(abs(c) for p in points for c in p)
    if scale == 0.0:
        return points
    return tuple(tuple(c / scale for c in p) for p in points)


def coincident(p: Vec3, q: Vec3) -> bool:
    """|p - q| <= 1e-12 * max(|p|, |q|, tiny)."""
    p, q = _scaled(p, q)
    gap = math.hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2])
    return gap <= DEGENERATE_RTOL * max(math.hypot(*p), math.hypot(*q), 1e-300)


def collinear(a: Vec3, b: Vec3, d: Vec3) -> bool:
    """|(B - A) x (D - A)| <= 1e-12 * |B - A| * |D - A|."""
    a, b, d = _scaled(a, b, d)
    u = (b[0] - a[0], b[1] - a[1], b[2] - a[2])
    v = (d[0] - a[0], d[1] - a[1], d[2] - a[2])
    cross = math.hypot(u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                       u[0] * v[1] - u[1] * v[0])
    return cross <= DEGENERATE_RTOL * math.hypot(*u) * math.hypot(*v)


