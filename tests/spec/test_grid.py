"""The grid as a value: every discrete number derived from physical quantities, bad cell lengths rejected."""

from __future__ import annotations

from fractions import Fraction

import pytest

from spec.actions import Action
from spec.errors import OptionError, ScenarioError
from spec.grid import PAPER_GRID, STANDARD_CELLS_M, Grid, grid_for
from spec.lanes import Lane
from spec.models import GOAL_RULES, MODEL_RULES, GoalKind, ModelKind
from spec.rules import collision_span, nearest_span
from spec.scenario import make_scenario


def test_the_paper_grid_has_the_papers_numbers() -> None:
    grid = PAPER_GRID
    assert (grid.cell, grid.speed, grid.time_unit_s, grid.av_cell, grid.road_cells) == (21.0, 7.0, 3, 10, 50)
    assert collision_span(Lane.RIGHT, MODEL_RULES[ModelKind.FINAL], grid) == (9, 11)
    assert collision_span(Lane.RIGHT, MODEL_RULES[ModelKind.PREPARATIONS], grid) == (10, 10)
    assert collision_span(Lane.LEFT, MODEL_RULES[ModelKind.FINAL], grid) == (10, 10)


@pytest.mark.parametrize(("cell_m", "av_cell", "road", "shift", "ticks", "radius"), [
    (21, 10, 50, -1, 3, 1), (10.5, 20, 100, -2, 6, 2), (7, 30, 150, -3, 9, 3), (5.25, 40, 200, -4, 12, 4)])
def test_finer_grids_cut_the_same_road_and_actions_finer(cell_m: float, av_cell: int, road: int, shift: int,
                                                         ticks: int, radius: int) -> None:
    grid = grid_for(cell_m)
    assert (grid.av_cell, grid.road_cells) == (av_cell, road)
    assert (grid.left_shift(Action.ACCELERATE), grid.ticks(Action.ACCELERATE)) == (shift, ticks)
    assert (grid.left_shift(Action.BRAKE), grid.ticks(Action.BRAKE)) == (-shift, ticks)
    assert grid.ticks(Action.DRIVE) == 2 * grid.units(Action.DRIVE)
    lo, hi = collision_span(Lane.RIGHT, MODEL_RULES[ModelKind.FINAL], grid)
    assert (av_cell - lo, hi - av_cell) == (radius, radius)  # the danger zone is 21 m on every grid
    assert nearest_span(GOAL_RULES[GoalKind.CLOSE_GAP], grid) == (av_cell + 1, av_cell + radius)


@pytest.mark.parametrize("cell_m", [10, 20, 42, 8.4, 6])
def test_a_cell_length_without_whole_effects_is_bad_input(cell_m: float) -> None:
    with pytest.raises(OptionError, match=r"--cell-m.*not a whole number"):
        Grid(Fraction(str(cell_m)))


def test_a_grid_finer_than_the_vehicle_counts_allow_is_bad_input() -> None:
    assert Grid(Fraction("4.2")).road_cells == 250  # whole effects, and still fits
    with pytest.raises(OptionError, match="too fine"):
        Grid(Fraction("3.5"))


@pytest.mark.parametrize("cell_m", [0, -21, float("nan"), float("inf"), "x", True])
def test_a_cell_length_that_is_not_a_positive_length_is_bad_input(cell_m: object) -> None:
    with pytest.raises(OptionError, match=r"--cell-m"):
        grid_for(cell_m)


def test_the_standard_grids_are_equal_values_and_the_paper_grid_is_the_default() -> None:
    assert grid_for(None) is PAPER_GRID and grid_for(21.0) is PAPER_GRID
    assert {Grid(c) for c in STANDARD_CELLS_M} == {grid_for(float(c)) for c in STANDARD_CELLS_M}
    assert make_scenario("left", [], []).grid is PAPER_GRID


def test_a_scenario_on_a_finer_grid_checks_its_own_window() -> None:
    fine = grid_for(10.5)
    assert make_scenario("left", [100], [], cell_m=10.5).grid == fine
    with pytest.raises(ScenarioError, match=r"left_lane\[0\]=101: cell outside the sensed window 0..100"):
        make_scenario("left", [101], [], cell_m=10.5)
    with pytest.raises(ScenarioError, match=r"cell_m=10: .*not a whole number"):
        make_scenario("left", [], [], cell_m=10)
    with pytest.raises(ScenarioError, match="initial collision"):
        make_scenario("right", [], [21], cell_m=10.5, model="final")  # within 21 m of the AV at cell 20
