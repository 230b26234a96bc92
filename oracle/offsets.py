"""The sensible depth-first search over integer offsets: the same search as ``search.sensible``, faster.

A state ``(lane changes, l, o, steps)`` stands for the interpreter's ``State`` (see
``oracle.abstraction``; an empty lane's offset is not part of the state and stays 0), with
one merge: oncoming ticks are counted up to the form's saturation only. From there on every
oncoming vehicle is past every danger zone and the goal line, and ticks only grow, so the
states merged have the same moves and the same goal from then on. Pruning a state because an
equivalent one was visited at the same step count cuts no plan the search could still find
(when the first one's search ended, nothing reachable from it was a goal), so the action list
is the state search's own, with fewer states stored; tests check both on generated scenarios.
The merge is of search states only: a plan's states are the interpreter's replay, cells never
clipped (semantics.md). Collisions become set look-ups.
"""

from __future__ import annotations

import sys

from oracle.abstraction import offsets_of
from oracle.interpreter import replay
from oracle.search import depth_first, trivial_answer
from spec.actions import Action
from spec.answers import Limits, SearchResult, Status
from spec.lanes import Lane
from spec.scenario import Problem

Key = tuple[int, int, int, int]  # lane changes, left offset, oncoming ticks, steps


class OffsetSearch:
    """Successors and the goal of one problem's offset form, for ``depth_first`` (its hot loop: set look-ups)."""

    def __init__(self, problem: Problem, merge_saturated: bool = True) -> None:
        form = self.form = offsets_of(problem)
        self.horizon = problem.horizon
        self.track_left = form.track_left
        # 0 without oncoming vehicles: o stays 0, as an empty lane's offset. Unmerged, a state is one interpreter
        # State (the tests check that mapping by the states stored), o counted only while a lane holds a vehicle.
        self.o_sat = form.o_saturation if merge_saturated or not problem.scenario.right_lane else sys.maxsize
        self.moves = [[(m.action, m.lc_dst, form.lanes[m.lc_dst] is Lane.LEFT, m.shift, m.ticks) for m in moves]
                      for moves in form.moves]
        self.left_bad_end = {s: form.left_bad_ends(s) for s in form.shifts}
        self.right_bad = {t: form.right_bad_starts(t) for t in form.tick_counts}

    def goal(self, key: Key) -> bool:
        lc, l_off, o, _ = key
        return self.form.goal(lc, l_off, o)

    def successors(self, key: Key) -> list[tuple[Action, Key]]:
        lc, l_off, o, steps = key
        if steps >= self.horizon:
            return []
        return [(action, (*after, steps + 1)) for action, after in self.moves_from(lc, l_off, o)]

    def moves_from(self, lc: int, l_off: int, o: int) -> list[tuple[Action, tuple[int, int, int]]]:
        """The collision-free moves from ``(lc, l, o)`` in the action order, each with the offsets it ends at
        (ticks counted up to saturation)."""
        out = []
        for action, lc_dst, to_left, shift, ticks in self.moves[lc]:
            l2 = l_off + shift
            if (l2 in self.left_bad_end[shift]) if to_left else (o in self.right_bad[ticks]):
                continue
            out.append((action, (lc_dst, l2 if self.track_left else 0, min(o + ticks, self.o_sat))))
        return out


def sensible(problem: Problem, limits: Limits | None = None, merge_saturated: bool = True) -> SearchResult:
    """Depth-first search in the action order with visited-state pruning (Spin's default search). The same
    ``limits.max_states`` lets the merged search go further than a search over states (or Spin's): where that one
    runs out of states this one may still answer."""
    limits = limits or Limits()
    trivial = trivial_answer(problem)
    if trivial is not None:
        return trivial
    search = OffsetSearch(problem, merge_saturated)
    start: Key = (0, 0, 0, 0)
    status, actions, _, explored, detail = depth_first(start, search.successors, search.goal, limits.max_states,
                                                       limits.timeout_s)
    if status is Status.PLAN:
        return SearchResult(status, actions, explored, detail, replay(problem, actions, "offsets"))
    if status is Status.NO_PLAN_WITHIN_HORIZON:
        detail = f"no plan within {problem.horizon} actions"
    return SearchResult(status, actions, explored, detail)
