"""The action table: search order, guards, and discrete effects that follow from the physics."""

from __future__ import annotations

import pytest

from spec.actions import ACTION_ORDER, ACTION_RULES, Action, parse_action
from spec.constants import DEFAULT_SPEED_MPS, SEGMENT_M
from spec.errors import ActionError
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
def test_effects_match_the_semantics_table(action: Action, shift: int, ticks: int, duration_s: float) -> None:
    rule = ACTION_RULES[action]
    assert (rule.left_shift_cells, rule.oncoming_ticks, rule.duration_s) == (shift, ticks, duration_s)


@pytest.mark.parametrize("action", list(Action))
def test_discrete_effects_equal_the_relative_physical_displacement(action: Action) -> None:
    rule = ACTION_RULES[action]
    av_m = float(rule.speed_factor) * DEFAULT_SPEED_MPS * rule.duration_s
    other_m = DEFAULT_SPEED_MPS * rule.duration_s
    assert (other_m - av_m) / SEGMENT_M == pytest.approx(rule.left_shift_cells)
    assert (other_m + av_m) / SEGMENT_M == pytest.approx(rule.oncoming_ticks)


def test_lane_changes_are_guarded_by_lane() -> None:
    assert ACTION_RULES[Action.RIGHT_LANE_CHANGE].from_lane is Lane.LEFT
    assert ACTION_RULES[Action.LEFT_LANE_CHANGE].from_lane is Lane.RIGHT
    assert [a for a in Action if ACTION_RULES[a].changes_lane] == [Action.LEFT_LANE_CHANGE, Action.RIGHT_LANE_CHANGE]


def test_unknown_action_is_rejected_with_the_known_names() -> None:
    with pytest.raises(ActionError, match=r"unknown action 'fly'.*accelerate"):
        parse_action("fly")
