"""Fast exact planning: breadth-first search over bitsets of relative offsets.

A state is ``(lane changes, l, o)`` (``oracle.abstraction``). One layer of the search (all
states after ``n`` actions) is one Python integer per lane-change count, bit
``row(l) * width + o``; an action moves a whole layer with one shift and one mask. ``o`` is
saturated at the first value past every oncoming vehicle's danger zone and goal line,
beyond which all values behave alike, so the grid is small.

The same shifts answer whether a plan of any length exists, on an over-approximation that
merges the ``l`` values beyond every vehicle into one row at each end (an action shifting
``l`` by ``k`` from an end row reaches every row up to ``k`` away): if it reaches no goal,
no plan exists at all; otherwise only "none within the horizon" is claimed.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from oracle.abstraction import Move, Offsets, offsets_of
from oracle.interpreter import replay
from oracle.search import trivial_answer
from spec.actions import Action
from spec.answers import SearchResult, Status
from spec.errors import EngineError
from spec.lanes import Lane
from spec.scenario import Problem


@dataclass(frozen=True, slots=True)
class _Flat:
    """One move as plain ints for the hot loop."""

    move: Move
    shift: int  # shift * width + ticks
    safe: int  # destination positions (before saturation) whose path was collision-free
    smear: tuple[int, ...]  # on the merged grid: extra shifts of the end row the move leaves


class BitSpace:
    """The grid of one problem over rows ``l_low .. l_high``; optionally merging ``pad`` rows at each end."""

    def __init__(self, problem: Problem, l_low: int, l_high: int, merged_ends: bool = False,
                 form: Offsets | None = None) -> None:
        form = self.form = form or offsets_of(problem)
        self.problem, self.l_low, self.merged = problem, l_low, merged_ends
        self.max_ticks = problem.grid.max_ticks
        self.pad = _pad(form)
        self.sat = form.o_saturation
        width = self.width = self.sat + self.max_ticks + 1
        rows = self.rows = l_high - l_low + 1
        self.row_bits = (1 << width) - 1
        self.rep = ((1 << (rows * width)) - 1) // self.row_bits  # bit 0 of every row
        self.lanes = form.lanes
        every = (1 << (rows * width)) - 1
        left_safe = {s: every & ~self._rows_at(form.left_bad_ends(s)) for s in form.shifts}
        right_safe = {t: self._right_safe(t) for t in form.tick_counts}
        self.moves: list[list[_Flat]] = []
        for moves in form.moves:
            flat = []
            for move in moves:
                safe = left_safe[move.shift] if form.lanes[move.lc_dst] is Lane.LEFT else right_safe[move.ticks]
                flat.append(_Flat(move, move.shift * width + move.ticks, safe, self._smear(move)))
            self.moves.append(flat)
        self.over = self._cols([o > self.sat for o in range(width)])
        self.col_sat = self._cols([o == self.sat for o in range(width)])
        self.goals = [self._goal_mask(lc) for lc in range(len(self.lanes))]

    # -- masks -------------------------------------------------------------------------
    def _rows(self, pred: Callable[[int], bool]) -> int:
        """All positions whose row's ``l`` satisfies ``pred``."""
        mask = 0
        for r in range(self.rows):
            if pred(self.l_low + r):
                mask |= self.row_bits << (r * self.width)
        return mask

    def _rows_at(self, offsets: frozenset[int]) -> int:
        """All positions whose row's ``l`` is one of ``offsets``."""
        mask = 0
        for off in offsets:
            r = off - self.l_low
            if 0 <= r < self.rows:
                mask |= self.row_bits << (r * self.width)
        return mask

    def _right_safe(self, ticks: int) -> int:
        """The destination columns a move of ``ticks`` ticks may reach without meeting a danger zone."""
        bad = self.form.right_bad_starts(ticks)
        return self._cols([o >= ticks and o - ticks not in bad for o in range(self.width)])

    def _cols(self, cols: list[bool]) -> int:
        """All positions whose column is marked in ``cols``."""
        bits = sum(1 << o for o, ok in enumerate(cols) if ok)
        return bits * self.rep

    def _goal_mask(self, lc: int) -> int:
        form = self.form
        if lc not in form.goal_lcs:
            return 0
        sat = self.sat
        mask = self._rows(lambda off: form.goal(lc, off, sat))
        if form.o_at_least is not None:
            mask &= self._cols([o >= form.o_at_least for o in range(self.width)])
        return mask & ~self.over

    def _smear(self, move: Move) -> tuple[int, ...]:
        """On the merged grid, the end row stands for every ``l`` beyond it: shifting it by ``k`` also
        reaches the rows 0 .. k - 1 away, as (row mask, bit shift) pairs flattened."""
        if not self.merged or not move.shift:
            return ()
        step = 1 if move.shift > 0 else -1
        end = self.pad if move.shift > 0 else self.rows - 1 - self.pad
        row = self.row_bits << (end * self.width)
        out: list[int] = []
        for k in range(0, move.shift, step):
            out += [row, k * self.width + move.ticks]
        return tuple(out)

    # -- moving sets ---------------------------------------------------------------------
    def start(self) -> int:
        """The initial position: l = 0, o = 0."""
        return 1 << ((0 - self.l_low) * self.width)

    def _saturate(self, y: int) -> int:
        over = y & self.over
        if not over:
            return y
        y ^= over
        for k in range(1, self.max_ticks + 1):
            y |= (over & (self.col_sat << k)) >> k
        return y

    def _merge_ends(self, y: int) -> int:
        """Fold the padding rows into the end rows, and clear them."""
        pad, width, top = self.pad, self.width, self.rows - 1 - self.pad
        for r in range(pad):
            y |= ((y >> (r * width)) & self.row_bits) << (pad * width)
            y |= ((y >> ((top + 1 + r) * width)) & self.row_bits) << (top * width)
        low = (1 << (pad * width)) - 1
        high = low << ((top + 1) * width)
        return y & ~low & ~high

    def _moved(self, flat: _Flat, x: int) -> int:
        y = (x << flat.shift if flat.shift >= 0 else x >> -flat.shift) & flat.safe
        for i in range(0, len(flat.smear), 2):
            row, shift = flat.smear[i], flat.smear[i + 1]
            part = x & row
            y |= (part << shift if shift >= 0 else part >> -shift) & flat.safe
        return y

    def image(self, flat: _Flat, x: int) -> int:
        """The positions ``flat`` reaches from the set ``x`` without a collision."""
        return self.finish(self._moved(flat, x))

    def preimage(self, flat: _Flat, y: int) -> int:
        """The positions from which ``flat`` lands in ``y`` (bounded grid only)."""
        return self.preimage_unsaturated(flat, self.unsaturated(y))

    def unsaturated(self, y: int) -> int:
        """``y`` with each saturated position also standing for the ones past it that saturate to it (what a move
        lands on before ``finish``)."""
        at_sat = y & self.col_sat
        for k in range(1, self.max_ticks + 1):
            y |= at_sat << k
        return y

    @staticmethod
    def preimage_unsaturated(flat: _Flat, y: int) -> int:
        """``preimage`` of a set already ``unsaturated``."""
        y &= flat.safe
        return y >> flat.shift if flat.shift >= 0 else y << -flat.shift

    def advance(self, layer: list[int]) -> list[int]:
        """The next layer: every move from every lane-change count."""
        out = [0] * len(layer)
        for lc, x in enumerate(layer):
            if x:
                for flat in self.moves[lc]:
                    out[flat.move.lc_dst] |= self._moved(flat, x)
        return [self.finish(y) for y in out]

    def finish(self, y: int) -> int:
        """Saturate ``o`` and, on the merged grid, fold the padding rows into the end rows."""
        y = self._saturate(y)
        return self._merge_ends(y) if self.merged else y

    def hits_goal(self, layer: list[int]) -> bool:
        """Whether any position of the layer meets the goal."""
        return any(x & g for x, g in zip(layer, self.goals))


