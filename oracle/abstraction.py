"""The offset abstraction that ``offsets``, ``bitplan`` and ``optimum`` share: one problem as integer offsets.

Every left-lane vehicle moves by the same shift and every oncoming vehicle by the same
ticks, so a state is ``(lc, l, o)``: lane changes, the left-lane offset (cells added to
every left-lane vehicle) and the oncoming ticks so far (cells taken off every oncoming
vehicle); the lane is ``spec.rules.lane_after(start, lc)``. This module translates each
rule of ``spec.rules`` into conditions on ``l`` and ``o`` once, for the problem's grid; the
engines built on it only search.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

from spec.actions import ACTION_ORDER, ACTION_RULES, Action
from spec.lanes import Lane
from spec.rules import behind_line, collision_span, lane_after, left_path, nearest_span, passed_line
from spec.scenario import Problem

Interval = tuple[int, int]


@dataclass(frozen=True, slots=True)
class Move:
    """One enabled action from one lane-change count: where it lands and how far it moves both lanes."""

    action: Action
    lc_src: int
    lc_dst: int
    shift: int  # added to l
    ticks: int  # added to o, one collision check after each


@dataclass(frozen=True, slots=True)
class Offsets:
    """A problem's guards, collisions and goal as conditions on ``(lc, l, o)``."""

    lanes: tuple[Lane, ...]  # the AV's lane after lc lane changes, lc = 0 .. max_lane_changes
    moves: tuple[tuple[Move, ...], ...]  # per lc, the enabled actions in the search order
    left_hits: frozenset[int]  # l at which a left-lane vehicle collides (AV in the left lane)
    right_hits: tuple[Interval, ...]  # merged intervals of o at which an oncoming vehicle collides (AV right)
    goal_lcs: frozenset[int]  # lane-change counts whose lane the goal accepts
    l_at_most: int | None  # goal: every target behind the AV iff l <= this
    l_within: Interval | None  # goal: the nearest target in its span iff l is in this (empty: no target)
    o_at_least: int | None  # goal: every oncoming vehicle passed iff o >= this
    track_left: bool  # an empty lane's offset is not part of the state: it stays 0 (o: see o_saturation)

    @property
    def shifts(self) -> frozenset[int]:
        """Every left-lane shift an enabled action makes."""
        return frozenset(m.shift for moves in self.moves for m in moves)

    @property
    def tick_counts(self) -> frozenset[int]:
        """Every number of oncoming ticks an enabled action makes."""
        return frozenset(m.ticks for moves in self.moves for m in moves)

    def left_bad_ends(self, shift: int) -> frozenset[int]:
        """The offsets a shift of ``shift`` may not end at: it would pass (or end at) a collision."""
        return frozenset(h - j + shift for h in self.left_hits for j in left_path(shift))

    def right_bad_starts(self, ticks: int) -> frozenset[int]:
        """The tick counts a move of ``ticks`` ticks may not start from: it would meet a danger zone."""
        return frozenset(o for lo, hi in self.right_hits for o in range(max(0, lo - ticks), hi + 1))

    def goal(self, lc: int, l_off: int, o: int) -> bool:
        """The goal, field by field, on offsets."""
        if lc not in self.goal_lcs:
            return False
        if self.l_at_most is not None and l_off > self.l_at_most:
            return False
        if self.l_within is not None and not self.l_within[0] <= l_off <= self.l_within[1]:
            return False
        return self.o_at_least is None or o >= self.o_at_least

    @property
    def o_saturation(self) -> int:
        """The tick count from which every oncoming vehicle is past every danger zone and the goal line."""
        points = [hi + 1 for _, hi in self.right_hits] + ([self.o_at_least] if self.o_at_least is not None else [])
        return max([0, *points])

    def interesting_l(self) -> list[int]:
        """Every l at which a left-lane condition can change (beyond them all, every l behaves alike)."""
        points = [0, *self.left_hits]
        if self.l_at_most is not None:
            points += [self.l_at_most, self.l_at_most + 1]
        if self.l_within is not None:
            points += list(self.l_within)
        return points


#: An interval no integer is in (the nearest-target goal without a target).
EMPTY: Interval = (1, 0)


@lru_cache(maxsize=64)  # a pipeline's stages ask for the same problem's form several times; a campaign must not keep
# every one
def offsets_of(problem: Problem) -> Offsets:
    """The offset form of ``problem``: each rule of ``spec.rules`` translated once."""
    scenario, rules, goal, grid = problem.scenario, problem.rules, problem.goal, problem.grid
    lanes = tuple(lane_after(scenario.lane, lc) for lc in range(rules.max_lane_changes + 1))
    moves = []
    for lc, lane in enumerate(lanes):
        row = []
        for action in ACTION_ORDER:
            rule = ACTION_RULES[action]
            lc_dst = lc + int(rule.changes_lane)
            if rule.from_lane in (None, lane) and lc_dst <= rules.max_lane_changes:
                row.append(Move(action, lc, lc_dst, grid.left_shift(action), grid.ticks(action)))
        moves.append(tuple(row))
    left_lo, left_hi = collision_span(Lane.LEFT, rules, grid)
    left_hits = frozenset(cell - c for c in scenario.left_lane for cell in range(left_lo, left_hi + 1))
    right_lo, right_hi = collision_span(Lane.RIGHT, rules, grid)
    right_hits = merged([(c - right_hi, c - right_lo) for c in scenario.right_lane])
    targets = [scenario.left_lane[i] for i in scenario.target_indices]
    l_at_most = behind_line(grid) - max(targets) if goal.targets_behind and targets else None
    span = nearest_span(goal, grid)
    l_within = None if span is None else (span[0] - targets[0], span[1] - targets[0]) if targets else EMPTY
    o_at_least = max(scenario.right_lane) - passed_line(grid) if goal.oncoming_passed and scenario.right_lane else None
    return Offsets(lanes, tuple(moves), left_hits, right_hits,
                   frozenset(lc for lc, lane in enumerate(lanes) if goal.av_lane in (None, lane)),
                   l_at_most, l_within, o_at_least, bool(scenario.left_lane))


def merged(spans: list[Interval]) -> tuple[Interval, ...]:
    """Overlapping or touching intervals joined; those wholly below o = 0 (never reached) dropped."""
    merged: list[Interval] = []
    for lo, hi in sorted(spans):
        if hi < 0:
            continue
        if merged and lo <= merged[-1][1] + 1:
            merged[-1] = (merged[-1][0], max(hi, merged[-1][1]))
        else:
            merged.append((lo, hi))
    return tuple(merged)
