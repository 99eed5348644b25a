"""weld_by_position: the first vertex at each bit-identical position, by hashing and exact checks."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from cgamesh.meshing import weld


def exact_weld(positions: np.ndarray) -> np.ndarray:
    """The reference: an exact sort of the rows' bytes (-0.0 taken as 0.0)."""
    rows = np.ascontiguousarray(positions, dtype=np.float64) + 0.0
    keys = rows.view(np.dtype((np.void, 24))).ravel()
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    return first[inverse.ravel()]


values = st.sampled_from([0.0, -0.0, 1.0, -1.0, 0.5, 1e-300, 3.0e38, np.nan, np.inf, 2.0])
rows = st.lists(st.tuples(values, values, values), min_size=1, max_size=60)


@given(rows)
def test_weld_matches_an_exact_sort_of_the_rows(data):
    positions = np.array(data, dtype=np.float64)
    assert np.array_equal(weld.weld_by_position(positions), exact_weld(positions))


@pytest.mark.parametrize("mix", [(0, 0, 0), (1, 0, 0)])
@given(data=rows)
def test_hash_collisions_are_resolved_exactly(mix, data):
    """With a hash that collides (constant, or one coordinate only) the answer is still exact."""
    positions = np.array(data, dtype=np.float64)
    saved = weld._MIX, weld._BLOCK
    weld._MIX = tuple(np.uint64(m) for m in mix)
    weld._BLOCK = 3  # runs that straddle the blocks the repeated rows are checked in
    try:
        assert np.array_equal(weld.weld_by_position(positions), exact_weld(positions))
    finally:
        weld._MIX, weld._BLOCK = saved


def test_a_seam_grid_welds_its_repeated_column():
    rng = np.random.default_rng(3)
    positions = rng.normal(size=(9000, 3))
    positions[8::9] = positions[0::9]  # each ring of 9 repeats its first vertex
    result = weld.weld_by_position(positions)
    expected = np.arange(len(positions))
    expected[8::9] = expected[0::9]
    assert np.array_equal(result, expected)
    assert np.array_equal(result, exact_weld(positions))


def test_empty_and_single():
    assert weld.weld_by_position(np.zeros((0, 3))).shape == (0,)
    assert weld.weld_by_position(np.zeros((1, 3))).tolist() == [0]
