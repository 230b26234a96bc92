"""Fast exact planning: breadth-first search over bitsets of relative offsets.

Every left-lane vehicle moves together and so does every oncoming one, so a state is
``(lane changes, l, o)``: ``l`` the left-lane offset (cells added to every left-lane
vehicle) and ``o`` the oncoming ticks so far; the lane follows from the parity of the lane
changes. One layer of the search (all states after ``n`` actions) is one Python integer
per lane-change count, bit ``row(l) * width + o``; an action moves a whole layer with one
shift and one mask. ``o`` is saturated at the first value past every oncoming vehicle's
danger zone and goal threshold, beyond which all values behave alike, so the grid is small.

The same shifts answer whether a plan of any length exists, on an over-approximation that
merges the ``l`` values beyond every vehicle into one row at each end: if it reaches no
goal, no plan exists at all; otherwise only "none within the horizon" is claimed.
"""

from __future__ import annotations

from dataclasses import dataclass

from oracle.answer import SearchResult, Status
from oracle.interpreter import problem_goal, step
from oracle.search import trivial_answer
from spec.actions import ACTION_ORDER, ACTION_RULES, Action
from spec.constants import AV_CELL
from spec.errors import EngineError
from spec.lanes import Lane
from spec.scenario import Collision, Problem, State

_MAX_TICKS = max(rule.oncoming_ticks for rule in ACTION_RULES.values())


@dataclass(frozen=True, slots=True)
class _Move:
    """One action from one lane-change count: where it lands, how far it shifts, what is safe."""

    action: Action
    lc_src: int
    lc_dst: int
    drow: int
    ticks: int
    shift: int  # drow * width + ticks
    safe: int  # destination positions (before saturation) whose path was collision-free


