"""Per-vertex colours: colormaps of scalar fields, direction colours, categorical segment colours.

Every function returns (V, 3) float64 LINEAR RGB in [0, 1], what ``SurfaceMesh.colors`` holds and
what glTF's COLOR_0 and USD's displayColor mean. The colormaps are defined, as published, on
sRGB-encoded values (perceptual uniformity is a property of the encoded values): they are
interpolated in sRGB and converted to linear RGB last, so a viewer shows the published colours.

Colormaps are small tables (52 evenly spaced samples, every fifth entry of each published
256-entry map) interpolated piecewise linearly with numpy, so nothing beyond numpy is imported
at run time; they stay within 1/255 of the published entries (coolwarm: 2.5/255):

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
    (0.2670, 0.0049, 0.3294), (0.2738, 0.0315, 0.3589), (0.2788, 0.0621, 0.3866),
    (0.2819, 0.0897, 0.4124), (0.2832, 0.1157, 0.4361), (0.2826, 0.1409, 0.4575),
    (0.2803, 0.1657, 0.4765), (0.2762, 0.1901, 0.4930), (0.2706, 0.2141, 0.5071),
    (0.2637, 0.2376, 0.5188), (0.2556, 0.2607, 0.5283), (0.2468, 0.2832, 0.5359),
    (0.2374, 0.3052, 0.5419), (0.2278, 0.3266, 0.5465), (0.2181, 0.3474, 0.5500),
    (0.2086, 0.3678, 0.5527), (0.1994, 0.3876, 0.5546), (0.1906, 0.4071, 0.5561),
    (0.1823, 0.4262, 0.5571), (0.1743, 0.4450, 0.5578), (0.1666, 0.4637, 0.5581),
    (0.1592, 0.4822, 0.5581), (0.1519, 0.5007, 0.5576), (0.1448, 0.5191, 0.5566),
    (0.1378, 0.5375, 0.5549), (0.1312, 0.5559, 0.5525), (0.1254, 0.5743, 0.5491),
    (0.1211, 0.5927, 0.5446), (0.1194, 0.6111, 0.5390), (0.1214, 0.6295, 0.5320),
    (0.1281, 0.6477, 0.5235), (0.1402, 0.6659, 0.5134), (0.1579, 0.6838, 0.5017),
    (0.1807, 0.7014, 0.4882), (0.2080, 0.7187, 0.4729), (0.2394, 0.7356, 0.4557),
    (0.2741, 0.7520, 0.4366), (0.3119, 0.7678, 0.4156), (0.3524, 0.7830, 0.3926),
    (0.3952, 0.7975, 0.3678), (0.4401, 0.8111, 0.3410), (0.4870, 0.8239, 0.3123),
    (0.5356, 0.8358, 0.2819), (0.5857, 0.8467, 0.2499), (0.6369, 0.8565, 0.2166),
    (0.6889, 0.8654, 0.1827), (0.7414, 0.8734, 0.1496), (0.7938, 0.8807, 0.1200),
    (0.8456, 0.8873, 0.0997), (0.8963, 0.8936, 0.0963), (0.9456, 0.8998, 0.1128),
    (0.9932, 0.9062, 0.1439),
])
_MAGMA = np.array([
    (0.0015, 0.0005, 0.0139), (0.0076, 0.0064, 0.0450), (0.0188, 0.0160, 0.0846),
    (0.0355, 0.0284, 0.1252), (0.0566, 0.0422, 0.1674), (0.0788, 0.0542, 0.2117),
    (0.1028, 0.0630, 0.2579), (0.1294, 0.0679, 0.3054), (0.1590, 0.0684, 0.3527),
    (0.1915, 0.0648, 0.3962), (0.2253, 0.0604, 0.4317), (0.2589, 0.0597, 0.4577),
    (0.2914, 0.0646, 0.4755), (0.3229, 0.0738, 0.4874), (0.3538, 0.0854, 0.4955),
    (0.3843, 0.0979, 0.5010), (0.4147, 0.1104, 0.5047), (0.4452, 0.1227, 0.5069),
    (0.4758, 0.1346, 0.5079), (0.5066, 0.1460, 0.5078), (0.5378, 0.1569, 0.5066),
    (0.5692, 0.1675, 0.5041), (0.6009, 0.1777, 0.5004), (0.6328, 0.1879, 0.4953),
    (0.6649, 0.1981, 0.4888), (0.6971, 0.2085, 0.4808), (0.7292, 0.2194, 0.4713),
    (0.7611, 0.2312, 0.4602), (0.7924, 0.2442, 0.4475), (0.8229, 0.2590, 0.4336),
    (0.8521, 0.2761, 0.4186), (0.8795, 0.2961, 0.4031), (0.9043, 0.3196, 0.3881),
    (0.9259, 0.3468, 0.3750), (0.9440, 0.3776, 0.3651), (0.9585, 0.4113, 0.3600),
    (0.9697, 0.4469, 0.3603), (0.9782, 0.4836, 0.3660), (0.9846, 0.5207, 0.3767),
    (0.9894, 0.5579, 0.3917), (0.9928, 0.5949, 0.4103), (0.9951, 0.6317, 0.4320),
    (0.9966, 0.6683, 0.4562), (0.9973, 0.7046, 0.4826), (0.9973, 0.7408, 0.5110),
    (0.9967, 0.7768, 0.5410), (0.9957, 0.8127, 0.5726), (0.9942, 0.8485, 0.6057),
    (0.9924, 0.8843, 0.6401), (0.9906, 0.9200, 0.6757), (0.9887, 0.9557, 0.7122),
    (0.9871, 0.9914, 0.7495),
])
_COOLWARM = np.array([
    (0.2298, 0.2987, 0.7537), (0.2527, 0.3328, 0.7837), (0.2758, 0.3667, 0.8126),
    (0.2994, 0.4002, 0.8398), (0.3237, 0.4332, 0.8647), (0.3483, 0.4657, 0.8883),
    (0.3736, 0.4975, 0.9095), (0.3992, 0.5285, 0.9285), (0.4252, 0.5591, 0.9461),
    (0.4517, 0.5882, 0.9602), (0.4785, 0.6166, 0.9727), (0.5054, 0.6440, 0.9832),
    (0.5326, 0.6698, 0.9904), (0.5597, 0.6948, 0.9961), (0.5869, 0.7181, 0.9989),
    (0.6139, 0.7399, 0.9991), (0.6408, 0.7608, 0.9978), (0.6673, 0.7792, 0.9930),
    (0.6933, 0.7963, 0.9863), (0.7190, 0.8120, 0.9777), (0.7438, 0.8251, 0.9658),
    (0.7680, 0.8370, 0.9525), (0.7914, 0.8468, 0.9366), (0.8137, 0.8543, 0.9185),
    (0.8353, 0.8605, 0.8990), (0.8554, 0.8638, 0.8766), (0.8756, 0.8602, 0.8514),
    (0.8959, 0.8499, 0.8235), (0.9128, 0.8367, 0.7945), (0.9281, 0.8222, 0.7651),
    (0.9409, 0.8056, 0.7352), (0.9510, 0.7869, 0.7048), (0.9595, 0.7670, 0.6741),
    (0.9648, 0.7446, 0.6432), (0.9682, 0.7208, 0.6123), (0.9699, 0.6958, 0.5813),
    (0.9681, 0.6685, 0.5505), (0.9649, 0.6402, 0.5198), (0.9594, 0.6103, 0.4894),
    (0.9513, 0.5788, 0.4594), (0.9417, 0.5464, 0.4297), (0.9294, 0.5123, 0.4007),
    (0.9152, 0.4769, 0.3722), (0.8995, 0.4407, 0.3441), (0.8809, 0.4023, 0.3171),
    (0.8611, 0.3629, 0.2906), (0.8394, 0.3219, 0.2649), (0.8155, 0.2778, 0.2403),
    (0.7906, 0.2314, 0.2162), (0.7635, 0.1787, 0.1934), (0.7351, 0.1045, 0.1715),
    (0.7057, 0.0156, 0.1502),
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
        t = np.where(np.isnan(values), np.nan, 0.5)
    else:
        # halves: the difference of two finite doubles can overflow, of their halves never
        with np.errstate(invalid="ignore"):  # NaN stays NaN, and is coloured below
            t = np.clip((0.5 * values - 0.5 * lo) / (0.5 * hi - 0.5 * lo), 0.0, 1.0)
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
    tangents = np.abs(np.asarray(tangents, dtype=np.float64).reshape(-1, 3))
    # divided by the largest component first, so neither huge nor tiny lengths over/underflow
    largest = tangents.max(axis=1)
    good = np.isfinite(largest) & (largest > 0.0)
    scaled = np.zeros(tangents.shape)
    np.divide(tangents, largest[:, None], out=scaled, where=good[:, None])
    length = np.sqrt(np.square(scaled) @ np.ones(3))
    srgb = np.zeros(tangents.shape)
    np.divide(scaled, length[:, None], out=srgb, where=good[:, None])
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
