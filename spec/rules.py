"""The rules of the transition system, each written once: guards, the lane encoding, collisions, the goal.

The interpreter evaluates these functions on states; every other engine translates the same
declarations into its own form (offset sets and bitsets in ``oracle.abstraction``, Z3 terms in
``oracle.bmc``, Promela in ``promela.render``) and never restates a rule. Each span is a closed
interval of cells ``(lo, hi)``.
"""

from __future__ import annotations

import enum
from collections.abc import Sequence
from functools import cache

from spec.actions import ACTION_RULES, Action
from spec.grid import Grid
from spec.lanes import Lane
from spec.models import GoalRule, ModelRules
from spec.state import Collision, State

Span = tuple[int, int]


class Guard(enum.Enum):
    """The guards that can disable an action."""

    LANE = "lane"  # the action needs the AV in a given lane
    LANE_CHANGE_LIMIT = "lane-change limit"  # the model allows no more lane changes


def disabled_guard(state: State, action: Action, rules: ModelRules) -> Guard | None:
    """The guard that disables ``action`` in ``state``, or None when it is enabled."""
    rule = ACTION_RULES[action]
    if rule.from_lane is not None and state.lane is not rule.from_lane:
        return Guard.LANE
    if rule.changes_lane and state.lane_changes >= rules.max_lane_changes:
        return Guard.LANE_CHANGE_LIMIT
    return None


def disabled_reason(state: State, action: Action, rules: ModelRules) -> str | None:
    """Why ``action`` is not enabled in ``state`` (its lane guard, the lane-change limit), or None when it is."""
    guard, lane = disabled_guard(state, action, rules), ACTION_RULES[action].from_lane
    if guard is Guard.LANE and lane is not None:
        return f"{action.value} needs the AV in the {lane.value} lane"
    if guard is Guard.LANE_CHANGE_LIMIT:
        return f"{action.value}: the {rules.kind.value} model allows at most {rules.max_lane_changes} lane changes"
    return None


def lane_after(start: Lane, lane_changes: int) -> Lane:
    """The lane encoding: after ``lane_changes`` lane changes the AV is in its start lane iff the count is even."""
    return start if lane_changes % 2 == 0 else start.other


@cache
def collision_span(lane: Lane, rules: ModelRules, grid: Grid) -> Span:
    """The cells at which a vehicle in ``lane`` collides with the AV when the AV is in that lane.

    A left-lane vehicle collides in the AV's own cell; an oncoming one within the model's
    danger radius (a distance, in whole cells of the grid) of it.
    """
    radius = grid.cells(rules.danger_m, f"the {rules.kind.value} model's danger zone") if lane is Lane.RIGHT else 0
    return grid.av_cell - radius, grid.av_cell + radius


def left_path(shift: int) -> range:
    """The offsets at which a left-lane vehicle is checked for a collision during an action that shifts it by
    ``shift`` cells: every cell it moves through, one at a time, up to where it ends (``shift``), so no vehicle
    passes through the AV on a grid where an action moves the left lane by more than one cell; without a shift,
    where it stands (the AV may have changed lanes). Where it started was checked in the state before. On the
    paper's grid a shift is at most one cell, and this is the landing cell alone."""
    if shift == 0:
        return range(0, 1)
    step = -1 if shift < 0 else 1
    return range(step, shift + step, step)


def collision_in(state: State, rules: ModelRules, grid: Grid, tick: int) -> Collision | None:
    """The collision in ``state``, if any: a vehicle of the AV's lane inside that lane's collision span."""
    lo, hi = collision_span(state.lane, rules, grid)
    cells = state.left_lane if state.lane is Lane.LEFT else state.right_lane
    for i, cell in enumerate(cells):
        if lo <= cell <= hi:
            return Collision(state, state.lane, i, cell, tick)
    return None


def passed_line(grid: Grid) -> int:
    """"Oncoming passed": an oncoming vehicle has passed the AV when its cell is at most this one."""
    return grid.av_cell


def behind_line(grid: Grid) -> int:
    """"Target behind": a target is behind the AV when its cell is at most this one (below the AV's cell)."""
    return grid.av_cell - 1


@cache
def nearest_span(goal: GoalRule, grid: Grid) -> Span | None:
    """Where the nearest target must be for ``goal`` (ahead of the AV, within its distance), or None: anywhere."""
    if goal.nearest_target_m is None:
        return None
    return grid.av_cell + 1, grid.av_cell + grid.cells(goal.nearest_target_m, f"the {goal.kind.value} goal's gap")


def goal_holds(state: State, goal: GoalRule, targets: Sequence[int], grid: Grid) -> bool:
    """Whether ``state`` meets ``goal``, field by field; ``targets`` are indices into ``state.left_lane``."""
    if goal.av_lane is not None and state.lane is not goal.av_lane:
        return False
    if goal.targets_behind and any(state.left_lane[i] > behind_line(grid) for i in targets):
        return False
    span = nearest_span(goal, grid)
    if span is not None and not (targets and span[0] <= state.left_lane[targets[0]] <= span[1]):
        return False
    return not (goal.oncoming_passed and any(cell > passed_line(grid) for cell in state.right_lane))
