"""Per-vertex colours: colormaps of scalar fields, direction colours, categorical segment colours.

Every function returns (V, 3) float64 LINEAR RGB in [0, 1], what ``SurfaceMesh.colors`` holds and
what glTF's COLOR_0 and USD's displayColor mean. The colormaps are defined, as published, on
sRGB-encoded values (perceptual uniformity is a property of the encoded values): they are
interpolated in sRGB and converted to linear RGB last, so a viewer shows the published colours.

Colormaps are small tables (33 evenly spaced samples of each published map) interpolated
piecewise linearly with numpy, so nothing beyond numpy is imported at run time:

- ``viridis`` (sequential, perceptually uniform, monotone lightness; the default) and ``magma``
  (sequential, perceptually uniform, dark to light): van der Walt and Smith's maps (CC0);
- ``coolwarm`` (diverging, blue - grey - red, for fields signed about a middle value):
  Moreland's smooth cool-warm map.

A vertex whose value is NaN gets ``NAN_COLOR``, a neutral mid grey (sRGB 0.5) that none of the
maps' interiors nor the segment palette uses.
"""

from __future__ import annotations

import numpy as np

from cgamesh.errors import InvalidInputError

# sRGB 0.5 grey, as linear RGB.
NAN_COLOR = (0.21404114048223255,) * 3

_VIRIDIS = np.array([
    (0.2670, 0.0049, 0.3294), (0.2770, 0.0503, 0.3757), (0.2823, 0.0950, 0.4173),
    (0.2829, 0.1359, 0.4534), (0.2788, 0.1755, 0.4834), (0.2706, 0.2141, 0.5071),
    (0.2590, 0.2515, 0.5247), (0.2450, 0.2877, 0.5373), (0.2297, 0.3224, 0.5457),
    (0.2143, 0.3556, 0.5512), (0.1994, 0.3876, 0.5546), (0.1856, 0.4186, 0.5568),
    (0.1727, 0.4488, 0.5579), (0.1607, 0.4785, 0.5581), (0.1490, 0.5081, 0.5573),
    (0.1378, 0.5375, 0.5549), (0.1276, 0.5669, 0.5506), (0.1206, 0.5964, 0.5436),
    (0.1206, 0.6258, 0.5335), (0.1323, 0.6550, 0.5197), (0.1579, 0.6838, 0.5017),
    (0.1966, 0.7118, 0.4792), (0.2461, 0.7389, 0.4520), (0.3041, 0.7647, 0.4199),
    (0.3692, 0.7889, 0.3829), (0.4401, 0.8111, 0.3410), (0.5160, 0.8312, 0.2943),
    (0.5958, 0.8487, 0.2433), (0.6785, 0.8637, 0.1895), (0.7624, 0.8764, 0.1371),
    (0.8456, 0.8873, 0.0997), (0.9261, 0.8973, 0.1041), (0.9932, 0.9062, 0.1439),
])
_MAGMA = np.array([
    (0.0015, 0.0005, 0.0139), (0.0137, 0.0118, 0.0687), (0.0396, 0.0311, 0.1335),
    (0.0743, 0.0520, 0.2027), (0.1131, 0.0655, 0.2768), (0.1590, 0.0684, 0.3527),
    (0.2117, 0.0620, 0.4186), (0.2654, 0.0602, 0.4618), (0.3167, 0.0717, 0.4854),
    (0.3660, 0.0903, 0.4980), (0.4147, 0.1104, 0.5047), (0.4635, 0.1299, 0.5077),
    (0.5128, 0.1482, 0.5076), (0.5629, 0.1654, 0.5047), (0.6136, 0.1818, 0.4985),
    (0.6649, 0.1981, 0.4888), (0.7164, 0.2150, 0.4753), (0.7674, 0.2337, 0.4578),
    (0.8169, 0.2559, 0.4365), (0.8633, 0.2837, 0.4124), (0.9043, 0.3196, 0.3881),
    (0.9372, 0.3649, 0.3686), (0.9609, 0.4183, 0.3596), (0.9767, 0.4762, 0.3645),
    (0.9867, 0.5356, 0.3822), (0.9928, 0.5949, 0.4103), (0.9961, 0.6537, 0.4462),
    (0.9973, 0.7118, 0.4882), (0.9969, 0.7696, 0.5349), (0.9951, 0.8271, 0.5857),
    (0.9924, 0.8843, 0.6401), (0.9894, 0.9415, 0.6975), (0.9871, 0.9914, 0.7495),
])
_COOLWARM = np.array([
    (0.2298, 0.2987, 0.7537), (0.2664, 0.3533, 0.8016), (0.3042, 0.4069, 0.8453),
    (0.3433, 0.4594, 0.8841), (0.3837, 0.5102, 0.9178), (0.4252, 0.5591, 0.9461),
    (0.4677, 0.6056, 0.9685), (0.5108, 0.6494, 0.9851), (0.5543, 0.6901, 0.9955),
    (0.5978, 0.7273, 0.9998), (0.6408, 0.7608, 0.9978), (0.6831, 0.7900, 0.9898),
    (0.7240, 0.8149, 0.9757), (0.7634, 0.8351, 0.9557), (0.8006, 0.8504, 0.9300),
    (0.8353, 0.8605, 0.8990), (0.8674, 0.8644, 0.8626), (0.8995, 0.8475, 0.8178),
    (0.9256, 0.8255, 0.7711), (0.9455, 0.7986, 0.7231), (0.9595, 0.7670, 0.6741),
    (0.9675, 0.7308, 0.6247), (0.9697, 0.6905, 0.5751), (0.9660, 0.6461, 0.5259),
    (0.9567, 0.5980, 0.4773), (0.9417, 0.5464, 0.4297), (0.9214, 0.4914, 0.3834),
    (0.8959, 0.4331, 0.3387), (0.8654, 0.3711, 0.2958), (0.8302, 0.3047, 0.2549),
    (0.7906, 0.2314, 0.2162), (0.7468, 0.1400, 0.1800), (0.7057, 0.0156, 0.1502),
])
COLORMAPS: dict[str, np.ndarray] = {"viridis": _VIRIDIS, "magma": _MAGMA, "coolwarm": _COOLWARM}

