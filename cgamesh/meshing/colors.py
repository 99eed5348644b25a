"""Per-vertex colours (linear RGB in [0, 1]) from tangents, values and segment ids."""

from __future__ import annotations

import numpy as np

# viridis at 9 evenly spaced stops (matplotlib's table), linearly interpolated between them.
_VIRIDIS = np.array([
    [0.267004, 0.004874, 0.329415], [0.282623, 0.140926, 0.457517], [0.253935, 0.265254, 0.529983],
    [0.206756, 0.371758, 0.553117], [0.163625, 0.471133, 0.558148], [0.127568, 0.566949, 0.550556],
    [0.134692, 0.658636, 0.517649], [0.266941, 0.748751, 0.440573], [0.477504, 0.821444, 0.318195],
    [0.741388, 0.873449, 0.149561], [0.993248, 0.906157, 0.143936]])
_COLORMAPS = {"viridis": _VIRIDIS}


def direction_colors(tangents: np.ndarray) -> np.ndarray:
    """(V, 3) colours |t| of unit directions (V, 3): diffusion viewers' red x, green y, blue z."""
    t = np.asarray(tangents, dtype=np.float64)
    length = np.linalg.norm(t, axis=1, keepdims=True)
    return np.abs(t) / np.where(length > 0.0, length, 1.0)


def colormap(values: np.ndarray, name: str = "viridis", lo: float | None = None,
             hi: float | None = None) -> np.ndarray:
    """(V, 3) colours of ``values`` (V,) through a built-in colormap, from lo (default min) to hi (max)."""
    if name not in _COLORMAPS:
        raise ValueError(f"unknown colormap {name!r}; expected one of {', '.join(_COLORMAPS)}")
    table = _COLORMAPS[name]
    v = np.asarray(values, dtype=np.float64)
    lo = float(np.min(v)) if lo is None and v.size else (0.0 if lo is None else lo)
    hi = float(np.max(v)) if hi is None and v.size else (1.0 if hi is None else hi)
    s = np.clip((v - lo) / (hi - lo), 0.0, 1.0) if hi > lo else np.zeros_like(v)
    x = s * (len(table) - 1)
    i = np.minimum(x.astype(np.int64), len(table) - 2)
    f = (x - i)[:, None]
    return table[i] * (1.0 - f) + table[i + 1] * f


def segment_colors(segment_ids: np.ndarray) -> np.ndarray:
    """(V, 3) a categorical colour per id: golden-ratio hues, so neighbouring ids differ."""
    ids = np.asarray(segment_ids, dtype=np.float64)
    hue = np.mod(ids * 0.618033988749895, 1.0)
    k = np.mod(np.array([5.0, 3.0, 1.0])[None, :] + hue[:, None] * 6.0, 6.0)
    value, saturation = 0.9, 0.65
    return value - value * saturation * np.clip(np.minimum(k, 4.0 - k), 0.0, 1.0)
