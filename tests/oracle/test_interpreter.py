"""One test per rule of the transition system, and the paper's worked example as a golden test."""

from __future__ import annotations

import pytest

from oracle.interpreter import step as grid_step
from oracle.interpreter import validate
from spec.actions import Action
from spec.grid import PAPER_GRID, STANDARD_CELLS_M, Grid
from spec.lanes import Lane
from spec.models import GOAL_RULES, MODEL_RULES, GoalKind, GoalRule, ModelKind, ModelRules
from spec.rules import disabled_reason, goal_holds
from spec.scenario import make_scenario, problem_for
from spec.state import Collision, State

AV_CELL = PAPER_GRID.av_cell


def step(state: State, action: Action, rules: ModelRules) -> State | Collision:
    """One step on the paper's grid."""
    return grid_step(state, action, rules, PAPER_GRID)


def goal(state: State, rule: GoalRule, targets: tuple[int, ...]) -> bool:
    return goal_holds(state, rule, targets, PAPER_GRID)

FINAL = MODEL_RULES[ModelKind.FINAL]
PREP = MODEL_RULES[ModelKind.PREPARATIONS]


def left(cells: list[int], oncoming: list[int] | None = None, **kw: int) -> State:
    return State(Lane.LEFT, tuple(cells), tuple(oncoming or []), **kw)


def right(cells: list[int], oncoming: list[int] | None = None, **kw: int) -> State:
    return State(Lane.RIGHT, tuple(cells), tuple(oncoming or []), **kw)


# -- the paper's worked example (Figure 3): accelerate, right lane change, brake ----------
PAPER_START = left([12, 14], [30])


@pytest.mark.parametrize(
    ("action", "expected"),
    [
        (Action.ACCELERATE, left([11, 13], [27], steps=1)),
        (Action.RIGHT_LANE_CHANGE, right([12, 14], [28], lane_changes=1, steps=1)),
        (Action.BRAKE, left([13, 15], [27], steps=1)),
    ],
)
def test_paper_worked_example_golden(action: Action, expected: State) -> None:
    assert step(PAPER_START, action, FINAL) == expected


def test_step_never_mutates_its_input() -> None:
    before = left([12], [30])
    step(before, Action.ACCELERATE, FINAL)
    assert before == left([12], [30])


# -- guards ---------------------------------------------------------------------------------
def test_guard_right_lane_change_only_from_left() -> None:
    assert disabled_reason(left([]), Action.RIGHT_LANE_CHANGE, FINAL) is None
    assert "left lane" in (disabled_reason(right([]), Action.RIGHT_LANE_CHANGE, FINAL) or "")


def test_guard_left_lane_change_only_from_right() -> None:
    assert disabled_reason(right([]), Action.LEFT_LANE_CHANGE, FINAL) is None
    assert "right lane" in (disabled_reason(left([]), Action.LEFT_LANE_CHANGE, FINAL) or "")


@pytest.mark.parametrize(("rules", "limit"), [(FINAL, 2), (PREP, 1)])
def test_guard_lane_change_limit(rules, limit: int) -> None:
    assert disabled_reason(left([], lane_changes=limit - 1), Action.RIGHT_LANE_CHANGE, rules) is None
    assert "at most" in (disabled_reason(left([], lane_changes=limit), Action.RIGHT_LANE_CHANGE, rules) or "")
    assert "at most" in (disabled_reason(right([], lane_changes=limit), Action.LEFT_LANE_CHANGE, rules) or "")


@pytest.mark.parametrize("action", [Action.ACCELERATE, Action.DRIVE, Action.BRAKE])
def test_guard_other_actions_always_enabled(action: Action) -> None:
    for state in (left([], lane_changes=2), right([], lane_changes=2)):
        assert disabled_reason(state, action, FINAL) is None


def test_disabled_action_raises() -> None:
    with pytest.raises(ValueError, match="left lane"):
        step(right([]), Action.RIGHT_LANE_CHANGE, FINAL)


# -- effects and ticks ----------------------------------------------------------------------
@pytest.mark.parametrize(
    ("action", "left_after", "oncoming_after"),
    [
        (Action.DRIVE, [15, 20], [38]),
        (Action.ACCELERATE, [14, 19], [37]),
        (Action.BRAKE, [16, 21], [37]),
    ],
)
def test_effect_and_ticks(action: Action, left_after: list[int], oncoming_after: list[int]) -> None:
    assert step(left([15, 20], [40]), action, FINAL) == left(left_after, oncoming_after, steps=1)


def test_lane_change_flips_lane_and_counts() -> None:
    after = step(left([15], [40]), Action.RIGHT_LANE_CHANGE, FINAL)
    assert after == right([15], [38], lane_changes=1, steps=1)
    back = step(after, Action.LEFT_LANE_CHANGE, FINAL)
    assert back == left([15], [36], lane_changes=2, steps=2)


def test_cells_are_never_clipped() -> None:
    state = left([0], [1])
    for _ in range(3):
        state = step(state, Action.BRAKE, FINAL)  # type: ignore[assignment]
    assert state == left([3], [-8], steps=3)


# -- collisions and the danger zone ----------------------------------------------------------
def test_collision_left_lane_vehicle_at_av_cell() -> None:
    hit = step(left([AV_CELL + 1]), Action.ACCELERATE, FINAL)
    assert isinstance(hit, Collision) and (hit.lane, hit.vehicle, hit.cell, hit.tick) == (Lane.LEFT, 0, AV_CELL, 0)


