"""The reference interpreter: the readable meaning of one decision step, goals, and plan validation.

Pure functions over frozen values: ``step`` returns a new state (or the collision),
never mutating its input.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

from spec.actions import ACTION_RULES, Action
from spec.constants import AV_CELL
from spec.lanes import Lane
from spec.models import GoalRule, ModelRules
from spec.scenario import Collision, Problem, State


def disabled_reason(state: State, action: Action, rules: ModelRules) -> str | None:
    """Why ``action`` is not enabled in ``state``, or None when it is."""
    rule = ACTION_RULES[action]
    if rule.from_lane is not None and state.lane is not rule.from_lane:
        return f"{action.value} needs the AV in the {rule.from_lane.value} lane"
    if rule.changes_lane and state.lane_changes >= rules.max_lane_changes:
        return f"{action.value}: the {rules.kind.value} model allows at most {rules.max_lane_changes} lane changes"
    return None


def enabled_actions(state: State, rules: ModelRules) -> list[Action]:
    """The enabled actions, in the search order."""
    return [a for a in Action if disabled_reason(state, a, rules) is None]


def collision_in(state: State, rules: ModelRules, tick: int) -> Collision | None:
    """The collision in ``state``, if any: a left-lane vehicle at the AV, or an oncoming one too near."""
    if state.lane is Lane.LEFT:
        for i, cell in enumerate(state.left_lane):
            if cell == AV_CELL:
                return Collision(state, Lane.LEFT, i, cell, tick)
    else:
        for i, cell in enumerate(state.right_lane):
            if abs(cell - AV_CELL) <= rules.danger_radius:
                return Collision(state, Lane.RIGHT, i, cell, tick)
    return None


def step(state: State, action: Action, rules: ModelRules) -> State | Collision:
    """One decision step: effect, collision check, oncoming ticks each followed by a check."""
    reason = disabled_reason(state, action, rules)
    if reason is not None:
        raise ValueError(reason)
    rule = ACTION_RULES[action]
    shift = rule.left_shift_cells
    after = replace(
        state,
        lane=rule.to_lane or state.lane,
        left_lane=tuple(cell + shift for cell in state.left_lane),
        lane_changes=state.lane_changes + int(rule.changes_lane),
        steps=state.steps + 1,
    )
    hit = collision_in(after, rules, 0)
    for tick in range(1, rule.oncoming_ticks + 1):
        if hit is not None:
            return hit
        after = replace(after, right_lane=tuple(cell - 1 for cell in after.right_lane))
        hit = collision_in(after, rules, tick)
    return hit if hit is not None else after


def goal(state: State, rule: GoalRule, targets: Sequence[int]) -> bool:
    """Whether ``state`` meets the goal; ``targets`` are indices into ``state.left_lane``."""
    if rule.av_lane is not None and state.lane is not rule.av_lane:
        return False
    if rule.targets_behind and any(state.left_lane[i] >= AV_CELL for i in targets):
        return False
    if rule.nearest_target_offset is not None:
        if not targets or state.left_lane[targets[0]] != AV_CELL + rule.nearest_target_offset:
            return False
    if rule.oncoming_passed and any(cell > AV_CELL for cell in state.right_lane):
        return False
    return True


def problem_goal(problem: Problem, state: State) -> bool:
    """Whether ``state`` meets the goal of ``problem``."""
    return goal(state, problem.goal, problem.scenario.target_indices)


@dataclass(frozen=True, slots=True)
class Validation:
    """The verdict on an action list: valid or not, why, and the state after every step."""

    valid: bool
    reason: str
    states: tuple[State, ...]  # the initial state, then one per executed step


def validate(problem: Problem, actions: Sequence[Action]) -> Validation:
    """Check that ``actions`` is a plan: enabled, collision-free, within the horizon, goal first at the end."""
    state = problem.scenario.initial_state()
    states = [state]
    start_hit = collision_in(state, problem.rules, 0)
    if start_hit is not None:
        return Validation(False, f"initial state: {start_hit.describe()}", tuple(states))
    if len(actions) > problem.horizon:
        return Validation(False, f"{len(actions)} actions exceed the horizon of {problem.horizon}", tuple(states))
    for n, action in enumerate(actions, start=1):
        if problem_goal(problem, state):
            return Validation(False, f"goal already reached before step {n}", tuple(states))
        reason = disabled_reason(state, action, problem.rules)
        if reason is not None:
            return Validation(False, f"step {n}: {reason}", tuple(states))
        result = step(state, action, problem.rules)
        if isinstance(result, Collision):
            return Validation(False, f"step {n} ({action.value}): {result.describe()}", tuple(states))
        state = result
        states.append(state)
    if not problem_goal(problem, state):
        return Validation(False, f"goal not reached after {len(actions)} action(s)", tuple(states))
    return Validation(True, "plan reaches the goal", tuple(states))
