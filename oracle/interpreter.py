"""The reference interpreter: the readable meaning of one decision step, plan validation and replay.

Pure functions over frozen values: ``step`` returns a new state (or the collision),
never mutating its input. The rules it applies (guards, collisions, the goal) are the
functions of ``spec.rules``; the effects come from the problem's grid.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from spec.actions import ACTION_RULES, Action
from spec.errors import EngineError
from spec.grid import Grid
from spec.models import ModelRules
from spec.rules import collision_in, disabled_guard, disabled_reason, goal_holds, left_path
from spec.scenario import Problem
from spec.state import Collision, State


def enabled_actions(state: State, rules: ModelRules) -> list[Action]:
    """The enabled actions, in the search order."""
    return [a for a in Action if disabled_guard(state, a, rules) is None]


def step(state: State, action: Action, rules: ModelRules, grid: Grid) -> State | Collision:
    """One decision step: the effect (the left lane moved one cell at a time, each followed by a collision check:
    ``spec.rules.left_path``), then the oncoming ticks, each followed by a check."""
    if disabled_guard(state, action, rules) is not None:
        raise ValueError(disabled_reason(state, action, rules))
    rule = ACTION_RULES[action]
    lane, lane_changes = rule.to_lane or state.lane, state.lane_changes + int(rule.changes_lane)
    steps, right = state.steps + 1, state.right_lane
    after = State(lane, state.left_lane, right, lane_changes, steps)
    for moved in left_path(grid.left_shift(action)):
        after = State(lane, tuple(cell + moved for cell in state.left_lane), right, lane_changes, steps)
        hit = collision_in(after, rules, grid, 0)
        if hit is not None:
            return hit
    for tick in range(1, grid.ticks(action) + 1):
        right = tuple(cell - 1 for cell in right)
        after = State(lane, after.left_lane, right, lane_changes, steps)
        hit = collision_in(after, rules, grid, tick)
        if hit is not None:
            return hit
    return after


def problem_step(problem: Problem, state: State, action: Action) -> State | Collision:
    """One decision step under ``problem``'s model and grid."""
    return step(state, action, problem.rules, problem.grid)


def problem_goal(problem: Problem, state: State) -> bool:
    """Whether ``state`` meets the goal of ``problem``."""
    return goal_holds(state, problem.goal, problem.scenario.target_indices, problem.grid)


def problem_collision(problem: Problem, state: State) -> Collision | None:
    """The collision in ``state`` (as after an effect) under ``problem``'s model and grid."""
    return collision_in(state, problem.rules, problem.grid, 0)


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
    start_hit = problem_collision(problem, state)
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
        result = problem_step(problem, state, action)
        if isinstance(result, Collision):
            return Validation(False, f"step {n} ({action.value}): {result.describe()}", tuple(states))
        state = result
        states.append(state)
    if not problem_goal(problem, state):
        return Validation(False, f"goal not reached after {len(actions)} action(s)", tuple(states))
    return Validation(True, "plan reaches the goal", tuple(states))


def replay(problem: Problem, actions: Sequence[Action], engine: str) -> tuple[State, ...]:
    """The interpreter's states along an engine's plan (initial included); a collision, a disabled action
    or a plan that misses the goal means the engine and the interpreter disagree: an engine error."""
    states = [problem.scenario.initial_state()]
    for n, action in enumerate(actions, start=1):
        reason = disabled_reason(states[-1], action, problem.rules)
        if reason is not None:
            raise EngineError(f"{engine}: the interpreter disagrees at step {n}: {reason}")
        nxt = problem_step(problem, states[-1], action)
        if isinstance(nxt, Collision):
            raise EngineError(f"{engine}: the interpreter disagrees at step {n}: {nxt.describe()}")
        states.append(nxt)
    if not problem_goal(problem, states[-1]):
        raise EngineError(f"{engine}: the interpreter disagrees: the plan does not reach the goal")
    return tuple(states)