class BitSpace:
    """The grid of one problem over rows ``l_low .. l_high``; optionally merging the end rows."""

    def __init__(self, problem: Problem, l_low: int, l_high: int, merged_ends: bool = False) -> None:
        scenario, rules = problem.scenario, problem.rules
        self.problem, self.l_low, self.merged = problem, l_low, merged_ends
        self.sat = saturation(problem)
        width = self.width = self.sat + _MAX_TICKS + 1
        rows = self.rows = l_high - l_low + 1
        self.row_bits = (1 << width) - 1
        self.rep = ((1 << (rows * width)) - 1) // self.row_bits  # bit 0 of every row
        self.lanes = [scenario.lane if lc % 2 == 0 else scenario.lane.other for lc in range(rules.max_lane_changes + 1)]
        left_free = self._rows(lambda off: all(c + off != AV_CELL for c in scenario.left_lane))
        col_safe = [all(abs(c - o - AV_CELL) > rules.danger_radius for c in scenario.right_lane) for o in range(width)]
        right_safe = {
            t: self._cols([o >= t and all(col_safe[o - k] for k in range(t + 1)) for o in range(width)])
            for t in {rule.oncoming_ticks for rule in ACTION_RULES.values()}
        }
        self.moves: list[list[_Move]] = [[] for _ in self.lanes]
        for lc, lane in enumerate(self.lanes):
            for action in ACTION_ORDER:
                rule = ACTION_RULES[action]
                if rule.from_lane not in (None, lane):
                    continue
                lc_dst = lc + int(rule.changes_lane)
                if lc_dst > rules.max_lane_changes:
                    continue
                t, drow = rule.oncoming_ticks, rule.left_shift_cells
                safe = left_free if self.lanes[lc_dst] is Lane.LEFT else right_safe[t]
                self.moves[lc].append(_Move(action, lc, lc_dst, drow, t, drow * width + t, safe))
        self.flat = [[self._flat_move(m) for m in moves] for moves in self.moves]
        self.over = self._cols([o > self.sat for o in range(width)])
        self.col_sat = self._cols([o == self.sat for o in range(width)])
        self.goals = [self._goal_mask(lane) for lane in self.lanes]

    # -- masks -------------------------------------------------------------------------
    def _rows(self, pred: object) -> int:
        """All positions whose row's ``l`` satisfies ``pred``."""
        mask = 0
        for r in range(self.rows):
            if pred(self.l_low + r):  # type: ignore[operator]
                mask |= self.row_bits << (r * self.width)
        return mask

    def _cols(self, cols: list[bool]) -> int:
        """All positions whose column is marked in ``cols``."""
        bits = sum(1 << o for o, ok in enumerate(cols) if ok)
        return bits * self.rep

    def _goal_mask(self, lane: Lane) -> int:
        goal, scenario = self.problem.goal, self.problem.scenario
        if goal.av_lane is not None and lane is not goal.av_lane:
            return 0
        targets = [scenario.left_lane[i] for i in scenario.target_indices]
        mask = (1 << (self.rows * self.width)) - 1
        if goal.targets_behind and targets:
            mask &= self._rows(lambda off: max(targets) + off < AV_CELL)
        if goal.nearest_target_offset is not None:
            offset = goal.nearest_target_offset
            mask &= self._rows(lambda off: bool(targets) and min(targets) + off == AV_CELL + offset)
        if goal.oncoming_passed and scenario.right_lane:
            threshold = max(scenario.right_lane) - AV_CELL
            mask &= self._cols([o >= threshold for o in range(self.width)])
        return mask & ~self.over

    # -- moving sets ---------------------------------------------------------------------
    def start(self) -> int:
        """The initial position: l = 0, o = 0."""
        return 1 << ((0 - self.l_low) * self.width)

    def _saturate(self, y: int) -> int:
        over = y & self.over
        if not over:
            return y
        y ^= over
        for k in range(1, _MAX_TICKS + 1):
            y |= (over & (self.col_sat << k)) >> k
        return y

    def _merge_ends(self, y: int) -> int:
        top = (self.rows - 1) * self.width
        y |= (y & self.row_bits) << self.width
        y |= (y >> top) << (top - self.width)
        return y & ~self.row_bits & ~(self.row_bits << top)

    def image(self, move: _Move, x: int) -> int:
        """The positions ``move`` reaches from the set ``x`` without a collision."""
        _, shift, safe, stay_row, ticks = self._flat_move(move)
        y = (x << shift if shift >= 0 else x >> -shift) & safe
        if stay_row:
            y |= ((x & stay_row) << ticks) & safe
        return self.finish(y)

    def _flat_move(self, move: _Move) -> tuple[int, int, int, int, int]:
        """A move as plain ints; on the merged grid, the end row a shift may also stay in."""
        stay_row = 0
        if self.merged and move.drow:
            end_row = 1 if move.drow > 0 else self.rows - 2
            stay_row = self.row_bits << (end_row * self.width)
        return move.lc_dst, move.shift, move.safe, stay_row, move.ticks

    def preimage(self, move: _Move, y: int) -> int:
        """The positions from which ``move`` lands in ``y`` (bounded grid only)."""
        at_sat = y & self.col_sat
        for k in range(1, _MAX_TICKS + 1):
            y |= at_sat << k
        y &= move.safe
        return y >> move.shift if move.shift >= 0 else y << -move.shift

    def advance(self, layer: list[int]) -> list[int]:
        """The next layer: every move from every lane-change count (the hot loop, kept flat)."""
        out = [0] * len(layer)
        for lc, x in enumerate(layer):
            if not x:
                continue
            for lc_dst, shift, safe, stay_row, ticks in self.flat[lc]:
                y = (x << shift if shift >= 0 else x >> -shift) & safe
                if stay_row:
                    y |= ((x & stay_row) << ticks) & safe
                out[lc_dst] |= y
        return [self.finish(y) for y in out]

    def finish(self, y: int) -> int:
        """Saturate ``o`` and, on the merged grid, fold the padding rows into the end rows."""
        y = self._saturate(y)
        return self._merge_ends(y) if self.merged else y

    def hits_goal(self, layer: list[int]) -> bool:
        """Whether any position of the layer meets the goal."""
        return any(x & g for x, g in zip(layer, self.goals))


