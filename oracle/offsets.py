"""The sensible depth-first search over integer offsets: the same search as ``search.sensible``, faster.

A state ``(lane changes, l, o, steps)`` maps one-to-one to the interpreter's ``State``
(left cells = initial + l, oncoming cells = initial - o, lane from the parity of the lane
changes; an empty lane's offset is not part of the state and stays 0), so visited-state
pruning prunes exactly the same states and the action list is identical; tests check
that on generated scenarios. Collisions become set look-ups.
"""

from __future__ import annotations

from dataclasses import dataclass

from oracle.answer import SearchResult, Status
from oracle.interpreter import step
from oracle.search import DEFAULT_MAX_STATES, depth_first, trivial_answer
from spec.actions import ACTION_ORDER, ACTION_RULES, Action
from spec.constants import AV_CELL
from spec.errors import EngineError
from spec.lanes import Lane
from spec.scenario import Collision, Problem, State

Key = tuple[int, int, int, int]  # lane changes, left offset, oncoming ticks, steps


@dataclass(frozen=True, slots=True)
class _Move:
    action: Action
    lc_dst: int
    to_left: bool
    shift: int
    ticks: int


class OffsetModel:
    """Guards, collisions and the goal of one problem as integer arithmetic and set look-ups."""

    def __init__(self, problem: Problem) -> None:
        scenario, rules, goal = problem.scenario, problem.rules, problem.goal
        self.horizon = problem.horizon
        self.track_left, self.track_right = bool(scenario.left_lane), bool(scenario.right_lane)
        radius = rules.danger_radius
        self.left_hit = {AV_CELL - c for c in scenario.left_lane}
        self.right_hit = {c - AV_CELL + d for c in scenario.right_lane for d in range(-radius, radius + 1)}
        lanes = [scenario.lane if lc % 2 == 0 else scenario.lane.other for lc in range(rules.max_lane_changes + 1)]
        self.moves: list[list[_Move]] = []
        for lc, lane in enumerate(lanes):
            moves = []
            for action in ACTION_ORDER:
                rule = ACTION_RULES[action]
                lc_dst = lc + int(rule.changes_lane)
                if rule.from_lane in (None, lane) and lc_dst <= rules.max_lane_changes:
                    to_left = lanes[lc_dst] is Lane.LEFT
                    moves.append(_Move(action, lc_dst, to_left, rule.left_shift_cells, rule.oncoming_ticks))
            self.moves.append(moves)
        targets = [scenario.left_lane[i] for i in scenario.target_indices]
        self.goal_lanes = {lc for lc, lane in enumerate(lanes) if goal.av_lane in (None, lane)}
        self.behind_below = AV_CELL - max(targets) if goal.targets_behind and targets else None
        self.nearest_at = None
        if goal.nearest_target_offset is not None:
            self.nearest_at = AV_CELL + goal.nearest_target_offset - min(targets) if targets else False
        passed = goal.oncoming_passed and scenario.right_lane
        self.passed_from = max(scenario.right_lane) - AV_CELL if passed else None

    def goal(self, key: Key) -> bool:
        lc, l_off, o, _ = key
        if lc not in self.goal_lanes:
            return False
        if self.behind_below is not None and l_off >= self.behind_below:
            return False
        if self.nearest_at is not None and (self.nearest_at is False or l_off != self.nearest_at):
            return False
        return self.passed_from is None or o >= self.passed_from

    def successors(self, key: Key) -> list[tuple[Action, Key]]:
        lc, l_off, o, steps = key
        if steps >= self.horizon:
            return []
        out = []
        for move in self.moves[lc]:
            l2 = l_off + move.shift
            if move.to_left:
                if l2 in self.left_hit:
                    continue
            elif any(o + k in self.right_hit for k in range(move.ticks + 1)):
                continue
            key = (move.lc_dst, l2 if self.track_left else 0, o + move.ticks if self.track_right else 0, steps + 1)
            out.append((move.action, key))
        return out


def sensible(problem: Problem, max_states: int = DEFAULT_MAX_STATES, timeout_s: float | None = None) -> SearchResult:
    """Depth-first search in the action order with visited-state pruning (Spin's default search)."""
    trivial = trivial_answer(problem)
    if trivial is not None:
        return trivial
    model = OffsetModel(problem)
    start: Key = (0, 0, 0, 0)
    status, actions, _, explored, detail = depth_first(start, model.successors, model.goal, max_states, timeout_s)
    if status is Status.PLAN:
        return SearchResult(status, actions, explored, detail, _states(problem, actions))
    if status is Status.NO_PLAN_WITHIN_HORIZON:
        detail = f"no plan within {problem.horizon} actions"
    return SearchResult(status, actions, explored, detail)


def _states(problem: Problem, plan: tuple[Action, ...]) -> tuple[State, ...]:
    """The interpreter's states along the plan; a collision means the two representations disagree."""
    states = [problem.scenario.initial_state()]
    for n, action in enumerate(plan, start=1):
        nxt = step(states[-1], action, problem.rules)
        if isinstance(nxt, Collision):
            raise EngineError(f"offsets: interpreter disagrees at step {n}: {nxt.describe()}")
        states.append(nxt)
    return tuple(states)
