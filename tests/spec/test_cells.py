"""The discretisation rules of spec/cells.py: metres to cells."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from spec.cells import first_platoon, left_cell, oncoming_cell
from spec.constants import AV_CELL, SEGMENT_M
from spec.lanes import Lane

metres = st.floats(min_value=-300.0, max_value=500.0, allow_nan=False)


def test_left_lane_vehicles_go_to_the_nearest_cell() -> None:
    assert left_cell(10.4, Lane.RIGHT) == AV_CELL and left_cell(10.6, Lane.RIGHT) == AV_CELL + 1
    assert left_cell(-10.6, Lane.RIGHT) == AV_CELL - 1 and left_cell(2 * SEGMENT_M, Lane.LEFT) == AV_CELL + 2


@given(metres.filter(lambda dx: dx != 0))
def test_own_lane_vehicle_is_never_in_the_avs_cell_and_stays_on_its_side(dx_m: float) -> None:
    cell = left_cell(dx_m, Lane.LEFT)
    assert cell != AV_CELL
    assert (cell > AV_CELL) == (dx_m > 0)


@given(metres)
def test_oncoming_cell_is_never_farther_from_the_av_than_the_vehicle(dx_m: float) -> None:
    cell_m = (oncoming_cell(dx_m) - AV_CELL) * SEGMENT_M
    assert abs(cell_m) <= abs(dx_m) < abs(cell_m) + SEGMENT_M


def test_targets_are_the_first_platoon_ahead_at_most_three() -> None:
    assert first_platoon([5, 11, 12, 13, 14], Lane.LEFT) == 3
    assert first_platoon([11, 13], Lane.LEFT) == 1
    assert first_platoon([10, 11, 20], Lane.RIGHT) == 2
    assert first_platoon([10, 11, 20], Lane.LEFT) == 1
    assert first_platoon([5], Lane.LEFT) == 0