# matplotlib's "tab10" without its grey (kept for NaN): neighbouring entries contrast in hue.
_SEGMENT_PALETTE = np.array([
    (0.1216, 0.4667, 0.7059), (1.0000, 0.4980, 0.0549), (0.1725, 0.6275, 0.1725),
    (0.8392, 0.1529, 0.1569), (0.5804, 0.4039, 0.7412), (0.5490, 0.3373, 0.2941),
    (0.8902, 0.4667, 0.7608), (0.7373, 0.7412, 0.1333), (0.0902, 0.7451, 0.8118),
])


def colormap(values: np.ndarray, name: str = "viridis", lo: float | None = None,
             hi: float | None = None) -> np.ndarray:
    """(V, 3) linear RGB of the scalar field ``values`` (V,) through the colormap ``name``.

    ``lo`` and ``hi`` are the values mapped to the two ends of the map (defaults: the smallest
    and largest finite value); values outside are clamped to the ends (infinities too), and
    ``lo > hi`` reverses the map. A field with no spread (``lo == hi``) maps wholly to the
    middle of the map. NaN values get ``NAN_COLOR``.
    """
    if name not in COLORMAPS:
        raise InvalidInputError(f"unknown colormap {name!r}; expected one of {', '.join(COLORMAPS)}")
    values = np.asarray(values, dtype=np.float64).reshape(-1)
    finite = np.isfinite(values)
    if lo is None or hi is None:
        if finite.any():
            low, high = values[finite].min(), values[finite].max()
        else:
            low = high = 0.0
        lo = low if lo is None else lo
        hi = high if hi is None else hi
    lo, hi = float(lo), float(hi)
    if not (np.isfinite(lo) and np.isfinite(hi)):
        raise InvalidInputError(f"colormap range must be finite, got lo={lo}, hi={hi}")
    if hi == lo:
        t = np.full(values.shape, 0.5)
    else:
        with np.errstate(invalid="ignore"):  # NaN stays NaN, and is coloured below
            t = np.clip((values - lo) / (hi - lo), 0.0, 1.0)
    table = COLORMAPS[name]
    knots = np.linspace(0.0, 1.0, len(table))
    t_safe = np.where(np.isnan(t), 0.0, t)
    srgb = np.stack([np.interp(t_safe, knots, table[:, j]) for j in range(3)], axis=1)
    out = srgb_to_linear(srgb)
    out[np.isnan(t)] = NAN_COLOR
    return out


def direction_colors(tangents: np.ndarray) -> np.ndarray:
    """(V, 3) linear RGB of the |unit tangent| colouring of diffusion-MRI viewers: x red,
    y green, z blue, in the data's own frame (for tractography: RAS, so left-right fibres are
    red, anterior-posterior green, inferior-superior blue).

    tangents: (V, 3), any length. The absolute unit tangent is the colour as those viewers
    display it (sRGB-encoded), so it is converted to linear RGB: an axis-aligned tangent is a
    pure primary either way. Zero-length or non-finite tangents get ``NAN_COLOR``.
    """
    tangents = np.asarray(tangents, dtype=np.float64).reshape(-1, 3)
    length = np.sqrt(np.square(tangents) @ np.ones(3))
    good = np.isfinite(length) & (length > 0.0)
    srgb = np.zeros(tangents.shape)
    np.divide(np.abs(tangents), length[:, None], out=srgb, where=good[:, None])
    out = srgb_to_linear(np.clip(srgb, 0.0, 1.0))
    out[~good] = NAN_COLOR
    return out


def segment_colors(segment_ids: np.ndarray) -> np.ndarray:
    """(V, 3) linear RGB of a categorical palette by segment id (V,): id k takes palette entry
    k mod 9 (matplotlib's tab10 hues, its grey left out), so consecutive ids, which the tree
    split gives to neighbouring segments, never share a colour. Ids are rounded to integers;
    NaN ids get ``NAN_COLOR``."""
    ids = np.asarray(segment_ids, dtype=np.float64).reshape(-1)
    known = np.isfinite(ids)
    index = np.mod(np.rint(np.where(known, ids, 0.0)), len(_SEGMENT_PALETTE)).astype(np.intp)
    out = srgb_to_linear(_SEGMENT_PALETTE)[index]
    out[~known] = NAN_COLOR
    return out


def srgb_to_linear(srgb: np.ndarray) -> np.ndarray:
    """The sRGB transfer function undone (IEC 61966-2-1), elementwise on values in [0, 1]."""
    srgb = np.asarray(srgb, dtype=np.float64)
    return np.where(srgb <= 0.04045, srgb / 12.92, ((srgb + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(linear: np.ndarray) -> np.ndarray:
    """The sRGB transfer function (IEC 61966-2-1), elementwise on linear values in [0, 1]."""
    linear = np.asarray(linear, dtype=np.float64)
    return np.where(linear <= 0.0031308, 12.92 * linear, 1.055 * np.power(np.maximum(linear, 0.0), 1.0 / 2.4) - 0.055)