def _l_range(form: Offsets, horizon: int) -> tuple[int, int]:
    """Every l reachable within ``horizon`` actions."""
    return min(0, min(form.shifts) * horizon), max(0, max(form.shifts) * horizon)


def _pad(form: Offsets) -> int:
    """Rows of padding at each end of a merged grid: the longest shift (at least one)."""
    return max(abs(s) for s in form.shifts) or 1


def shortest(problem: Problem) -> SearchResult:
    """The first shortest plan in the action order, or a proof that none exists."""
    trivial = trivial_answer(problem)
    if trivial is not None:
        return trivial
    form = offsets_of(problem)
    space = BitSpace(problem, *_l_range(form, problem.horizon), form=form)
    layers = [[space.start()] + [0] * (len(space.lanes) - 1)]
    explored = 1
    for _ in range(problem.horizon):
        layer = space.advance(layers[-1])
        layers.append(layer)
        explored += sum(x.bit_count() for x in layer)
        if space.hits_goal(layer):
            actions = _first_plan(space, layers)
            return SearchResult(Status.PLAN, actions, explored, states=replay(problem, actions, "bitplan"))
        if not any(layer):
            return SearchResult(Status.NO_PLAN, (), explored, "every path collides")
    return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), explored, f"no plan within {problem.horizon} actions")


