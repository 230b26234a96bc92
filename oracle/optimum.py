"""The least-cost plan found by the interpreter alone: the conformance check of the ``optimal`` strategy.

A uniform-cost search over the interpreter's states, with the cost of ``spec.cost`` as a tuple
compared lexicographically (every term only grows along a plan, so the first goal state taken
from the queue is optimal). A state taken from the queue after the same situation (lanes,
cells, lane changes) was taken with no more steps is dominated and skipped: it costs no less
(the queue's order), and the earlier one has at least as much horizon left, while what can
follow, and the goal, depend on the situation alone; so each situation's successors (the
interpreter's steps) and goal are worked out once, however many step counts it is met at. It
shares nothing with the Z3 encoding but the spec: an engine whose objective orders or counts
the terms differently returns a plan this search beats.
"""

from __future__ import annotations

import heapq
import itertools
import operator
from dataclasses import dataclass

from oracle.interpreter import enabled_actions, problem_collision, problem_goal, problem_step
from spec.actions import Action
from spec.cost import COST_TERMS, step_cost, total_cost
from spec.lanes import Lane
from spec.scenario import Problem
from spec.state import State

Cost = tuple[int, ...]


@dataclass(frozen=True, slots=True)
class Optimum:
    """The least cost of a plan within the horizon and one plan of that cost (None: no plan within the horizon)."""

    cost: Cost | None
    actions: tuple[Action, ...]


def plan_cost(problem: Problem, actions: tuple[Action, ...]) -> Cost:
    """The cost of an action list, replayed by the interpreter (which must accept it: validate it first)."""
    state, ends = problem.scenario.initial_state(), []
    for action in actions:
        after = problem_step(problem, state, action)
        if not isinstance(after, State):
            raise ValueError(f"{action.value} collides: not a plan")
        ends.append(after)
        state = after
    return total_cost(zip(actions, ends))


def lexicographic_optimum(problem: Problem, max_states: int = 2_000_000) -> Optimum:
    """The least-cost plan of at most ``problem.horizon`` actions (a plan ends at its first goal state)."""
    start = problem.scenario.initial_state()
    if problem_collision(problem, start) is not None:
        return Optimum(None, ())
    situations = _Situations(problem)
    order = itertools.count()
    zero: Cost = (0,) * len(COST_TERMS)
    first = situations.of(start)
    queue: list[tuple[Cost, int, Situation, int, tuple[Action, ...]]] = [(zero, next(order), first, 0, ())]
    best: dict[tuple[Situation, int], Cost] = {(first, 0): zero}  # (situation, steps) -> the least cost pushed
    fewest_steps: dict[Situation, int] = {}  # situation -> the fewest steps it was taken with
    while queue:
        cost, _, situation, steps, actions = heapq.heappop(queue)
        if best[situation, steps] < cost or fewest_steps.get(situation, steps + 1) <= steps:
            continue
        fewest_steps[situation] = steps
        if situations.goal(situation):
            return Optimum(cost, actions)
        if steps >= problem.horizon:
            continue
        for action, after, added in situations.successors(situation):
            if fewest_steps.get(after, steps + 2) <= steps + 1:
                continue  # taken already with no more steps: it would be skipped when taken from the queue
            total = tuple(map(operator.add, cost, added))
            known = best.get((after, steps + 1))
            if known is None or total < known:
                best[after, steps + 1] = total
                if len(best) > max_states:
                    raise MemoryError(f"optimum: more than {max_states} states")
                heapq.heappush(queue, (total, next(order), after, steps + 1, (*actions, action)))
    return Optimum(None, ())


Situation = tuple[Lane, tuple[int, ...], tuple[int, ...], int]  # a state's lane, cells and lane changes


class _Situations:
    """The interpreter's steps and goal on situations (a state less its step count, which no rule reads), each
    worked out once: a search meets the same situation at many step counts."""

    def __init__(self, problem: Problem) -> None:
        self.problem = problem
        self._state: dict[Situation, State] = {}
        self._successors: dict[Situation, list[tuple[Action, Situation, Cost]]] = {}
        self._goal: dict[Situation, bool] = {}

    def of(self, state: State) -> Situation:
        """The situation of ``state`` (kept with a state of it, to step from)."""
        key = (state.lane, state.left_lane, state.right_lane, state.lane_changes)
        self._state.setdefault(key, state)
        return key

    def goal(self, situation: Situation) -> bool:
        known = self._goal.get(situation)
        if known is None:
            known = self._goal[situation] = problem_goal(self.problem, self._state[situation])
        return known

    def successors(self, situation: Situation) -> list[tuple[Action, Situation, Cost]]:
        """The collision-free successors in the action order, each with what it adds to the cost."""
        known = self._successors.get(situation)
        if known is None:
            state, known = self._state[situation], []
            for action in enabled_actions(state, self.problem.rules):
                after = problem_step(self.problem, state, action)
                if isinstance(after, State):
                    known.append((action, self.of(after), step_cost(action, after)))
            self._successors[situation] = known
        return known
