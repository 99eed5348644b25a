"""Length units of real-data inputs (centrelines), in metres: ``--units`` and a format's default unit.

Scene files name their own unit from a shorter list (cgamesh.inputs.scene).
"""

from __future__ import annotations

METERS_PER_UNIT = {"nm": 1e-9, "um": 1e-6, "mm": 1e-3, "cm": 1e-2, "m": 1.0}
