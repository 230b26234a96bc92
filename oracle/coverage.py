"""Which rules of the spec a scenario exercises: guards, collision rules, goal fields, models of the pipeline.

A campaign reports, per rule, how many of its scenarios exercised it, so a campaign that never
meets a rule says so. The interpreter explores a scenario's states breadth first (at most
``MAX_STATES`` per model, within the horizon) under each model the pipeline would try and
notes every rule that decided something there:

- ``guard: lane`` / ``guard: lane-change limit``: an action disabled by that guard;
- ``collision: left lane`` / ``collision: oncoming, at the effect`` / ``collision: oncoming, on a tick``:
  a step that ended in that collision; ``collision: left lane, in passing``: a left-lane vehicle
  hit in a cell the action moves it *through*, not where it ends (``spec.rules.left_path``). Only
  a grid whose actions move the left lane by more than one cell has it: there the left-lane rule
  decides differently from the paper's 21 m grid, where every left-lane collision is where the
  vehicle ends (``grid_rules``);
- ``goal: <field>``: a state where that field alone kept the goal from holding (it decided);
  ``goal: reached``: a state meeting the goal;
- ``model: <kind>``: a model the pipeline consults (the next model only after no plan in the first).
"""

from __future__ import annotations

import enum
from collections import deque
from dataclasses import replace
from typing import Any

from oracle.interpreter import problem_collision, problem_goal, problem_step
from spec.actions import Action
from spec.grid import Grid
from spec.lanes import Lane
from spec.models import PIPELINE, GoalRule, models_for
from spec.rules import Guard, disabled_guard, goal_holds
from spec.scenario import Problem, Scenario, problem_for
from spec.state import Collision, State

MAX_STATES = 80  # per model: enough to meet every rule near the start, cheap enough (~20 ms) for every scenario
GOAL_FIELDS = ("av_lane", "targets_behind", "nearest_target_m", "oncoming_passed")
_EMPTY: dict[str, Any] = {"av_lane": None, "targets_behind": False, "nearest_target_m": None, "oncoming_passed": False}


def rules_exercised(scenario: Scenario, first_model_has_plan: bool | None = None) -> set[str]:
    """The rules ``scenario`` exercises (see the module's docstring). ``first_model_has_plan``: whether the
    pipeline's first model found a plan (then the next is not consulted); None: consult every model."""
    found: set[str] = set()
    for n, kind in enumerate(models_for(scenario.model)):
        if n > 0 and first_model_has_plan:
            break
        found.add(f"model: {kind.value}")
        _explore(problem_for(scenario, kind), found)
    return found


def _explore(problem: Problem, found: set[str]) -> None:
    start = problem.scenario.initial_state()
    if problem_collision(problem, start) is not None:
        return
    seen = {start}
    queue = deque([start])
    while queue and len(seen) <= MAX_STATES:
        state = queue.popleft()
        _goal_fields(problem, state, found)
        if problem_goal(problem, state) or state.steps >= problem.horizon:
            continue
        for action in Action:
            guard = disabled_guard(state, action, problem.rules)
            if guard is not None:
                found.add(f"guard: {guard.value}")
                continue
            after = problem_step(problem, state, action)
            if isinstance(after, Collision):
                found.add(_collision_rule(after))
                if _in_passing(after, state, problem, problem.grid.left_shift(action)):
                    found.add(IN_PASSING)
            elif after not in seen:
                seen.add(after)
                queue.append(after)


def _in_passing(hit: Collision, before: State, problem: Problem, shift: int) -> bool:
    """Whether the left-lane rule decided the step in passing: a vehicle hit before the action's shift had moved it
    to where it ends, where a rule that checked only where vehicles end would have let the step through."""
    if hit.lane is not Lane.LEFT or hit.tick != 0 or hit.cell == before.left_lane[hit.vehicle] + shift:
        return False
    landed = replace(hit.state, left_lane=tuple(cell + shift for cell in before.left_lane))
    return problem_collision(problem, landed) is None


def _collision_rule(hit: Collision) -> str:
    if hit.lane is Lane.LEFT:
        return "collision: left lane"
    return "collision: oncoming, at the effect" if hit.tick == 0 else "collision: oncoming, on a tick"


def _goal_fields(problem: Problem, state: State, found: set[str]) -> None:
    targets = problem.scenario.target_indices
    if goal_holds(state, problem.goal, targets, problem.grid):
        found.add("goal: reached")
        return
    for name in GOAL_FIELDS:
        if getattr(problem.goal, name) == _EMPTY[name]:
            continue  # this goal does not have the field
        without: GoalRule = replace(problem.goal, **{name: _EMPTY[name]})
        if goal_holds(state, without, targets, problem.grid):
            found.add(f"goal: {name}")


IN_PASSING = "collision: left lane, in passing"

#: Every rule a campaign can exercise, in report order.
ALL_RULES = (
    *(f"guard: {guard.value}" for guard in Guard),
    "collision: left lane", IN_PASSING, "collision: oncoming, at the effect", "collision: oncoming, on a tick",
    *(f"goal: {name}" for name in GOAL_FIELDS), "goal: reached",
    *(f"model: {kind.value}" for kind in PIPELINE),
)


def grid_rules(grid: Grid) -> tuple[str, ...]:
    """The rules that decide on ``grid`` where the paper's grid has no such decision: a left-lane vehicle passed
    through, where some action moves the left lane by more than one cell."""
    return (IN_PASSING,) if max(abs(grid.left_shift(a)) for a in Action) > 1 else ()


def rules_on(grid: Grid) -> tuple[str, ...]:
    """The rules a campaign on ``grid`` can exercise, in report order."""
    return tuple(rule for rule in ALL_RULES if rule != IN_PASSING or IN_PASSING in grid_rules(grid))


class CoverageTarget(enum.Enum):
    """Which rules a campaign must exercise at least once, or fail (``overtake crossval --coverage-target``)."""

    NONE = "none"
    GRID = "grid"  # every rule that decides differently on the campaign's grid than on the paper's (``grid_rules``)
    ALL = "all"  # every rule that can occur on the campaign's grid (``rules_on``)

    def rules(self, grid: Grid) -> tuple[str, ...]:
        return {CoverageTarget.NONE: (), CoverageTarget.GRID: grid_rules(grid),
                CoverageTarget.ALL: rules_on(grid)}[self]
