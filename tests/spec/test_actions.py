"""The action table: search order, guards, and the physics every grid derives its effects from."""

from __future__ import annotations

import pytest

from spec.actions import ACTION_ORDER, ACTION_RULES, Action, parse_action
from spec.errors import ActionError
from spec.grid import PAPER_GRID, STANDARD_CELLS_M, Grid
from spec.lanes import Lane


def test_search_order_is_the_papers() -> None:
    assert [a.value for a in ACTION_ORDER] == ["left_lane_change", "accelerate", "right_lane_change", "drive", "brake"]


@pytest.mark.parametrize(
    ("action", "shift", "ticks", "duration_s"),
    [
        (Action.DRIVE, 0, 2, 3.0),
        (Action.LEFT_LANE_CHANGE, 0, 2, 3.0),
        (Action.RIGHT_LANE_CHANGE, 0, 2, 3.0),
        (Action.ACCELERATE, -1, 3, 3.0),
        (Action.BRAKE, 1, 3, 6.0),
    ],
)
def test_effects_on_the_paper_grid_match_the_semantics_table(action: Action, shift: int, ticks: int,
                                                              duration_s: float) -> None:
    grid = PAPER_GRID
    assert (grid.left_shift(action), grid.ticks(action), ACTION_RULES[action].duration_s) == (shift, ticks, duration_s)


@pytest.mark.parametrize("cell_m", STANDARD_CELLS_M, ids=lambda c: f"{float(c):g}m")
@pytest.mark.parametrize("action", list(Action))
def test_discrete_effects_equal_the_relative_physical_displacement_on_every_grid(action: Action, cell_m) -> None:
    grid, rule = Grid(cell_m), ACTION_RULES[action]
    av_m = rule.speed_factor * grid.speed_mps * rule.duration_s
    other_m = grid.speed_mps * rule.duration_s
    assert (other_m - av_m) / grid.cell_m == grid.left_shift(action)
    assert (other_m + av_m) / grid.cell_m == grid.ticks(action)


def test_lane_changes_are_guarded_by_lane() -> None:
    assert ACTION_RULES[Action.RIGHT_LANE_CHANGE].from_lane is Lane.LEFT
    assert ACTION_RULES[Action.LEFT_LANE_CHANGE].from_lane is Lane.RIGHT
    assert [a for a in Action if ACTION_RULES[a].changes_lane] == [Action.LEFT_LANE_CHANGE, Action.RIGHT_LANE_CHANGE]


def test_unknown_action_is_rejected_with_the_known_names() -> None:
    with pytest.raises(ActionError, match=r"unknown action 'fly'.*accelerate"):
        parse_action("fly")
