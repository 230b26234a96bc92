"""The sound model in the interpreter: its step, plan validation and its planners (sensible, shortest, optimal).

Pure functions over frozen values, like the paper's interpreter (``oracle.interpreter``): the rules
are ``spec.sound``'s, the search is ``oracle.search.depth_first`` (sensible), an ordered
breadth-first search (shortest) or a uniform-cost search with ``spec.cost`` (optimal) over
``SoundState``s. A plan reaches the goal with every step safe
at every instant and its last state safe for ever (the minimal-risk manoeuvre); the empty plan
is held to the same. The sound model cannot prove that no plan of any length exists (time grows
without bound): beyond the horizon it says so, never "no plan".
"""

from __future__ import annotations

import heapq
import time
from collections import deque
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from functools import lru_cache

from oracle.search import depth_first
from spec.actions import Action
from spec.answers import Limits, SearchResult, Status, Strategy
from spec.cost import COST_DOC, COST_TERMS, action_cost
from spec.rules import disabled_guard, disabled_reason
from spec.scenario import Problem
from spec.sound import SoundRules, SoundState, Violation
from spec.state import State


@lru_cache(maxsize=64)  # a few problems at a time (a pipeline's stages); a campaign must not keep every one
def rules_for(problem: Problem) -> SoundRules:
    """The sound model's rules on ``problem``'s scenario (its vehicles as intervals, its phantoms)."""
    sc = problem.scenario
    sound = sc.sound
    if sound is None:
        raise ValueError("the problem's scenario has no sound model")
    return SoundRules(sound, sc.lane, sc.left_lane, sc.right_lane, sc.grid, sc.target_indices)


def start(problem: Problem) -> SoundState:
    """The sound model's initial state."""
    return SoundState(problem.scenario.lane, 0, 0, 0, 0, None, None)


def step(problem: Problem, state: SoundState, action: Action) -> SoundState | Violation:
    """One decision step: the state after ``action``, or the violation that forbids it."""
    if disabled_guard(_paper(state), action, problem.rules) is not None:
        raise ValueError(disabled_reason(_paper(state), action, problem.rules))
    rules = rules_for(problem)
    found = rules.step_violation(state, action)
    return found if found is not None else rules.after(state, action)


def done(problem: Problem, state: SoundState) -> bool:
    """Whether a plan may end in ``state``: the goal holds for every position, and the state is safe for ever."""
    rules = rules_for(problem)
    return rules.goal_holds(state, problem.goal) and rules.continuation_violation(state) is None


def display(problem: Problem, state: SoundState) -> State:
    """The paper-style state shown for a sound state: every vehicle where the common speed puts its cell (the sound
    model's sets are wider; traces show the cells for reading, and ``oracle.reach`` checks the sets)."""
    sc, t, d = problem.scenario, state.t_units, state.d_cells
    return State(state.lane, tuple(c + t - d for c in sc.left_lane), tuple(c - t - d for c in sc.right_lane),
                 state.lane_changes, state.steps)


def _paper(state: SoundState) -> State:
    """A paper state with the lane and counts of ``state`` (the guards read nothing else)."""
    return State(state.lane, (), (), state.lane_changes, state.steps)


def _successors(problem: Problem, state: SoundState) -> Iterator[tuple[Action, SoundState]]:
    if state.steps >= problem.horizon:
        return
    rules = rules_for(problem)
    for action in Action:
        if disabled_guard(_paper(state), action, problem.rules) is None and rules.step_violation(state, action) is None:
            nxt = rules.after(state, action)
            if not rules.hopeless(nxt, problem.goal):
                yield action, nxt


def _trivial(problem: Problem) -> SearchResult | None:
    first = start(problem)
    hit = rules_for(problem).start_violation(first)
    if hit is not None:
        return SearchResult(Status.NO_PLAN, (), 1, f"initial state: {hit.describe()}")
    if done(problem, first):
        return SearchResult(Status.PLAN, (), 1, "goal holds in the initial state, safe for ever",
                            (display(problem, first),))
    return None


