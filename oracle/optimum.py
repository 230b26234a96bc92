"""The least-cost plan found by the interpreter alone: the conformance check of the ``optimal`` strategy.

A uniform-cost search over the interpreter's states, with the cost of ``spec.cost`` as a tuple
compared lexicographically (every term only grows along a plan, so the first goal state taken
from the queue is optimal). A state taken from the queue after the same situation (lanes,
cells, lane changes) was taken with no more steps is dominated and skipped: it costs no less
(the queue's order), and the earlier one has at least as much horizon left, while what can
follow, and the goal, depend on the situation alone. It shares nothing with the Z3 encoding but the spec: an engine
whose objective orders or counts the terms differently returns a plan this search beats.
"""

from __future__ import annotations

import heapq
import itertools
from dataclasses import dataclass

from oracle.interpreter import enabled_actions, problem_collision, problem_goal, problem_step
from spec.actions import Action
from spec.cost import COST_TERMS, step_cost, total_cost
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
    order = itertools.count()
    queue: list[tuple[Cost, int, State, tuple[Action, ...]]] = [((0,) * len(COST_TERMS), next(order), start, ())]
    best: dict[State, Cost] = {start: queue[0][0]}
    fewest_steps: dict[tuple[object, ...], int] = {}  # situation -> the fewest steps it was taken with
    while queue:
        cost, _, state, actions = heapq.heappop(queue)
        situation = (state.lane, state.left_lane, state.right_lane, state.lane_changes)
        if best.get(state, cost) < cost or fewest_steps.get(situation, len(actions) + 1) <= len(actions):
            continue
        fewest_steps[situation] = len(actions)
        if problem_goal(problem, state):
            return Optimum(cost, actions)
        if len(actions) >= problem.horizon:
            continue
        for action in enabled_actions(state, problem.rules):
            after = problem_step(problem, state, action)
            if not isinstance(after, State):
                continue
            total = _add(cost, step_cost(action, after))
            if total < best.get(after, (*total[:-1], total[-1] + 1)):
                best[after] = total
                if len(best) > max_states:
                    raise MemoryError(f"optimum: more than {max_states} states")
                heapq.heappush(queue, (total, next(order), after, (*actions, action)))
    return Optimum(None, ())


def _add(a: Cost, b: Cost) -> Cost:
    return tuple(x + y for x, y in zip(a, b, strict=True))
