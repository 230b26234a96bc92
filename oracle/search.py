"""Explicit-state planners over interpreter states: depth-first ``sensible`` and a reference BFS.

States include the step count, so pruning a visited state never cuts a path that a
shorter prefix could still complete within the horizon: both searches are exhaustive.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable, Hashable, Iterable, Iterator
from typing import TypeVar

from oracle.interpreter import enabled_actions, problem_collision, problem_goal, problem_step
from spec.actions import Action
from spec.answers import Limits, SearchResult, Status
from spec.scenario import Problem
from spec.state import Collision, State

K = TypeVar("K", bound=Hashable)

#: Default bound on stored states before a search reports ``incomplete``.
DEFAULT_MAX_STATES = Limits().max_states


def _successors(problem: Problem, state: State) -> Iterator[tuple[Action, State]]:
    """Collision-free successors in the action order; none at the horizon or in a goal state."""
    if state.steps >= problem.horizon:
        return
    for action in enabled_actions(state, problem.rules):
        nxt = problem_step(problem, state, action)
        if not isinstance(nxt, Collision):
            yield action, nxt


def trivial_answer(problem: Problem) -> SearchResult | None:
    """The answer when the initial state already decides: a collision or the goal."""
    start = problem.scenario.initial_state()
    hit = problem_collision(problem, start)
    if hit is not None:
        return SearchResult(Status.NO_PLAN, (), 1, f"initial state: {hit.describe()}")
    if problem_goal(problem, start):
        return SearchResult(Status.PLAN, (), 1, "goal holds in the initial state", (start,))
    return None


def depth_first(
    start: K,
    successors: Callable[[K], Iterable[tuple[Action, K]]],
    is_goal: Callable[[K], bool],
    max_states: int = DEFAULT_MAX_STATES,
    timeout_s: float | None = None,
    key: Callable[[K], Hashable] | None = None,
) -> tuple[Status, tuple[Action, ...], tuple[K, ...], int, str]:
    """Depth-first search in successor order with visited-state pruning, stopping at the first goal.

    Generic over the state representation, so that the readable search over interpreter
    states and the fast one over integer offsets are the same algorithm. ``key``: what a
    state is visited as (default: itself). Returns (status, actions, states along the plan,
    states stored, detail).
    """
    deadline = None if timeout_s is None else time.monotonic() + timeout_s
    seen: Callable[[K], Hashable] = key or (lambda k: k)
    visited = {seen(start)}
    plan: list[Action] = []
    path = [start]
    stack = [iter(successors(start))]
    while stack:
        for action, nxt in stack[-1]:
            mark = seen(nxt)
            if mark in visited:
                continue
            visited.add(mark)
            plan.append(action)
            path.append(nxt)
            if is_goal(nxt):
                return Status.PLAN, tuple(plan), tuple(path), len(visited), ""
            if len(visited) >= max_states:
                return Status.INCOMPLETE, (), (), len(visited), f"state limit {max_states} reached"
            if deadline is not None and len(visited) % 1024 == 0 and time.monotonic() > deadline:
                return Status.INCOMPLETE, (), (), len(visited), f"time limit {timeout_s} s reached"
            stack.append(iter(successors(nxt)))
            break
        else:
            stack.pop()
            path.pop()
            if plan:
                plan.pop()
    return Status.NO_PLAN_WITHIN_HORIZON, (), (), len(visited), ""


def sensible(problem: Problem, max_states: int = DEFAULT_MAX_STATES) -> SearchResult:
    """Depth-first search in the action order with visited-state pruning (Spin's default search).

    The readable reference; ``oracle.offsets.sensible`` is the same search on integers.
    """
    trivial = trivial_answer(problem)
    if trivial is not None:
        return trivial
    status, actions, states, explored, detail = depth_first(
        problem.scenario.initial_state(), lambda s: _successors(problem, s), lambda s: problem_goal(problem, s),
        max_states)
    if status is Status.NO_PLAN_WITHIN_HORIZON:
        detail = f"no plan within {problem.horizon} actions"
    return SearchResult(status, actions, explored, detail, states)


def shortest_reference(problem: Problem, max_states: int = DEFAULT_MAX_STATES) -> SearchResult:
    """Breadth-first search with ordered expansion: the first shortest plan in the action order.

    Slow but plain; the fast planner in ``oracle.bitplan`` is checked against it.
    """
    trivial = trivial_answer(problem)
    if trivial is not None:
        return trivial
    start = problem.scenario.initial_state()
    parent: dict[State, tuple[State, Action] | None] = {start: None}
    queue = deque([start])
    while queue:
        state = queue.popleft()
        for action, nxt in _successors(problem, state):
            if nxt in parent:
                continue
            parent[nxt] = (state, action)
            if problem_goal(problem, nxt):
                actions, states = _path(parent, nxt)
                return SearchResult(Status.PLAN, actions, len(parent), states=states)
            if len(parent) >= max_states:
                return SearchResult(Status.INCOMPLETE, (), len(parent), f"state limit {max_states} reached")
            queue.append(nxt)
    return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), len(parent), f"no plan within {problem.horizon} actions")


def _path(
    parent: dict[State, tuple[State, Action] | None], last: State
) -> tuple[tuple[Action, ...], tuple[State, ...]]:
    actions: list[Action] = []
    states = [last]
    link = parent[last]
    while link is not None:
        state, action = link
        actions.append(action)
        states.append(state)
        link = parent[state]
    return tuple(reversed(actions)), tuple(reversed(states))
