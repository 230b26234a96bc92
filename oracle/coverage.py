"""Which rules of the spec a scenario exercises: guards, collision rules, goal fields, models of the pipeline.

A campaign reports, per rule, how many of its scenarios exercised it, so a campaign that never
meets a rule says so. The interpreter explores a scenario's states breadth first (at most
``MAX_STATES`` per model, within the horizon) under each model the pipeline would try and
notes every rule that decided something there:

- ``guard: lane`` / ``guard: lane-change limit``: an action disabled by that guard;
- ``collision: left lane`` / ``collision: oncoming, at the effect`` / ``collision: oncoming, on a tick``:
  a step that ended in that collision;
- ``goal: <field>``: a state where that field alone kept the goal from holding (it decided);
  ``goal: reached``: a state meeting the goal;
- ``model: <kind>``: a model the pipeline consults (the next model only after no plan in the first).
"""

from __future__ import annotations

from collections import deque
from dataclasses import replace
from typing import Any

from oracle.interpreter import problem_collision, problem_goal, problem_step
from spec.actions import Action
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
            elif after not in seen:
                seen.add(after)
                queue.append(after)


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


#: Every rule a campaign can exercise, in report order.
ALL_RULES = (
    *(f"guard: {guard.value}" for guard in Guard),
    "collision: left lane", "collision: oncoming, at the effect", "collision: oncoming, on a tick",
    *(f"goal: {name}" for name in GOAL_FIELDS), "goal: reached",
    *(f"model: {kind.value}" for kind in PIPELINE),
)