def saturation(problem: Problem) -> int:
    """The oncoming tick count from which every oncoming vehicle is past danger and the goal line."""
    right = problem.scenario.right_lane
    if not right:
        return 0
    return max(0, max(right) - AV_CELL + problem.rules.danger_radius + 1)


def shortest(problem: Problem) -> SearchResult:
    """The first shortest plan in the action order, or a proof that none exists."""
    trivial = trivial_answer(problem)
    if trivial is not None:
        return trivial
    space = BitSpace(problem, -problem.horizon, problem.horizon)
    layers = [[space.start()] + [0] * (len(space.lanes) - 1)]
    explored = 1
    for _ in range(problem.horizon):
        layer = space.advance(layers[-1])
        layers.append(layer)
        explored += sum(x.bit_count() for x in layer)
        if space.hits_goal(layer):
            actions, states = _first_plan(space, layers)
            return SearchResult(Status.PLAN, actions, explored, states=states)
        if not any(layer):
            return SearchResult(Status.NO_PLAN, (), explored, "every path collides")
    return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), explored, f"no plan within {problem.horizon} actions")


def beyond_horizon(problem: Problem, explored: int = 0) -> SearchResult:
    """After an exhaustive bounded search: is there no plan at all, or none within the horizon?"""
    scenario, goal = problem.scenario, problem.goal
    points = [0] + [AV_CELL - c for c in scenario.left_lane]
    targets = [scenario.left_lane[i] for i in scenario.target_indices]
    if targets:
        points += [AV_CELL - max(targets) - 1, AV_CELL - max(targets)]
        if goal.nearest_target_offset is not None:
            points.append(AV_CELL + goal.nearest_target_offset - min(targets))
    space = BitSpace(problem, min(points) - 2, max(points) + 2, merged_ends=True)
    reach = [space.start()] + [0] * (len(space.lanes) - 1)
    frontier = reach
    while any(frontier):
        frontier = [new & ~old for new, old in zip(space.advance(frontier), reach)]
        reach = [a | b for a, b in zip(reach, frontier)]
        if space.hits_goal(frontier):
            detail = f"no plan within {problem.horizon} actions; a longer one may exist"
            return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), explored, detail)
    return SearchResult(Status.NO_PLAN, (), explored, "no plan of any length: the goal is unreachable")


def _first_plan(space: BitSpace, layers: list[list[int]]) -> tuple[tuple[Action, ...], tuple[State, ...]]:
    """Walk forward from the start, taking the first action (in order) that can still reach the goal in time."""
    depth = len(layers) - 1
    back = [[x & g for x, g in zip(layers[depth], space.goals)]]
    for k in range(depth - 1, 0, -1):
        can = [0] * len(space.lanes)
        for lc, moves in enumerate(space.moves):
            for move in moves:
                can[lc] |= space.preimage(move, back[-1][move.lc_dst])
        back.append([c & x for c, x in zip(can, layers[k])])
    back.reverse()  # back[k - 1]: positions after k actions that reach the goal at ``depth``
    problem, lc, here = space.problem, 0, space.start()
    state = problem.scenario.initial_state()
    plan: list[Action] = []
    states = [state]
    for k in range(depth):
        for move in space.moves[lc]:
            there = space.image(move, here)
            if there & back[k][move.lc_dst]:
                break
        else:
            raise EngineError("bitplan: lost the plan while walking back (internal error)")
        result = step(state, move.action, problem.rules)
        if isinstance(result, Collision):
            raise EngineError(f"bitplan: interpreter disagrees at step {k + 1}: {result.describe()}")
        plan.append(move.action)
        states.append(result)
        lc, here, state = move.lc_dst, there, result
    if not problem_goal(problem, state):
        raise EngineError("bitplan: interpreter disagrees: the plan does not reach the goal")
    return tuple(plan), tuple(states)
