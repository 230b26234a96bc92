"""The least-cost plan found without Z3: the conformance check of the ``optimal`` strategy.

A uniform-cost search with the cost of ``spec.cost`` as a tuple compared lexicographically
(every term only grows along a plan, so the first goal state taken from the queue is
optimal), over the offset form of ``oracle.abstraction`` (a state is its lane changes and
the two lanes' offsets; the offsets engines use it, and it is checked against the
interpreter's states by the tests and by every campaign's trace-equality property). A state
taken from the queue after the same situation (lane changes and offsets) was taken with no
more steps is dominated and skipped: it costs no less (the queue's order), and the earlier
one has at least as much horizon left, while what can follow, and the goal, depend on the
situation alone. It shares nothing with the Z3 encoding but the spec (``oracle.bmc``
translates the rules on its own): an engine whose objective orders or counts the terms
differently returns a plan this search beats. ``tests/oracle/test_optimum.py`` checks it
against every plan walked through the interpreter.
"""

from __future__ import annotations

import functools
import heapq
from dataclasses import dataclass

from oracle.interpreter import problem_collision, problem_step
from oracle.offsets import OffsetSearch
from spec.actions import Action
from spec.cost import COST_TERMS, action_cost, total_cost
from spec.lanes import Lane
from spec.scenario import Problem
from spec.state import State

Cost = tuple[int, ...]
Situation = tuple[int, int, int]  # lane changes, left-lane offset, oncoming ticks


@dataclass(frozen=True, slots=True)
class Optimum:
    """The least cost of a plan within the horizon and one plan of that cost (None: no plan within the horizon)."""

    cost: Cost | None
    actions: tuple[Action, ...]
    explored: int = 0  # (situation, steps) pairs pushed


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
    """The least-cost plan of at most ``problem.horizon`` actions (a plan ends at its first goal state).

    A cost is packed into one integer, its terms the digits in base horizon + 1 (an action adds at most 1 to
    each term, so none exceeds the horizon): the lexicographic order of the terms is the order of the integers."""
    if problem_collision(problem, problem.scenario.initial_state()) is not None:
        return Optimum(None, ())
    base = problem.horizon + 1
    situations = _Situations(OffsetSearch(problem), base)
    first: Situation = (0, 0, 0)
    links: list[tuple[int, Action | None]] = [(-1, None)]  # per queue entry: the entry it came from, its action
    queue: list[tuple[int, int, Situation, int]] = [(0, 0, first, 0)]  # cost, entry (ties: pushed first), ...
    best: dict[tuple[Situation, int], int] = {(first, 0): 0}  # (situation, steps) -> the least cost pushed
    fewest_steps: dict[Situation, int] = {}  # situation -> the fewest steps it was taken with
    while queue:
        cost, entry, situation, steps = heapq.heappop(queue)
        if best[situation, steps] < cost or fewest_steps.get(situation, steps + 1) <= steps:
            continue
        fewest_steps[situation] = steps
        if situations.goal(situation):
            return Optimum(_unpacked(cost, base), _actions(links, entry), len(best))
        if steps >= problem.horizon:
            continue
        for action, after, added in situations.successors(situation):
            if fewest_steps.get(after, steps + 2) <= steps + 1:
                continue  # taken already with no more steps: it would be skipped when taken from the queue
            total = cost + added
            known = best.get((after, steps + 1))
            if known is None or total < known:
                best[after, steps + 1] = total
                if len(best) > max_states:
                    raise MemoryError(f"optimum: more than {max_states} states")
                links.append((entry, action))
                heapq.heappush(queue, (total, len(links) - 1, after, steps + 1))
    return Optimum(None, (), len(best))


def _actions(links: list[tuple[int, Action | None]], entry: int) -> tuple[Action, ...]:
    """The actions that led to a queue entry, first to last."""
    actions = []
    while entry > 0:
        entry, action = links[entry]
        assert action is not None  # only the first entry has none
        actions.append(action)
    return tuple(reversed(actions))


def _packed(cost: Cost, base: int) -> int:
    return functools.reduce(lambda packed, term: packed * base + term, cost, 0)


def _unpacked(packed: int, base: int) -> Cost:
    terms = []
    for _ in COST_TERMS:
        packed, term = divmod(packed, base)
        terms.append(term)
    return tuple(reversed(terms))


class _Situations:
    """The moves and the goal of each situation, worked out once: a search meets one at many step counts. (Oncoming
    ticks are counted up to saturation, ``oracle.offsets``: situations that differ only beyond it are one, and the
    dominance rule above applies to them.)"""

    def __init__(self, search: OffsetSearch, base: int) -> None:
        self.search = search
        self.added = {(action, lane): _packed(action_cost(action, lane), base) for action in Action for lane in Lane}
        self._successors: dict[Situation, list[tuple[Action, Situation, int]]] = {}

    def goal(self, situation: Situation) -> bool:
        return self.search.form.goal(*situation)

    def successors(self, situation: Situation) -> list[tuple[Action, Situation, int]]:
        """The collision-free successors in the action order, each with what it adds to the cost (packed)."""
        known = self._successors.get(situation)
        if known is None:
            lanes, added = self.search.form.lanes, self.added
            known = self._successors[situation] = [(action, after, added[action, lanes[after[0]]])
                                                   for action, after in self.search.moves_from(*situation)]
        return known
