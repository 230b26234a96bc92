"""The discretisation rules of spec/cells.py: metres to cells."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from spec.cells import first_platoon, left_cell, oncoming_cell
from spec.grid import PAPER_GRID, STANDARD_CELLS_M, Grid
from spec.lanes import Lane

metres = st.floats(min_value=-300.0, max_value=500.0, allow_nan=False)
grids = st.sampled_from([Grid(c) for c in STANDARD_CELLS_M])
AV = PAPER_GRID.av_cell


def test_left_lane_vehicles_go_to_the_nearest_cell() -> None:
    grid = PAPER_GRID
    assert left_cell(10.4, Lane.RIGHT, grid) == AV and left_cell(10.6, Lane.RIGHT, grid) == AV + 1
    assert left_cell(-10.6, Lane.RIGHT, grid) == AV - 1 and left_cell(42.0, Lane.LEFT, grid) == AV + 2
    assert left_cell(10.6, Lane.RIGHT, Grid(10.5)) == 21  # the AV's cell is 20 on the 10.5 m grid


@given(metres.filter(lambda dx: dx != 0), grids)
def test_own_lane_vehicle_is_never_in_the_avs_cell_and_stays_on_its_side(dx_m: float, grid: Grid) -> None:
    cell = left_cell(dx_m, Lane.LEFT, grid)
    assert cell != grid.av_cell
    assert (cell > grid.av_cell) == (dx_m > 0)


@given(metres, grids)
def test_oncoming_cell_is_never_farther_from_the_av_than_the_vehicle(dx_m: float, grid: Grid) -> None:
    cell_m = (oncoming_cell(dx_m, grid) - grid.av_cell) * grid.cell
    assert abs(cell_m) <= abs(dx_m) < abs(cell_m) + grid.cell


def test_targets_are_the_first_platoon_ahead_at_most_three() -> None:
    grid = PAPER_GRID
    assert first_platoon([5, 11, 12, 13, 14], Lane.LEFT, grid) == 3
    assert first_platoon([11, 13], Lane.LEFT, grid) == 1
    assert first_platoon([10, 11, 20], Lane.RIGHT, grid) == 2
    assert first_platoon([10, 11, 20], Lane.LEFT, grid) == 1
    assert first_platoon([5], Lane.LEFT, grid) == 0


@given(grids)
def test_a_platoon_is_the_same_vehicles_on_every_grid(grid: Grid) -> None:
    """Vehicles one paper cell (21 m) apart are one platoon however finely the road is cut."""
    per = round(PAPER_GRID.cell / grid.cell)
    ahead = [grid.av_cell + per * k for k in (1, 2, 3, 4)]
    assert first_platoon(ahead, Lane.LEFT, grid) == 3
    assert first_platoon([ahead[0], ahead[0] + 2 * per], Lane.LEFT, grid) == 1