def test_left_lane_vehicle_ignored_while_av_in_right_lane() -> None:
    assert not isinstance(step(right([AV_CELL + 1]), Action.ACCELERATE, FINAL), Collision)


def test_collision_after_an_intermediate_tick() -> None:
    # an oncoming vehicle passes through the danger zone during the ticks of one action
    hit = step(right([], [AV_CELL + 4]), Action.ACCELERATE, FINAL)
    assert isinstance(hit, Collision) and (hit.lane, hit.cell, hit.tick) == (Lane.RIGHT, AV_CELL + 1, 3)


@pytest.mark.parametrize(("rules", "cell", "collides"), [
    (FINAL, AV_CELL + 3, True),   # 3 -> 2 -> 1 (inside radius 1)
    (PREP, AV_CELL + 3, False),   # 3 -> 2 -> 1: radius 0 never reached
    (PREP, AV_CELL + 2, True),    # 2 -> 1 -> 0
])
def test_danger_radius(rules, cell: int, collides: bool) -> None:
    assert isinstance(step(right([], [cell]), Action.DRIVE, rules), Collision) is collides


def test_lane_change_into_a_vehicle_collides_after_the_effect() -> None:
    hit = step(right([AV_CELL]), Action.LEFT_LANE_CHANGE, FINAL)
    assert isinstance(hit, Collision) and hit.tick == 0


def test_oncoming_ignored_while_av_in_left_lane() -> None:
    assert not isinstance(step(left([], [AV_CELL]), Action.DRIVE, FINAL), Collision)


# -- goals -------------------------------------------------------------------------------------
OVERTAKE, RETURN, CLOSE = (GOAL_RULES[k] for k in GoalKind)


def test_goal_final_every_target_behind_in_left_lane() -> None:
    assert goal(left([8, 9, 30]), OVERTAKE, (0, 1))
    assert not goal(left([8, 10, 30]), OVERTAKE, (0, 1))
    assert not goal(right([8, 9, 30]), OVERTAKE, (0, 1))


def test_goal_case_a_back_left_with_oncoming_passed() -> None:
    assert goal(left([5, 12], [10]), RETURN, ())
    assert not goal(left([5, 12], [11]), RETURN, ())
    assert not goal(right([5, 12], [3]), RETURN, ())


def test_goal_case_b_gap_closed_with_oncoming_passed() -> None:
    assert goal(left([AV_CELL + 1, 20], [4]), CLOSE, (0,))
    assert not goal(left([AV_CELL + 2, 20], [4]), CLOSE, (0,))
    assert not goal(left([AV_CELL + 1, 20], [12]), CLOSE, (0,))
    assert not goal(left([AV_CELL + 1]), CLOSE, ())  # no target: nothing to close on


def test_preparations_goal_follows_the_starting_lane() -> None:
    assert problem_for(make_scenario("right", [], [30]), ModelKind.PREPARATIONS).goal.kind is GoalKind.RETURN_LEFT
    assert problem_for(make_scenario("left", [12], [30], 1), ModelKind.PREPARATIONS).goal.kind is GoalKind.CLOSE_GAP


# -- the horizon and validation ------------------------------------------------------------------
def test_horizon_bounds_plan_length() -> None:
    scenario = make_scenario("left", [12], [], 1, horizon=4)
    plan = [Action.ACCELERATE, Action.RIGHT_LANE_CHANGE, Action.ACCELERATE, Action.ACCELERATE, Action.LEFT_LANE_CHANGE]
    verdict = validate(problem_for(scenario, ModelKind.FINAL), plan)
    assert not verdict.valid and "horizon of 4" in verdict.reason
    assert validate(problem_for(scenario, ModelKind.FINAL, horizon=5), plan).valid


def test_validate_rejects_a_plan_passing_through_the_goal_early() -> None:
    scenario = make_scenario("left", [], [], 0)
    verdict = validate(problem_for(scenario, ModelKind.FINAL), [Action.DRIVE])
    assert not verdict.valid and "goal already reached before step 1" in verdict.reason


def test_validate_reports_the_collision_and_states_so_far() -> None:
    scenario = make_scenario("left", [12], [], 1)
    verdict = validate(problem_for(scenario, ModelKind.FINAL), [Action.ACCELERATE, Action.ACCELERATE])
    assert not verdict.valid and "step 2 (accelerate): collision with left_lane[0] at cell 10" in verdict.reason
    assert len(verdict.states) == 2


@pytest.mark.parametrize("grid", [Grid(c) for c in STANDARD_CELLS_M], ids=lambda g: g.describe())
def test_no_left_lane_vehicle_passes_through_the_av_on_any_grid(grid: Grid) -> None:
    """On a finer grid an action moves the left lane by several cells: the vehicle passes every cell between."""
    av, ahead = grid.av_cell, abs(grid.left_shift(Action.ACCELERATE))
    for cell, action in ((av + 1, Action.ACCELERATE), (av - 1, Action.BRAKE)):
        hit = grid_step(left([cell]), action, FINAL, grid)
        assert isinstance(hit, Collision) and hit.cell == av, (cell, action, hit)
    assert not isinstance(grid_step(left([av + ahead + 1]), Action.ACCELERATE, FINAL, grid), Collision)
    scenario = make_scenario("left", [av + 1], [], 1, grid=grid)
    assert not validate(problem_for(scenario, ModelKind.FINAL), [Action.ACCELERATE]).valid
