"""A cell means anywhere within it: each extent holds every distance the discretiser puts in that cell, and no more
(its ends are limits of such distances)."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from spec.cells import left_cell, left_extent_m, oncoming_cell, oncoming_extent_m
from spec.grid import STANDARD_CELLS_M, Grid
from spec.lanes import Lane

GRIDS = st.sampled_from([Grid(c) for c in STANDARD_CELLS_M])
DISTANCES = st.floats(-300.0, 900.0, allow_nan=False)


@given(GRIDS, st.sampled_from(list(Lane)), DISTANCES)
def test_a_same_direction_vehicle_lies_in_the_extent_of_its_cell(grid: Grid, lane: Lane, dx_m: float) -> None:
    lo, hi = left_extent_m(left_cell(dx_m, lane, grid), lane, grid)
    assert lo <= dx_m <= hi


@given(GRIDS, DISTANCES)
def test_an_oncoming_vehicle_lies_in_the_extent_of_its_cell(grid: Grid, dx_m: float) -> None:
    lo, hi = oncoming_extent_m(oncoming_cell(dx_m, grid), grid)
    assert lo <= dx_m <= hi


@pytest.mark.parametrize("grid", [Grid(c) for c in STANDARD_CELLS_M], ids=lambda g: g.describe())
@pytest.mark.parametrize("lane", list(Lane))
def test_each_extent_is_no_wider_than_what_its_cell_takes(grid: Grid, lane: Lane) -> None:
    """Just inside either end of an extent the discretiser still gives that cell (the ends are tight)."""
    eps = 1e-6
    for cell in range(grid.av_cell - 4, grid.av_cell + 5):
        if not (cell == grid.av_cell and lane is Lane.LEFT):
            lo, hi = left_extent_m(cell, lane, grid)
            assert {left_cell(lo + eps, lane, grid), left_cell(hi - eps, lane, grid)} == {cell}
        lo, hi = oncoming_extent_m(cell, grid)
        assert {oncoming_cell(lo + eps, grid), oncoming_cell(hi - eps, grid)} == {cell}
