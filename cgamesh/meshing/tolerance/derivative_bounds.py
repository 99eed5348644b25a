"""Bounds of a curve's first and second derivatives over each cell of a dense sampling.

A surface's members (circle centre, radius and plane normal; a ruling's end points) are
smooth within each segment of the curve (the projection of a polynomial or rational curve,
paper section 6) but only continuous, or once differentiable, at the joints. Sampled at
S + 1 evenly spaced parameters per segment (spacing delta), divided differences are exact
values of derivatives at unknown points (the mean-value theorem for divided differences,
component by component):

    D1_i = (f_i+1 - f_i) / delta                          = f'(xi),   xi in [t_i, t_i+1]
    D2_i = (f_i+1 - 2 f_i + f_i-1) / delta^2              = f''(xi),  xi in [t_i-1, t_i+1]
    D3_i = (f_i+2 - 3 f_i+1 + 3 f_i - f_i-1) / delta^3    = f'''(xi), xi in [t_i-1, t_i+2]

The differences are also weighted means of the derivatives (their Peano kernels):

    D2_i = integral over s in [-1, 1] of f''(t_i + s delta) (1 - |s|) ds,
    D1_i = integral over s in [0, 1] of f'(t_i + s delta) ds,

so at a point x, |f''(x) - D2_i| <= L3 (|x - t_i| + delta / 3) (the hat kernel's mean |s| is
1/3), where L3 bounds |f'''| over the neighbourhood: a point of cell i is within delta / 2 of
sample i or i + 1 (within delta of the one inside, in a segment's end cells). Likewise
|f'(x) - D1_i| <= (delta / 2) max |f''| over the cell. L3 is LIPSCHITZ_SAFETY times the
largest neighbouring |D3| (f''' itself varies between the samples; the factor covers that
variation, which is what the property tests check). A rounding allowance for the differences
of float64 read-outs is added. Differences never straddle a joint: each segment is sampled and
differenced on its own.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# The largest neighbouring third difference, times this, bounds |f'''| over a cell's neighbourhood.
LIPSCHITZ_SAFETY = 2.0
# Relative rounding error of the sampled read-outs (projection, square roots): the divided
# differences get an allowance of this times the values' magnitude over delta^k.
READ_OUT_ROUNDING = 1e-12
# At least this many cells per segment (third differences need four samples).
MIN_CELLS = 4


def segment_samples(segment_count: int, cells: int) -> np.ndarray:
    """Parameters (segments, cells + 1): each segment [s, s + 1] split into ``cells`` cells."""
    fraction = np.linspace(0.0, 1.0, cells + 1)
    return np.arange(segment_count, dtype=np.float64)[:, None] + fraction[None, :]


@dataclass(frozen=True)
class CellDerivatives:
    """Per cell (segments, S, d), component by component: |f| bounded by ``value``; f' within
    ``first_radius`` of ``first``, f'' within ``second_radius`` of ``second``, everywhere in the cell."""

    value: np.ndarray
    first: np.ndarray
    first_radius: np.ndarray
    second: np.ndarray
    second_radius: np.ndarray

    def columns(self, start: int, stop: int) -> CellDerivatives:
        """The bounds of components start..stop-1 alone: every bound is taken component by
        component, so one call on stacked members gives each member's own bounds, bit for bit."""
        pick = slice(start, stop)
        return CellDerivatives(self.value[..., pick], self.first[..., pick], self.first_radius[..., pick],
                               self.second[..., pick], self.second_radius[..., pick])

    def norms(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Upper bounds (segments, S) of |f|, |f'| and |f''| (Euclidean norms) over each cell."""
        return (lengths(self.value), lengths(np.abs(self.first) + self.first_radius),
                lengths(np.abs(self.second) + self.second_radius))


def lengths(x: np.ndarray) -> np.ndarray:
    """Euclidean lengths over the last axis (the bounds' one formula for them)."""
    return np.sqrt(np.sum(x * x, axis=-1))


def cell_derivatives(values: np.ndarray) -> CellDerivatives:
    """Estimates with proven radii (given the Lipschitz margin) of f' and f'' over each cell.

    values (segments, S + 1, d): f sampled by ``segment_samples`` (parameter spacing 1 / S).
    """
    segments, samples, _ = values.shape
    cells = samples - 1
    if cells < MIN_CELLS:
        raise ValueError(f"need at least {MIN_CELLS} cells per segment, got {cells}")
    delta = 1.0 / cells
    magnitude = np.max(np.abs(values), axis=1, keepdims=True)  # (segments, 1, d)
    rounding = READ_OUT_ROUNDING * np.maximum(magnitude, np.finfo(float).tiny)

    # the differences of each order from the last one's (what np.diff(values, n=k) computes)
    first_differences = np.diff(values, axis=1)
    second_differences = np.diff(first_differences, axis=1)
    d1 = first_differences / delta  # (segments, S, d): f' somewhere in cell i
    d2 = second_differences / delta ** 2  # f'' at samples 1..S-1 (within a delta)
    d3 = np.abs(np.diff(second_differences, axis=1)) / delta ** 3 + 8.0 * rounding / delta ** 3

    # Third derivative over the neighbourhood [t_i-2, t_i+3] of cell i: the D3 taken there
    # (entry m of d3 spans samples m .. m+3; cell i wants m = i-2 .. i, clipped at the ends):
    # the largest of three shifted copies of d3 padded with its end entries.
    padded = np.concatenate([d3[:, :1], d3[:, :1], d3, d3[:, -1:], d3[:, -1:]], axis=1)
    third = LIPSCHITZ_SAFETY * np.maximum(np.maximum(padded[:, :-2], padded[:, 1:-1]), padded[:, 2:])

    # A point of cell i is within delta / 2 of sample i or i+1, where D2 (a hat-weighted mean of
    # f'' over one spacing each side, mean distance delta / 3) was taken; at the ends of a
    # segment only the sample inside has a D2, within delta (cell 0 uses D2 at sample 1, the
    # last cell at S-1). So f'' there is within half their difference plus
    # (distance + delta / 3) L3 of their mean.
    second_at = np.concatenate([d2[:, :1], d2, d2[:, -1:]], axis=1)  # index j <-> D2 at sample j
    left, right = second_at[:, :-1], second_at[:, 1:]
    second = 0.5 * (left + right)
    reach = np.full(cells, 0.5 * delta)
    reach[[0, -1]] = delta
    second_radius = (0.5 * np.abs(left - right) + (reach + delta / 3.0)[None, :, None] * third
                     + 4.0 * rounding / delta ** 2)
    # D1 is the mean of f' over the cell: f' anywhere in it is within (delta / 2) max |f''|.
    first_radius = 0.5 * delta * (np.abs(second) + second_radius) + 2.0 * rounding / delta
    value = np.maximum(np.abs(values[:, :-1]), np.abs(values[:, 1:])) + 0.5 * delta * (np.abs(d1) + first_radius)
    return CellDerivatives(value, d1, first_radius, second, second_radius)


def cell_bounds(values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per cell upper bounds (segments, S) of |f|, |f'| and |f''| (Euclidean norms) over each cell."""
    return cell_derivatives(values).norms()