def live_positions(problem: Problem) -> Callable[[int, int, int, int], bool]:
    """Which offsets ``(lane changes, l, o)`` after ``steps`` actions (at least one) still reach the goal within the
    horizon (the goal, or a step towards it), as a test ``live(lc, l, o, steps)``; every position at step 0. A
    search that skips every other successor finds the same first plan as one that explores them: they hold no goal,
    and none is on its way. Computed backwards from the goals over the whole grid: a position the search reaches
    has its successors among the positions the search reaches, so no forward pass is needed."""
    form = offsets_of(problem)
    space = BitSpace(problem, *_l_range(form, problem.horizon), form=form)
    width, nothing = space.width, [0] * len(space.lanes)
    real = ~space.over & ((1 << (space.rows * width)) - 1)  # saturated columns only: a shift back across a row's
    # edge lands past the saturation column, where no state is
    live = [list(nothing) for _ in range(problem.horizon + 1)]
    for k in range(problem.horizon, 0, -1):
        onward = list(nothing)
        if k < problem.horizon and any(live[k + 1]):
            landing = [space.unsaturated(x) for x in live[k + 1]]
            for lc, moves in enumerate(space.moves):
                for flat in moves:
                    if landing[flat.move.lc_dst]:
                        onward[lc] |= space.preimage_unsaturated(flat, landing[flat.move.lc_dst])
        live[k] = [(g | o) & real for g, o in zip(space.goals, onward, strict=True)]
        if k + 1 < problem.horizon and live[k] == live[k + 1]:  # a fixed point: one more step left changes nothing
            live[1:k] = [live[k]] * (k - 1)
            break
    if not form.track_left:  # the search keeps l at 0 where no left-lane vehicle is tracked: any row stands for it
        live = [[_columns(x, space) for x in layer] for layer in live]
    low = space.l_low

    def is_live(lc: int, l_off: int, o: int, steps: int) -> bool:
        return bool(live[steps][lc] >> ((l_off - low) * width + o) & 1) if 0 < steps < len(live) else steps == 0

    return is_live


def _columns(x: int, space: BitSpace) -> int:
    """Every row's columns folded onto the row of l = 0."""
    folded = 0
    while x:
        folded |= x & space.row_bits
        x >>= space.width
    return folded << ((0 - space.l_low) * space.width)


def beyond_horizon(problem: Problem, explored: int = 0) -> SearchResult:
    """After an exhaustive bounded search: is there no plan at all, or none within the horizon?"""
    form = offsets_of(problem)
    points = form.interesting_l()
    pad = _pad(form)
    space = BitSpace(problem, min(points) - 1 - pad, max(points) + 1 + pad, merged_ends=True, form=form)
    reach = [space.start()] + [0] * (len(space.lanes) - 1)
    frontier = reach
    while any(frontier):
        frontier = [new & ~old for new, old in zip(space.advance(frontier), reach)]
        reach = [a | b for a, b in zip(reach, frontier)]
        if space.hits_goal(frontier):
            detail = f"no plan within {problem.horizon} actions; a longer one may exist"
            return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), explored, detail)
    return SearchResult(Status.NO_PLAN, (), explored, "no plan of any length: the goal is unreachable")


def _first_plan(space: BitSpace, layers: list[list[int]]) -> tuple[Action, ...]:
    """Walk forward from the start, taking the first action (in order) that can still reach the goal in time."""
    depth = len(layers) - 1
    back = [[x & g for x, g in zip(layers[depth], space.goals)]]
    for k in range(depth - 1, 0, -1):
        can = [0] * len(space.lanes)
        for lc, moves in enumerate(space.moves):
            for flat in moves:
                can[lc] |= space.preimage(flat, back[-1][flat.move.lc_dst])
        back.append([c & x for c, x in zip(can, layers[k])])
    back.reverse()  # back[k - 1]: positions after k actions that reach the goal at ``depth``
    lc, here = 0, space.start()
    plan: list[Action] = []
    for k in range(depth):
        for flat in space.moves[lc]:
            there = space.image(flat, here)
            if there & back[k][flat.move.lc_dst]:
                break
        else:
            raise EngineError("bitplan: lost the plan while walking back (internal error)")
        plan.append(flat.move.action)
        lc, here = flat.move.lc_dst, there
    return tuple(plan)