def beyond(problem: Problem) -> str:
    """What the sound model says when no plan is found within the horizon."""
    return f"no plan within {problem.horizon} actions (the sound model proves nothing beyond its horizon)"


def sensible(problem: Problem, limits: Limits | None = None) -> SearchResult:
    """Depth-first search in the action order (the paper's "sensible" plan), states with their step counts."""
    trivial = _trivial(problem)
    if trivial is not None:
        return trivial
    limits = limits or Limits()
    status, actions, states, explored, detail = depth_first(
        start(problem), lambda s: _successors(problem, s), lambda s: done(problem, s), limits.max_states,
        limits.timeout_s)
    if status is Status.NO_PLAN_WITHIN_HORIZON:
        detail = beyond(problem)
    return SearchResult(status, actions, explored, detail, tuple(display(problem, s) for s in states))


def shortest(problem: Problem, limits: Limits | None = None) -> SearchResult:
    """Breadth-first search with ordered expansion: the first shortest plan in the action order."""
    trivial = _trivial(problem)
    if trivial is not None:
        return trivial
    limits = limits or Limits()
    deadline = None if limits.timeout_s is None else time.monotonic() + limits.timeout_s
    first = start(problem)
    parent: dict[tuple[object, ...], tuple[SoundState, SoundState | None, Action | None]] = {
        first.key(): (first, None, None)}
    queue = deque([first])
    while queue:
        state = queue.popleft()
        for action, nxt in _successors(problem, state):
            if nxt.key() in parent:
                continue
            parent[nxt.key()] = (nxt, state, action)
            if done(problem, nxt):
                actions, states = _path(parent, nxt)
                return SearchResult(Status.PLAN, actions, len(parent), "",
                                    tuple(display(problem, s) for s in states))
            if len(parent) >= limits.max_states:
                return SearchResult(Status.INCOMPLETE, (), len(parent), f"state limit {limits.max_states} reached")
            if deadline is not None and len(parent) % 256 == 0 and time.monotonic() > deadline:
                return SearchResult(Status.INCOMPLETE, (), len(parent), f"time limit {limits.timeout_s} s reached")
            queue.append(nxt)
    return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), len(parent), beyond(problem))


def optimal(problem: Problem, limits: Limits | None = None) -> SearchResult:
    """The least-cost plan (``spec.cost``, lexicographic) of at most ``horizon`` actions: a uniform-cost search.

    Every cost term only grows along a plan, so the first goal state taken from the queue is least-cost (ties: the
    one pushed first). A state taken after one with the same key (``SoundState.key``: everything the future depends
    on but the steps) was taken with no more steps is dominated: it costs no less (the queue's order) and has no
    more of the horizon left. ``tests/oracle/test_sound.py`` checks it against every plan of a walk."""
    trivial = _trivial(problem)
    if trivial is not None:
        return trivial
    limits = limits or Limits()
    deadline = None if limits.timeout_s is None else time.monotonic() + limits.timeout_s
    first = start(problem)
    entries: list[tuple[SoundState, int, Action | None]] = [(first, -1, None)]  # state, the entry before, action
    queue: list[tuple[tuple[int, ...], int]] = [((0,) * len(COST_TERMS), 0)]  # cost, entry (ties: pushed first)
    fewest: dict[tuple[object, ...], int] = {}  # key -> the fewest steps it was taken with
    while queue:
        cost, entry = heapq.heappop(queue)
        state = entries[entry][0]
        if fewest.get(state.key(), state.steps + 1) <= state.steps:
            continue
        fewest[state.key()] = state.steps
        if done(problem, state):
            actions, states = _entries_path(entries, entry)
            return SearchResult(Status.PLAN, actions, len(entries), f"optimal under {COST_DOC}",
                                tuple(display(problem, s) for s in states),
                                {"cost": dict(zip(COST_TERMS, cost, strict=True)), "cost_order": list(COST_TERMS)})
        for action, nxt in _successors(problem, state):
            if fewest.get(nxt.key(), nxt.steps + 1) <= nxt.steps:
                continue
            entries.append((nxt, entry, action))
            added = action_cost(action, nxt.lane)
            heapq.heappush(queue, (tuple(a + b for a, b in zip(cost, added, strict=True)), len(entries) - 1))
        if len(entries) >= limits.max_states:
            return SearchResult(Status.INCOMPLETE, (), len(entries), f"state limit {limits.max_states} reached")
        if deadline is not None and time.monotonic() > deadline:
            return SearchResult(Status.INCOMPLETE, (), len(entries), f"time limit {limits.timeout_s} s reached")
    return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), len(entries), beyond(problem))


