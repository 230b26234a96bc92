"""Rule coverage sees grids: a left-lane vehicle passed through is its own rule, exercised only where an action moves
the left lane by more than one cell, and a coverage target names the rules a campaign on a grid must meet."""

from __future__ import annotations

import pytest

from oracle.coverage import ALL_RULES, IN_PASSING, CoverageTarget, grid_rules, rules_exercised, rules_on
from spec.actions import Action
from spec.grid import PAPER_GRID, STANDARD_CELLS_M, Grid
from spec.scenario import make_scenario

FINER = [Grid(c) for c in STANDARD_CELLS_M if Grid(c) != PAPER_GRID]


def test_the_paper_grid_has_no_rule_of_its_own_and_every_finer_grid_has_the_passing_rule() -> None:
    assert grid_rules(PAPER_GRID) == () and IN_PASSING not in rules_on(PAPER_GRID)
    for grid in FINER:
        assert grid_rules(grid) == (IN_PASSING,) and rules_on(grid) == ALL_RULES


@pytest.mark.parametrize("grid", FINER, ids=lambda g: g.describe())
def test_a_vehicle_one_cell_ahead_is_hit_in_passing_on_a_finer_grid(grid: Grid) -> None:
    """Accelerating moves it |shift| > 1 cells back: it is hit in the AV's cell, before the cell where it ends."""
    scenario = make_scenario("left", [grid.av_cell + 1], [], 1, grid=grid)
    assert abs(grid.left_shift(Action.ACCELERATE)) > 1
    assert {"collision: left lane", IN_PASSING} <= rules_exercised(scenario)


@pytest.mark.parametrize("grid", FINER, ids=lambda g: g.describe())
def test_a_vehicle_hit_where_it_ends_is_not_in_passing(grid: Grid) -> None:
    """A vehicle exactly one shift ahead ends in the AV's cell (the AV alone in the left lane, one action): a left-lane
    collision, but not one in passing; the only other reachable left-lane collisions come later, from other cells."""
    shift = abs(grid.left_shift(Action.ACCELERATE))
    scenario = make_scenario("left", [grid.av_cell + shift], [], 1, horizon=1, grid=grid)
    found = rules_exercised(scenario)
    assert "collision: left lane" in found and IN_PASSING not in found


def test_the_paper_grid_never_hits_in_passing() -> None:
    for cell in range(PAPER_GRID.av_cell - 3, PAPER_GRID.av_cell + 4):
        if cell != PAPER_GRID.av_cell:
            assert IN_PASSING not in rules_exercised(make_scenario("left", [cell], [], 0))


def test_coverage_targets_name_the_rules_per_grid() -> None:
    assert CoverageTarget.NONE.rules(Grid(10.5)) == ()
    assert CoverageTarget.GRID.rules(PAPER_GRID) == () and CoverageTarget.GRID.rules(Grid(10.5)) == (IN_PASSING,)
    assert CoverageTarget.ALL.rules(PAPER_GRID) == rules_on(PAPER_GRID)


def test_a_hit_in_passing_that_a_landing_only_rule_rejects_anyway_is_not_counted() -> None:
    """Two vehicles at av+1 and av+2 on the 10.5 m grid: accelerating hits the first in passing, but the second lands
    in the AV's cell, so a rule that checked only where vehicles end rejects the step too: nothing is decided
    differently from the paper's grid."""
    grid = Grid(10.5)
    scenario = make_scenario("left", [grid.av_cell + 1, grid.av_cell + 2], [], 1, horizon=1, grid=grid)
    found = rules_exercised(scenario)
    assert "collision: left lane" in found and IN_PASSING not in found
