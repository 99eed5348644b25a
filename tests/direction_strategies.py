"""Hypothesis strategies of directions for scene property tests: exact +-axes (where a plain
tube facing -z once crashed) as often as random directions on the sphere."""

from __future__ import annotations

import math

from hypothesis import strategies as st

AXES = [(1.0, 0.0, 0.0), (-1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, -1.0, 0.0), (0.0, 0.0, 1.0), (0.0, 0.0, -1.0)]
coordinate = st.floats(-1.0, 1.0, allow_nan=False)
sphere_direction = st.tuples(coordinate, coordinate, coordinate).filter(lambda v: math.hypot(*v) > 1e-3)
direction = st.one_of(st.sampled_from(AXES), sphere_direction)