def _entries_path(entries: list[tuple[SoundState, int, Action | None]],
                  entry: int) -> tuple[tuple[Action, ...], tuple[SoundState, ...]]:
    actions, states = [], [entries[entry][0]]
    while entry > 0:
        _, entry, action = entries[entry]
        if action is not None:
            actions.append(action)
        states.append(entries[entry][0])
    return tuple(reversed(actions)), tuple(reversed(states))


def _path(parent: dict[tuple[object, ...], tuple[SoundState, SoundState | None, Action | None]],
          last: SoundState) -> tuple[tuple[Action, ...], tuple[SoundState, ...]]:
    actions, states = [], [last]
    _, before, action = parent[last.key()]
    while before is not None and action is not None:
        actions.append(action)
        states.append(before)
        _, before, action = parent[before.key()]
    return tuple(reversed(actions)), tuple(reversed(states))


def solve(problem: Problem, strategy: Strategy, limits: Limits) -> SearchResult:
    """The interpreter's answer for a problem of the sound model."""
    return {Strategy.SHORTEST: shortest, Strategy.OPTIMAL: optimal}.get(strategy, sensible)(problem, limits)


@dataclass(frozen=True, slots=True)
class SoundValidation:
    """The verdict on an action list under the sound model, with the violation that breaks it, if any."""

    valid: bool
    reason: str
    states: tuple[State, ...]  # display states: the initial one, then one per executed step
    violation: Violation | None = None


def validate(problem: Problem, actions: Sequence[Action]) -> SoundValidation:
    """Check that ``actions`` is a plan of the sound model: enabled, safe at every instant, within the horizon, the
    goal first at the end, and the end safe for ever."""
    rules, state = rules_for(problem), start(problem)
    shown = [display(problem, state)]
    hit = rules.start_violation(state)
    if hit is not None:
        return SoundValidation(False, f"initial state: {hit.describe()}", tuple(shown), hit)
    if len(actions) > problem.horizon:
        return SoundValidation(False, f"{len(actions)} actions exceed the horizon of {problem.horizon}", tuple(shown))
    for n, action in enumerate(actions, start=1):
        if done(problem, state):
            return SoundValidation(False, f"goal already reached before step {n}", tuple(shown))
        reason = disabled_reason(_paper(state), action, problem.rules)
        if reason is not None:
            return SoundValidation(False, f"step {n}: {reason}", tuple(shown))
        result = step(problem, state, action)
        if isinstance(result, Violation):
            return SoundValidation(False, f"step {n} ({action.value}): {result.describe()}", tuple(shown), result)
        state = result
        shown.append(display(problem, state))
    if not rules.goal_holds(state, problem.goal):
        return SoundValidation(False, f"goal not reached for every position after {len(actions)} action(s)",
                               tuple(shown))
    after = rules.continuation_violation(state)
    if after is not None:
        return SoundValidation(False, f"no safe continuation after the plan: {after.describe()}", tuple(shown), after)
    return SoundValidation(True, "plan reaches the goal, safe at every instant and for ever after", tuple(shown))
