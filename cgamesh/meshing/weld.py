"""Welding vertices by position: meshers repeat vertices at UV seams and cap rims."""

from __future__ import annotations

import numpy as np


def weld_by_position(positions: np.ndarray) -> np.ndarray:
    """(V,) index of the first vertex at each bit-identical position (positions (V, 3))."""
    rows = np.ascontiguousarray(positions, dtype=np.float64)
    rows = rows + 0.0  # -0.0 and 0.0 are the same place
    keys = rows.view(np.dtype((np.void, rows.dtype.itemsize * 3))).ravel()
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    return first[inverse.ravel()]
