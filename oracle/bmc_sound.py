"""The Z3 bounded encoding of the sound model: ``spec.windows``'s table and everything it leaves out, as Z3 terms.

A step of the sound model (``spec.sound``, ``oracle.sound``) is safe when every vehicle keeps its
gap over the step's window. The windows come from ``spec.windows.sound_table`` and its lookup
rule (``SoundTable.window``), translated here: a window while the first ramp runs is a
disjunction over its whole keys (its instants absolute); any other is its relative shape,
selected by the speed before the boundary, the action, the lane and the lane moved into, and
moved by ``t * unit_s`` seconds and ``d * cell_m + gain_m[first]`` metres (symbolic in the
step's state). What the table leaves out is computed here, from ``spec``: the vehicles as
intervals (their cells' extents widened by the sensing error, then the phantoms), their growth
with their lane's speed bounds, the AV's envelope, the required gap (a constant once the
instant is known: every closing speed is), and the conditions of ``spec/windows.py``'s
docstring (AHEAD, ONCOMING, entering, followers, the continuation's end, the goal at its
boundary). Each condition is linear in ``t``, ``d`` and one end of a vehicle's interval.

State per step: ``right`` (the AV's lane), ``lc`` (lane changes), ``t`` (time units), ``d``
(cells of nominal advance), ``first`` and ``last`` (speed indices into the table's
``speeds_mps``, ``NO_SPEED`` = -1 before the first action), ``moved`` (the lane the last action
moved into: 0 none, 1 left, 2 right) and one Bool per same-direction vehicle, ``follows``: it
follows the AV in the left lane (``SoundState.followers``: classified at the start, and again at
the boundary of every move into the left lane). The numbers are Z3 Reals: each is a sum of whole
constants (or one of a few), so always whole, and the solver stays in linear real arithmetic
(``t`` and ``d`` as Ints beside the Real interval ends took 1.6x as long on a scenario measured).

Dead states are pruned as the interpreter prunes them (``SoundRules.hopeless``, translated in
``SoundEncoding._hopeless``; ``PRUNE``): a state from which the goal can never hold is no state
of a plan. It changes no answer (the interpreter's own test holds it to that, and
``tests/oracle/test_bmc_sound.py`` runs this encoding without it), but without it a proof of
"no plan within the horizon" meets every path that drives on for ever behind its target, and
bounded model checking takes them one by one: tens of seconds per such scenario of the seeded
sample at horizon 30 (a third of it has no plan), where the prune makes it a fraction of one.

The sensed vehicles' interval ends are Real parameters, fixed per problem by assumption literals
(as ``oracle.bmc`` fixes its cells): one encoding serves every problem of a shape (the AV's
lane, how many vehicles each lane holds, the targets, the model, the goal, the horizon, the grid,
the sound model's assumptions), on a solver kept per shape. A phantom's ends are constants of
the shape; a condition on an infinite end is folded to true or false here, never given to Z3.

A plan ends where ``done`` holds (the goal at the continuation window's boundary, and the
continuation safe: its window, then its end) and nowhere before. ``shortest`` adds one step at a
time and asks whether ``done`` holds at step k and at no earlier step (each step's transition
under a literal assumed for the bound asked, so a plan is never asked to go on past its end); it
proves "no plan of any length" as the interpreter does, when no path of m actions avoids the goal
(``_shortest``). ``optimal`` takes whether a plan exists, and its fewest actions, from
``shortest``, then unrolls to the horizon with a symbolic length and minimises ``spec.cost`` term
by term (``oracle.bmc``'s procedures, on this encoding). Two rewritings keep the solver's work
small and change no condition: the pieces of a stretch refuse intervals of one term per vehicle,
merged before they reach Z3 (``_union``, ``_strongest``), and every unrolled state states its lane
from the parity of its lane changes (``Unrolling.lanes``). The identity check's scenarios
(``Checks.PAPER_CELLS``) are the interpreter's alone: refused here with an ``EngineError``.
"""

from __future__ import annotations

import math
import time
from collections import OrderedDict
from collections.abc import Callable, Hashable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, replace
from typing import NamedTuple, TypeAlias, TypeVar

import z3

from oracle import bmc
from oracle.bmc_own import Own, unbroken
from spec.actions import ACTION_ORDER, ACTION_RULES, Action
from spec.answers import Limits, SearchResult, Status, Strategy
from spec.cost import COST_DOC, COST_TERMS, total_cost
from spec.errors import EngineError
from spec.lanes import Lane
from spec.motion import ramp_s
from spec.scenario import Problem, Scenario
from spec.sound import (
    EPS_M,
    Checks,
    SoundState,
    advance,
    follower_limit_m,
    hold_floor_mps,
    rear_binds,
    sensed_extents,
)
from spec.state import State
from spec.windows import NO_SPEED, Instant, Stretch, Window, sound_table

#: ``moved`` as an integer: the lane the last action moved into.
MOVED: dict[Lane | None, int] = {None: 0, Lane.LEFT: 1, Lane.RIGHT: 2}

Cond: TypeAlias = z3.BoolRef | bool  # a condition: a Z3 term, or one folded to a constant here
End: TypeAlias = z3.ArithRef | float  # a vehicle's interval end: a parameter, or a phantom's constant (maybe infinite)


def _and(*parts: Cond) -> Cond:
    if any(p is False for p in parts):
        return False
    terms = [p for p in parts if p is not True]
    return True if not terms else terms[0] if len(terms) == 1 else _all(terms)


def _or(*parts: Cond) -> Cond:
    if any(p is True for p in parts):
        return True
    terms = [p for p in parts if p is not False]
    return False if not terms else terms[0] if len(terms) == 1 else _any(terms)


def _all(terms: Sequence[z3.BoolRef]) -> z3.BoolRef:
    """``z3.And`` of Z3 terms without the wrapper's coercions (a fifth of the time an encoding takes to build)."""
    return _connective(z3.Z3_mk_and, terms)


def _any(terms: Sequence[z3.BoolRef]) -> z3.BoolRef:
    """``z3.Or``, as ``_all``."""
    return _connective(z3.Z3_mk_or, terms)


def _connective(make: Callable[..., z3.Ast], terms: Sequence[z3.BoolRef]) -> z3.BoolRef:
    ctx = terms[0].ctx
    array = (z3.Ast * len(terms))()
    for i, term in enumerate(terms):
        array[i] = term.as_ast()
    return z3.BoolRef(make(ctx.ref(), len(terms), array), ctx)


def _not(part: Cond) -> Cond:
    return (not part) if isinstance(part, bool) else z3.Not(part)


def _term(part: Cond) -> z3.BoolRef:
    return z3.BoolVal(part) if isinstance(part, bool) else part


def _union(spans: Sequence[tuple[float, float]]) -> list[tuple[float, float]]:
    """The union of half-open intervals ``[lo, hi)`` (empty ones left out), as disjoint ones in order."""
    out: list[tuple[float, float]] = []
    for lo, hi in sorted(s for s in spans if s[0] < s[1]):
        if out and lo <= out[-1][1]:
            out[-1] = (out[-1][0], max(out[-1][1], hi))
        else:
            out.append((lo, hi))
    return out


def _strongest(pieces: Sequence[tuple[float, float]]) -> list[tuple[float, float]]:
    """The (need, line) pairs no other pair implies: a condition ``x >= need or y <= line`` follows from one with a
    need at least as large and a line at least as low."""
    return [p for i, p in enumerate(pieces)
            if not any(q[0] >= p[0] and q[1] <= p[1] and (q != p or j < i) for j, q in enumerate(pieces) if j != i)]


@dataclass(frozen=True, slots=True)
class SoundStep:
    """The Z3 variables of one state."""

    right: z3.BoolRef
    lc: z3.ArithRef
    t: z3.ArithRef
    d: z3.ArithRef
    first: z3.ArithRef
    last: z3.ArithRef
    moved: z3.ArithRef
    follows: tuple[z3.BoolRef, ...]  # per same-direction vehicle (sensed, then phantoms)

    def fields(self) -> tuple[z3.ExprRef, ...]:
        return (self.right, self.lc, self.t, self.d, self.first, self.last, self.moved, *self.follows)


NUMBER = z3.Real


def _variables(name: str, same: int) -> SoundStep:
    return SoundStep(z3.Bool(f"right{name}"), NUMBER(f"lc{name}"), NUMBER(f"t{name}"), NUMBER(f"d{name}"),
                     NUMBER(f"first{name}"), NUMBER(f"last{name}"), NUMBER(f"moved{name}"),
                     tuple(z3.Bool(f"follows{name}_{j}") for j in range(same)))


def _pairs(template: SoundStep, step: SoundStep) -> list[tuple[z3.ExprRef, z3.ExprRef]]:
    return list(zip(template.fields(), step.fields(), strict=True))


class Substitution:
    """``z3.substitute`` with its pairs taken in once, unchecked (the wrapper checks every pair's sorts on every call:
    most of the time an unrolling takes). Every pair here is a template's variable and a step's of the same field."""

    def __init__(self, pairs: Sequence[tuple[z3.ExprRef, z3.ExprRef]]) -> None:
        self.count = len(pairs)
        self.old, self.new = (z3.Ast * self.count)(), (z3.Ast * self.count)()
        for i, (old, new) in enumerate(pairs):
            self.old[i], self.new[i] = old.as_ast(), new.as_ast()
        self.keep = pairs  # the arrays hold the terms' pointers: their Python references stay alive with them

    def __call__(self, term: z3.BoolRef) -> z3.BoolRef:
        ctx = term.ctx
        found = z3.Z3_substitute(ctx.ref(), term.as_ast(), self.count, self.old, self.new)
        return z3.BoolRef(found, ctx)


class Skip(NamedTuple):
    """Vehicles (by index in their lane) the lane's speeds do not move: their conditions are ``oracle.bmc_own``'s."""

    same: frozenset[int]
    oncoming: frozenset[int]


NO_SKIP = Skip(frozenset(), frozenset())


@dataclass(frozen=True, slots=True)
class Interval:
    """A vehicle's positions at the plan's start, metres ahead of the AV: parameters, or a phantom's constants."""

    lo: End
    hi: End


@dataclass(frozen=True, slots=True)
class Frame:
    """Where a window's instants are: absolute (``dt``, ``dx`` None), or moved by ``dt`` seconds and ``dx`` metres."""

    dt: z3.ArithRef | None = None
    dx: z3.ArithRef | None = None


ABSOLUTE = Frame()


def extents(scenario: Scenario) -> tuple[list[tuple[float, float]], list[tuple[float, float]]]:
    """The sensed vehicles' intervals (same-direction, oncoming): each cell's extent, or what the snapshot measured
    (``spec.sound.sensed_extents``), widened by the sensing error (none for sets that hold it) and the snapshot's
    age in their lane (``Sound.start_error_m``)."""
    sound, grid = scenario.sound, scenario.grid
    assert sound is not None
    e, f = sound.start_error_m(Lane.LEFT), sound.start_error_m(Lane.RIGHT)
    same, oncoming = sensed_extents(scenario.lane, scenario.left_lane, scenario.right_lane, grid, scenario.left_m,
                                    scenario.right_m)
    return [(lo - e, hi + e) for lo, hi in same], [(lo - f, hi + f) for lo, hi in oncoming]


class SoundEncoding:
    """The sound model's transition system for one problem shape, over its sensed vehicles' interval ends."""

    def __init__(self, problem: Problem, prune: bool = True) -> None:
        scenario = problem.scenario
        sound = scenario.sound
        if sound is None:
            raise ValueError("the problem's scenario has no sound model")
        if sound.checks is not Checks.PHYSICAL:
            raise EngineError("z3: the identity check (the paper's cell rules on the sound model's code path) is "
                              "answered by the interpreter only")
        self.problem, self.sound, self.grid = problem, sound, problem.grid
        self.table = table = sound_table(sound, problem.grid, hold_floor_mps(scenario), scenario.lane)
        b = sound.bounds
        self.low, self.high = b.same_mps.low_mps, b.same_mps.high_mps
        self.low_o, self.high_o = b.oncoming_mps.low_mps, b.oncoming_mps.high_mps
        self.ex, self.ev = sound.tracking.position_m, sound.tracking.speed_mps
        self.length_m = sound.safety.vehicle_length_m
        self.gap = sound.safety.required_gap_m
        self.params: list[z3.ArithRef] = []
        self.same = [Interval(self._param(f"same_lo_{i}"), self._param(f"same_hi_{i}"))
                     for i in range(len(scenario.left_lane))]
        self.oncoming = [Interval(self._param(f"oncoming_lo_{i}"), self._param(f"oncoming_hi_{i}"))
                         for i in range(len(scenario.right_lane))]
        self.sensed_oncoming = len(self.oncoming)
        for p in sound.phantoms():
            (self.same if p.lane is Lane.LEFT else self.oncoming).append(Interval(*p.stretch_m))
        self.targets = scenario.target_indices
        self.prune = prune
        speeds = [table.speeds_mps[i] for i in table.action_speed.values()]
        #: ``SoundRules.dip_m``: the most a ramp centred on a boundary puts the AV behind its nominal position there.
        self.dip_m = max((v1 - v2) * ramp_s(v1, v2) / 8 for v1 in speeds for v2 in speeds if v1 > v2)
        self._check_start_gain()
        self._forms: dict[tuple[int | None, float, int], z3.ArithRef | None] = {}
        self._frames: dict[int, Frame] = {}
        self._candidates: dict[tuple[int, Action | None], list[tuple[z3.BoolRef, Window, Frame, Lane]]] = {}
        self.start = start = _variables("_0", len(self.same))  # an unrolling's step 0
        window = table.start[scenario.lane]
        if (window.boundary.t_s, window.boundary.x_m) != (0.0, 0.0):
            raise EngineError("z3: the start window's boundary is not the plan's start")
        start_follows = [_not(self._held(v, window.boundary, ABSOLUTE)) for v in self.same]
        self.start_safe = _term(_and(*self._safe(window, ABSOLUTE, [False] * len(self.same)),
                                     *self._start_in_lane(window, start_follows)))
        self.initial = z3.And(start.right == (scenario.lane is Lane.RIGHT), start.lc == 0, start.t == 0,
                              start.d == 0, start.first == NO_SPEED, start.last == NO_SPEED, start.moved == 0,
                              *[f == _term(v) for f, v in zip(start.follows, start_follows, strict=True)],
                              self.start_safe)
        here, after, action = _variables("_a", len(self.same)), _variables("_b", len(self.same)), z3.Int("action")
        self.step_template = (here, action, after, self.transition(here, action, after))
        self.done_template = (here, self.done(here))

    def _param(self, name: str) -> z3.ArithRef:
        self.params.append(z3.Real(name))
        return self.params[-1]

    def values(self, scenario: Scenario) -> list[tuple[z3.ArithRef, float]]:
        """Each interval-end parameter with its value in ``scenario`` (a scenario of this encoding's shape)."""
        same, oncoming = extents(scenario)
        return list(zip(self.params, [end for pair in (*same, *oncoming) for end in pair], strict=True))

    def _check_start_gain(self) -> None:
        """The encoding moves a window by the gain of the state's first speed, 0 before the first action; the lookup
        takes the action's speed (or the start's) there. Those gains are 0 wherever the window is not early (no
        first ramp: the speeds are equal), which this checks."""
        table = self.table
        for lane in table.starts:
            for action in (*Action, None):
                if action is not None and ACTION_RULES[action].from_lane not in (None, lane):
                    continue
                first = table.start_speed if action is None else table.action_speed[action]
                if (lane, 0, 0, NO_SPEED, NO_SPEED, None, action) not in table.early and table.gain_m[first] != 0:
                    raise EngineError(f"z3: a window from the start ({action}) is not early but moves by a gain")

    # -- conditions: ``end + speed * dt - dx  op  const`` ------------------------------------------------------
    def _atom(self, end: End, speed: float, frame: Frame, op: str, const: float) -> Cond:
        if isinstance(end, float) and math.isinf(end):
            return end > 0 if op == ">=" else end < 0  # every comparison of an infinite end with a finite value
        offset = end if isinstance(end, float) else 0.0
        lhs = self._linear(None if isinstance(end, float) else end, speed, frame)
        if lhs is None:
            return {"<": offset < const, "<=": offset <= const, ">=": offset >= const}[op]
        rhs = z3.RealVal(const - offset)
        return {"<": lhs < rhs, "<=": lhs <= rhs, ">=": lhs >= rhs}[op]

    def _linear(self, end: z3.ArithRef | None, speed: float, frame: Frame) -> z3.ArithRef | None:
        """``end + speed * dt - dx`` (None: a constant), built once."""
        key = (None if end is None else end.get_id(), speed, id(frame))
        if key not in self._forms:
            terms: list[z3.ArithRef] = [] if end is None else [end]
            if frame.dt is not None and frame.dx is not None:
                if speed:
                    terms.append(z3.RealVal(speed) * frame.dt)
                terms.append(-frame.dx)
            self._forms[key] = None if not terms else terms[0] if len(terms) == 1 else z3.Sum(*terms)
        return self._forms[key]

    def _held(self, v: Interval, at: Instant, frame: Frame) -> Cond:
        """Held to AHEAD at ``at``: every position clear ahead, ``lo + low t - L >= x + e_x``."""
        return self._atom(v.lo, self.low, frame, ">=", self._held_from(at))

    def _held_from(self, at: Instant) -> float:
        """The least ``lo`` (moved to the window's place) of a vehicle held to AHEAD at ``at``."""
        return at.x_m + self.ex + self.length_m - self.low * at.t_s

    def _passed(self, v: Interval, at: Instant, frame: Frame) -> Cond:
        """An oncoming vehicle certainly past the AV at ``at``: ``hi - low_o t + L <= x - e_x - EPS_M``."""
        return self._atom(v.hi, -self.low_o, frame, "<=", self._passed_from(at))

    def _passed_from(self, at: Instant) -> float:
        """The most ``hi`` (moved to the window's place) of an oncoming vehicle certainly past the AV at ``at``."""
        return at.x_m - self.ex - EPS_M - self.length_m + self.low_o * at.t_s

    def _ahead_need(self, at: Instant) -> float:
        """The least ``lo`` (moved to the window's place) a vehicle held to AHEAD needs at ``at``."""
        return at.x_m + self.ex + self.length_m + self.gap(at.v_mps + self.ev - self.low) - self.low * at.t_s

    def _behind_allow(self, at: Instant) -> float:
        """The most ``hi`` a vehicle the AV cuts in ahead of may have at ``at``."""
        return at.x_m - self.ex - self.length_m - self.gap(self.high - at.v_mps + self.ev) - self.high * at.t_s

    def _safe(self, window: Window, frame: Frame, follows: Sequence[Cond], skip: Skip = NO_SKIP) -> list[Cond]:
        """Every stretch of ``window`` keeps its conditions (``SoundRules.check_segment``); ``skip``: the vehicles
        that move by their own dynamics (``oracle.bmc_own``), not held to their lane's speeds here."""
        out: list[Cond] = []
        for s in window.stretches:
            if s.left:
                out += self._entering(s, frame, skip) if s.entering else self._ahead(s, frame, follows, skip)
            if s.right:
                out += self._oncoming(s, frame, skip)
        return out

    def _start_in_lane(self, window: Window, follows: Sequence[Cond], skip: Skip = NO_SKIP) -> list[Cond]:
        """At the start in the left lane, then as in it (``SoundRules.start_violation``): the start stretch's
        ``_ahead`` conditions, its followers those not held ahead there (``follows``)."""
        return [c for s in window.stretches if s.left and s.at_start for c in self._ahead(s, ABSOLUTE, follows, skip)]

    def _lane_same(self, follows: Sequence[Cond], skip: Skip) -> list[tuple[Interval, Cond]]:
        """The same-direction vehicles held to their lane's speeds, each with whether it follows the AV."""
        return [(v, f) for i, (v, f) in enumerate(zip(self.same, follows, strict=True)) if i not in skip.same]

    def _lane_oncoming(self, skip: Skip) -> list[Interval]:
        return [v for j, v in enumerate(self.oncoming) if j not in skip.oncoming]

    def _ahead(self, s: Stretch, frame: Frame, follows: Sequence[Cond], skip: Skip = NO_SKIP) -> list[Cond]:
        """AHEAD: a vehicle not a follower, held ahead at a piece's start and short of the gap at its worst instant;
        BEHIND: a follower over the pieces where followers bind (``spec.sound.rear_binds``), nearer than a cut-in's.
        Both are bounds on the same term (``lo + low dt - dx``), so each piece refuses an interval of it; their
        union, merged, is what the stretch refuses (fewer atoms, the same condition)."""
        refused = []
        for b in s.pieces:
            need = self._ahead_need(b.ahead) + EPS_M
            refused.append((self._held_from(b.start), need))
        out = [_or(follower, self._atom(v.lo, self.low, frame, "<", lo), self._atom(v.lo, self.low, frame, ">=", hi))
               for lo, hi in _union(refused) for v, follower in self._lane_same(follows, skip)]
        rear = [self._behind_allow(b.behind) for b in s.pieces if b.rear]
        if rear:  # BEHIND: each follower behind as a cut-in must be, at the strictest of those pieces
            allow = min(rear)
            out += [_or(_not(follower), self._atom(v.hi, self.high, frame, "<=", allow - EPS_M))
                    for v, follower in self._lane_same(follows, skip)]
        return out

    def _oncoming(self, s: Stretch, frame: Frame, skip: Skip = NO_SKIP) -> list[Cond]:
        """ONCOMING: a vehicle not passed at a piece's start and short of the gap at its worst instant. A piece whose
        need is no larger and whose passing line no lower than another's asks nothing more: left out."""
        pieces = []
        for b in s.pieces:
            at = b.oncoming
            need = at.x_m + self.ex + self.length_m + self.gap(at.v_mps + self.ev + self.high_o) + EPS_M \
                + self.high_o * at.t_s
            pieces.append((need, self._passed_from(b.start)))
        return [_or(self._atom(v.lo, -self.high_o, frame, ">=", need), self._atom(v.hi, -self.low_o, frame, "<=", line))
                for need, line in _strongest(pieces) for v in self._lane_oncoming(skip)]

    def _entering(self, s: Stretch, frame: Frame, skip: Skip = NO_SKIP) -> list[Cond]:
        """Each same-direction vehicle certainly ahead at every piece, or certainly behind at every piece (at the
        plan's start: one that cannot be clear ahead, ``spec.sound.follower_limit_m``)."""
        ahead = max(self._ahead_need(b.ahead) for b in s.pieces)
        if s.at_start:
            if frame is not ABSOLUTE:
                raise EngineError("z3: a start stretch in a moved window")
            first = s.pieces[0].start
            behind = follower_limit_m(first.x_m, self.sound)
        else:
            behind = min(self._behind_allow(b.behind) for b in s.pieces)
        return [_or(self._atom(v.lo, self.low, frame, ">=", ahead + EPS_M),
                    self._atom(v.hi, 0.0 if s.at_start else self.high, frame, "<=", behind - EPS_M))
                for v, _ in self._lane_same([False] * len(self.same), skip)]

    def _end(self, window: Window, frame: Frame, lane: Lane, follows: Sequence[Cond], skip: Skip = NO_SKIP) \
            -> list[Cond]:
        """After the continuation: in the right lane every oncoming vehicle passed; in the left lane, unless the AV
        is slow enough never to close in, no vehicle but a follower held ahead, and no follower at all where one
        would close in on the AV (``spec.sound.rear_binds`` at the end speed)."""
        end = window.end
        if lane is Lane.RIGHT:
            return [self._passed(v, end, frame) for v in self._lane_oncoming(skip)]
        out = []
        if self.sound.minimal_risk.closes_in(end.v_mps, self.low):
            out += [_not(_and(_not(f), self._held(v, end, frame))) for v, f in self._lane_same(follows, skip)]
        if rear_binds(self.sound.bounds, end.v_mps):  # a follower that keeps its speed closes in for ever
            out += [_not(f) for _, f in self._lane_same(follows, skip)]
        return out

    def _goal(self, window: Window, frame: Frame, lane: Lane, skip: Skip = NO_SKIP) -> list[Cond]:
        """The goal at the continuation window's boundary (``SoundRules.goal_holds``)."""
        goal, at, out = self.problem.goal, window.boundary, list[Cond]()
        if goal.av_lane is not None:
            out.append(lane is goal.av_lane)
        ex, length = self.ex, self.length_m
        if goal.targets_behind:
            out += [self._atom(self.same[i].hi, self.high, frame, "<=", at.x_m - ex - length - self.high * at.t_s)
                    for i in self.targets if i not in skip.same]
        if goal.nearest_target_m is not None:
            if not self.targets:
                out.append(False)
            elif self.targets[0] not in skip.same:
                v, most = self.same[self.targets[0]], float(goal.nearest_target_m)
                out.append(self._atom(v.lo, self.low, frame, ">=", at.x_m + ex + length - self.low * at.t_s))
                out.append(self._atom(v.hi, self.high, frame, "<=", at.x_m - ex + length + most - self.high * at.t_s))
        if goal.oncoming_passed:
            out += [self._passed(v, at, frame) for j, v in enumerate(self.oncoming[:self.sensed_oncoming])
                    if j not in skip.oncoming]
        return out

    # -- the interpreter's prune, translated (``SoundRules.hopeless``) -------------------------------------------
    def _hopeless(self, window: Window, frame: Frame, lane: Lane, follows: Sequence[Cond]) -> Cond:
        """Whether the goal can hold neither in a state nor after it (``SoundRules.hopeless``, on the state's
        continuation window's boundary, its time and reference position): a sound prune of dead states."""
        goal, at, out = self.problem.goal, window.boundary, list[Cond]()
        t = z3.RealVal(at.t_s) + frame.dt if frame.dt is not None else z3.RealVal(at.t_s)
        x = z3.RealVal(at.x_m) + frame.dx if frame.dx is not None else z3.RealVal(at.x_m)
        ex, length, g_min = self.ex, self.length_m, self.sound.safety.min_gap_m
        if goal.nearest_target_m is not None and self.targets:
            v, most = self.same[self.targets[0]], float(goal.nearest_target_m)
            out.append(v.hi + self.high * t - (v.lo + self.low * t) + 2 * ex > most + EPS_M)
            room = most - g_min - 2 * ex
            out += [v.hi + self.high * t - (p.lo + self.low * t) > room + EPS_M for p in self.same
                    if isinstance(p.hi, float) and math.isinf(p.hi)]
        phantoms = [v.lo for v in self.oncoming if isinstance(v.hi, float) and math.isinf(v.hi)]
        if not (goal.targets_behind and self.targets and phantoms):
            return _or(*out)
        least = self.gap(self.ev + self.high_o)
        nearest = max(float(lo) for lo in phantoms)
        speed_gain = max(self.table.speeds_mps) - self.high
        for i in self.targets:
            v = self.same[i]
            if lane is Lane.LEFT:
                held = v.lo + self.low * t - length >= x + self.dip_m + ex
                skip = _or(follows[i], _not(held))
            else:
                skip = False
            passed = v.hi + self.high * t + length + g_min + ex <= x - self.dip_m - ex
            hit: Cond = True
            if speed_gain > 0:  # passed no sooner than ``passed_at``: the right lane closed by then
                def closed(passed_at: z3.ArithRef, v: Interval = v) -> z3.BoolRef:
                    av_at = v.hi + self.high * passed_at + length + g_min + ex
                    return nearest - self.high_o * passed_at - (av_at + ex) - length < least - EPS_M
                wait = (v.hi + self.high * t + length + g_min + 2 * ex - x - self.dip_m) / speed_gain
                hit = z3.Or(closed(t), closed(t + wait))  # passed_at = t + max(0, wait); ``closed`` only grows
            out.append(_and(_not(skip), z3.Not(passed), hit))
        return _or(*out)

    def hopeless(self, s: SoundStep) -> Cond:
        """``_hopeless`` on the state ``s`` (through its continuation window's lookup)."""
        return _or(*[_and(selected, self._hopeless(window, frame, lane, s.follows))
                     for selected, window, frame, lane in self.candidates(s, None)])

    # -- the lookup: which window a state and an action have ------------------------------------------------
    def _gain(self, first: z3.ArithRef) -> z3.ArithRef:
        """The first ramp's gain of the state's first speed (0 before the first action, ``_check_start_gain``)."""
        gain: z3.ArithRef = z3.RealVal(0)
        for index, value in enumerate(self.table.gain_m):
            if value != 0:
                gain = z3.If(first == index, z3.RealVal(value), gain)
        return gain

    def _frame(self, s: SoundStep) -> Frame:
        key = s.t.get_id()
        if key not in self._frames:
            self._frames[key] = Frame(z3.RealVal(self.table.unit_s) * s.t,
                                      z3.RealVal(self.table.cell_m) * s.d + self._gain(s.first))
        return self._frames[key]

    def candidates(self, s: SoundStep, action: Action | None) -> list[tuple[z3.BoolRef, Window, Frame, Lane]]:
        """Every window ``action`` (None: the continuation) may have from ``s``, with the condition that selects it
        (``SoundTable.window``; the conditions exclude each other)."""
        key = (s.t.get_id(), action)
        if key not in self._candidates:
            self._candidates[key] = self._lookup(s, action)
        return self._candidates[key]

    def _lookup(self, s: SoundStep, action: Action | None) -> list[tuple[z3.BoolRef, Window, Frame, Lane]]:
        table, out = self.table, []
        early = []
        for (lane, t, d, first, last, moved, act), window in table.early.items():
            if act is action:
                guard = _all([s.right == (lane is Lane.RIGHT), s.t == t, s.d == d, s.first == first, s.last == last,
                              s.moved == MOVED[moved]])
                early.append(guard)
                out.append((guard, window, ABSOLUTE, lane))
        later = z3.Not(_any(early)) if early else z3.BoolVal(True)
        default = table.start_speed if action is None else table.action_speed[action]
        before = z3.If(s.last != NO_SPEED, s.last, z3.If(s.first != NO_SPEED, s.first, default))
        frame = self._frame(s)
        shapes: dict[tuple[int, Lane], dict[Lane | None, Window]] = {}
        for (speed, act, lane, moved), window in table.relative.items():
            if act is action:
                shapes.setdefault((speed, lane), {})[moved] = window
        for (speed, lane), by_move in shapes.items():
            common = [later, before == speed, s.right == (lane is Lane.RIGHT)]
            if len(set(by_move.values())) == 1:  # the move before does not change this shape: one candidate
                out.append((_all(common), next(iter(by_move.values())), frame, lane))
                continue
            for moved, window in by_move.items():
                out.append((_all([*common, s.moved == MOVED[moved]]), window, frame, lane))
        return out

    # -- the transition system --------------------------------------------------------------------------------
    def transition(self, a: SoundStep, action_var: z3.ArithRef, b: SoundStep) -> z3.BoolRef:
        """One decision step from ``a`` to ``b`` by the action numbered ``action_var`` (ACTION_ORDER): its guard, its
        effect (``spec.sound.advance``), the followers, and its window safe."""
        rules, grid, options = self.problem.rules, self.grid, []
        for index, action in enumerate(ACTION_ORDER):
            rule = ACTION_RULES[action]
            guard = [a.lc < rules.max_lane_changes] if rule.changes_lane else []
            if rule.from_lane is not None:
                guard.append(a.right == (rule.from_lane is Lane.RIGHT))
            lane_after = (rule.to_lane is Lane.RIGHT) if rule.to_lane is not None else a.right
            units, speed = grid.units(action), self.table.action_speed[action]
            effect = [b.right == lane_after, b.lc == a.lc + int(rule.changes_lane), b.t == a.t + units,
                      b.d == a.d + units - grid.left_shift(action),
                      b.first == z3.If(a.first == NO_SPEED, speed, a.first), b.last == speed,
                      b.moved == MOVED[rule.to_lane]]
            into_left = rule.to_lane is Lane.LEFT
            if not into_left:
                effect += [y == x for x, y in zip(a.follows, b.follows, strict=True)]
            windows = []
            for selected, window, frame, _ in self.candidates(a, action):
                body = self._safe(window, frame, b.follows)
                if into_left:  # the followers: those not held ahead at this action's boundary
                    body += [f == _term(_not(self._held(v, window.boundary, frame)))
                             for v, f in zip(self.same, b.follows, strict=True)]
                windows.append(_term(_and(selected, *body)))
            options.append(_all([action_var == index, *guard, *effect, _any(windows)]))
        if self.prune:
            return _term(_and(_any(options), _not(self.hopeless(b))))
        return _any(options)

    def done(self, s: SoundStep) -> z3.BoolRef:
        """A plan may end in ``s``: the goal at the continuation window's boundary, and the continuation safe (its
        window, then its end)."""
        options = []
        for selected, window, frame, lane in self.candidates(s, None):
            body = [*self._goal(window, frame, lane), *self._safe(window, frame, s.follows),
                    *self._end(window, frame, lane, s.follows)]
            options.append(_term(_and(selected, *body)))
        return _any(options)

    def start_refused(self, scenario: Scenario, own: Own | None = None, timeout_s: float | None = None) -> bool:
        """Whether ``scenario``'s start is refused (the start's conditions on its values, simplified to a constant);
        ``own``: its measured vehicles (``oracle.bmc_own``), each held to its own dynamics."""
        if not own:
            return z3.is_false(self._at(scenario, self.start_safe))
        skip = Skip(own.skip_same, own.skip_oncoming)
        window = self.table.start[scenario.lane]
        follows = self._follows(window.boundary, own)
        lane_bound = self._safe(window, ABSOLUTE, [False] * len(self.same), skip) + \
            self._start_in_lane(window, follows, skip)
        return not (z3.is_true(self._at(scenario, _term(_and(*lane_bound))))
                    and unbroken(own.broken(window, [z3.BoolVal(False)] * len(self.same))
                                 + own.start_broken(window, follows), timeout_s))

    def _at(self, scenario: Scenario, term: z3.BoolRef) -> z3.BoolRef:
        """``term`` at ``scenario``'s interval ends, simplified (to a constant: they are its only unknowns)."""
        fixed = [(p, z3.RealVal(v)) for p, v in self.values(scenario)]
        return z3.simplify(z3.substitute(term, *fixed) if fixed else term)

    def holds(self, scenario: Scenario, actions: Sequence[Action], goal: bool, own: Own | None = None,
              timeout_s: float | None = None) -> bool:
        """Whether ``actions``, a sequence known whole (``spec.commitment.Proofs.holds``), keep every condition from
        ``scenario``'s start: each step's window (``SoundTable.window`` at the step's own state, its lookup rule
        evaluated here, every state being known; cut where the ramp into the next action starts), the followers
        classified at each move into the left lane as ``transition`` does, then the continuation (its window and its
        end; with ``goal``, the goal at its boundary). No prune and no count of lane changes: an escape is neither
        a plan's step nor a move towards the goal. ``own``: the scenario's measured vehicles, each held to its own
        dynamics (``oracle.bmc_own``; a move back from the passing lane under the no-acceleration profile holds
        them from the passing window's start)."""
        table, lane = self.table, scenario.lane
        own = own if own else None
        skip = NO_SKIP if own is None else Skip(own.skip_same, own.skip_oncoming)
        state = SoundState(lane, 0, 0, 0, 0, None, None)
        out_units: int | None = None  # when the AV moved out into the passing lane (``SoundRules.passing_from_s``)
        start = table.start[lane]
        follows = self._follows(start.boundary, own)
        conditions: list[Cond] = []
        broken: list[z3.BoolRef] = []
        for k, action in enumerate(actions):
            following = actions[k + 1] if k + 1 < len(actions) else None
            window = table.state_window(state, action, following)
            to_lane = ACTION_RULES[action].to_lane
            if to_lane is Lane.LEFT:
                follows = self._follows(window.boundary, own)
            conditions += self._safe(window, ABSOLUTE, follows, skip)
            if own is not None:
                held_s = None
                if to_lane is Lane.LEFT and own.held_passing:
                    held_s = out_units * table.unit_s if out_units is not None else \
                        0.0 if state.lane is Lane.RIGHT else None
                broken += own.broken(window, follows, held_s)
            if to_lane is not None:
                out_units = state.t_units if to_lane is Lane.RIGHT else None
            state = advance(state, action, self.grid, table.speeds_mps[table.action_speed[action]])
        window = table.state_window(state, None)
        if goal:
            conditions += self._goal(window, ABSOLUTE, state.lane, skip)
            if own is not None:
                conditions += own.goal(window, state.lane, self.problem.goal, self.targets, self.sensed_oncoming)
        conditions += [*self._safe(window, ABSOLUTE, follows, skip), *self._end(window, ABSOLUTE, state.lane, follows,
                                                                                 skip)]
        if own is not None:
            broken += [*own.broken(window, follows), *own.end_broken(window, state.lane, follows)]
        return z3.is_true(self._at(scenario, _term(_and(*conditions)))) and unbroken(broken, timeout_s)

    def _follows(self, at: Instant, own: Own | None) -> list[Cond]:
        """Which same-direction vehicles follow the AV from a move into the left lane (or the start) at ``at``: those
        not held ahead there, each measured one by its own dynamics."""
        return [z3.Not(own.held(i, at)) if own is not None and i in own.same else _not(self._held(v, at, ABSOLUTE))
                for i, v in enumerate(self.same)]


class Unrolling:
    """An encoding's steps unrolled on one solver: step 0 is the encoding's start, each step after it the step
    template on its own variables."""

    def __init__(self, enc: SoundEncoding) -> None:
        self.enc = enc
        self.steps: list[SoundStep] = [enc.start]
        self.actions: list[z3.ArithRef] = []

    def bounds(self, k: int) -> z3.BoolRef:
        """Invariants after k actions, implied by the rules but cheap for the solver to use."""
        s, grid = self.steps[k], self.enc.grid
        units = [grid.units(a) for a in ACTION_ORDER]
        advance = [grid.units(a) - grid.left_shift(a) for a in ACTION_ORDER]
        speeds = len(self.enc.table.speeds_mps)
        return z3.And(self.lanes(k), s.t >= min(units) * k, s.t <= max(units) * k, s.d >= min(advance) * k,
                      s.d <= max(advance) * k, s.first >= 0, s.first < speeds, s.last >= 0, s.last < speeds,
                      s.moved >= 0, s.moved <= 2)

    def lanes(self, k: int) -> z3.BoolRef:
        """The lane after k actions (or, in a bounded unrolling, after k steps, the plan's end repeated): the start's
        after an even number of lane changes, the other after an odd one; the lane changes a whole number within
        the model's limit. Implied by the rules; without it, a proof that no plan does with fewer lane changes
        (every plan from the right lane needs one) takes the solver hundreds of milliseconds."""
        s, most = self.steps[k], self.enc.problem.rules.max_lane_changes
        odd = _any([s.lc == n for n in range(1, most + 1, 2)]) if most >= 1 else z3.BoolVal(False)
        starts_right = self.enc.problem.scenario.lane is Lane.RIGHT
        return z3.And(_any([s.lc == n for n in range(most + 1)]), s.right == (z3.Not(odd) if starts_right else odd))

    def advance(self) -> tuple[SoundStep, z3.ArithRef, SoundStep]:
        """Add the variables of one more decision step: the state it starts from, its action, the state it ends in."""
        a = self.steps[-1]
        action_var = z3.Int(f"a_{len(self.actions) + 1}")
        self.actions.append(action_var)
        self.steps.append(_variables(f"_{len(self.steps)}", len(self.enc.same)))
        return a, action_var, self.steps[-1]

    def extend(self) -> z3.BoolRef:
        """Add one decision step; return its transition constraint (the step template on this step's variables)."""
        a, action_var, b = self.advance()
        here, action, after, template = self.enc.step_template
        return Substitution([(action, action_var), *_pairs(here, a), *_pairs(after, b)])(template)

    def done_at(self, k: int) -> z3.BoolRef:
        here, template = self.enc.done_template
        return Substitution(_pairs(here, self.steps[k]))(template)

    def decode(self, model: z3.ModelRef, length: int, scenario: Scenario) -> tuple[tuple[Action, ...],
                                                                                   tuple[State, ...]]:
        """The plan of ``length`` actions in ``model`` and its display states (``oracle.sound.display``) from the
        model's own lanes, times, advances and lane changes."""
        def value(term: z3.ArithRef) -> int:
            return _value(model, term)

        actions = tuple(ACTION_ORDER[value(a)] for a in self.actions[:length])
        states = []
        for k in range(length + 1):
            s = self.steps[k]
            t, d = value(s.t), value(s.d)
            lane = Lane.RIGHT if z3.is_true(model.eval(s.right, model_completion=True)) else Lane.LEFT
            states.append(State(lane, tuple(c + t - d for c in scenario.left_lane),
                                tuple(c - t - d for c in scenario.right_lane), value(s.lc), k))
        return actions, tuple(states)


#: Whether the encoding prunes dead states as the interpreter does (``SoundEncoding._hopeless``).
PRUNE = True


def shape(problem: Problem) -> Hashable:
    """What an encoding depends on: ``oracle.bmc``'s shape, the sound model's assumptions, the minimal-risk
    manoeuvre's hold speed, the prune."""
    return bmc.shape(problem), problem.scenario.sound, hold_floor_mps(problem.scenario), PRUNE



_encodings: OrderedDict[Hashable, SoundEncoding] = OrderedDict()


def encoding(problem: Problem) -> SoundEncoding:
    """The encoding of ``problem``'s shape, built once for every solver of that shape (the shortest and the optimal
    strategies unroll the same templates)."""
    key = shape(problem)
    found = _encodings.pop(key, None)
    _encodings[key] = found if found is not None else SoundEncoding(problem, PRUNE)
    while len(_encodings) > bmc.KEEP_AT_MOST:
        _encodings.popitem(last=False)
    return _encodings[key]


class Kept(bmc.Kept):
    """``oracle.bmc.Kept``'s solver (checks within the time limit, interrupts, assumption literals) on this encoding
    (``bmc.Kept.__init__`` builds the paper's: not called)."""

    def __init__(self, problem: Problem) -> None:
        self.sound_enc = encoding(problem)
        self.unrolling = Unrolling(self.sound_enc)
        self.solver = z3.Solver()
        self.gave_up = False
        self.model = None
        self._literals = {}
        self._asserted = []
        self._whole = None

    def fixing(self, scenario: Scenario) -> list[z3.BoolRef]:
        """The literals that fix every interval-end parameter at ``scenario``'s values."""
        return [self.literal(term == z3.RealVal(value)) for term, value in self.sound_enc.values(scenario)]


class Shortest(Kept, bmc.Shortest):
    """``shortest``'s solver: the unrolling grows one step at a time; ``reached[k]`` equals ``done`` after k
    actions. Step j's transition holds only under its literal ``live[j - 1]``, assumed for the steps of the bound
    asked: a plan of k actions is never asked to go on past k (a state where it may end need have no safe
    successor), however deep an earlier problem unrolled the kept solver."""

    def __init__(self, problem: Problem) -> None:
        super().__init__(problem)
        self.add(self.sound_enc.initial)
        self.reached: list[z3.BoolRef] = []
        self.live: list[z3.BoolRef] = []
        self.last_bound: int | None = None
        self.last_proved = False  # whether the last problem's answer was no plan (its bound: where paths ended)

    def goal(self, k: int) -> z3.BoolRef:
        enc = self.unrolling
        while len(self.reached) <= k:
            if self.reached:
                live = z3.Bool(f"live_{len(self.reached)}")
                self.add(z3.Implies(live, enc.extend()), enc.bounds(len(self.reached)))
                self.live.append(live)
            literal = z3.Bool(f"done_{len(self.reached)}")
            self.add(literal == enc.done_at(len(self.reached)))
            self.reached.append(literal)
        return self.reached[k]

    def steps(self, k: int) -> list[z3.BoolRef]:
        """The literals that make the first k steps transitions."""
        self.goal(k)
        return self.live[:k]


class Optimal(Kept, bmc.Optimal):
    """``optimal``'s solver: the whole unrolling to the horizon with a symbolic length, and the cost terms
    (``below`` and ``equal`` are ``oracle.bmc.Optimal``'s)."""

    def __init__(self, problem: Problem) -> None:
        super().__init__(problem)
        self.length, constraints, self.terms, self.counted = bounded(self.unrolling)
        self.add(*constraints)
        self.last_cost: tuple[int, ...] | None = None


def bounded(unrolling: Unrolling) -> tuple[z3.ArithRef, list[z3.BoolRef], dict[str, z3.ArithRef],
                                         dict[str, list[z3.BoolRef]]]:
    """Plans of any length up to the horizon (``oracle.bmc.bounded`` on this encoding): a symbolic length N, steps
    after N repeat the last state, ``done`` at N and not before; the cost term by term, with one literal per step
    for the terms that count steps."""
    enc = unrolling.enc
    horizon = enc.problem.horizon
    length = z3.Int("length")
    here, action, after, transition = enc.step_template
    done, k_var = enc.done_template[1], z3.Int("k")
    reached = z3.And(z3.Implies(length == k_var, done), z3.Implies(k_var < length, z3.Not(done)))
    frozen = z3.And(*[y == x for x, y in zip(here.fields(), after.fields(), strict=True)])
    move = z3.And(reached, z3.If(k_var < length, transition, frozen))
    live = k_var + 1 <= length
    brake = ACTION_ORDER.index(Action.BRAKE)
    counts = {"right_lane_steps": z3.And(live, after.right), "brakes": z3.And(live, action == brake)}
    constraints = [enc.initial, length >= 0, length <= horizon]
    counted: dict[str, list[z3.BoolRef]] = {name: [] for name in counts}
    for k in range(horizon):
        a, action_var, b = unrolling.advance()
        substitute = Substitution([(k_var, z3.IntVal(k)), (action, action_var), *_pairs(here, a), *_pairs(after, b)])
        constraints += [substitute(move), unrolling.lanes(k + 1)]
        for name, condition in counts.items():
            literal = z3.Bool(f"{name}_{k + 1}")
            constraints.append(literal == substitute(condition))
            counted[name].append(literal)
    constraints.append(Substitution([(k_var, z3.IntVal(horizon)), *_pairs(here, unrolling.steps[horizon])])(reached))
    terms = {"lane_changes": unrolling.steps[-1].lc, "length": length,
             **{name: z3.Sum([z3.If(x, 1, 0) for x in literals]) if literals else z3.IntVal(0)
                for name, literals in counted.items()}}
    return length, constraints, terms, counted


K = TypeVar("K", bound=Kept)


@contextmanager
def _solver_for(kind: type[K], problem: Problem) -> Iterator[K]:
    """The kept solver of ``problem``'s shape (``oracle.bmc._solver_for``'s rules, in its store: one that gave up,
    was interrupted or raised is dropped; ``bmc.isolated()`` gives each problem its own)."""
    key = (kind, shape(problem))
    found = None if bmc._isolated else bmc._kept.pop(key, None)
    kept = found if isinstance(found, kind) else kind(problem)
    yield kept
    if not (bmc._isolated or kept.gave_up):
        bmc._kept[key] = kept
        while len(bmc._kept) > bmc.KEEP_AT_MOST:
            bmc._kept.popitem(last=False)


def _refused_start(kept: Kept, scenario: Scenario) -> SearchResult | None:
    if kept.sound_enc.start_refused(scenario):
        return SearchResult(Status.NO_PLAN, (), 0, "initial state refused")
    return None


def shortest(problem: Problem, limits: Limits | None = None) -> SearchResult:
    """``_shortest``, its answer kept for ``optimal``."""
    return _remember(problem, _shortest(problem, limits))


def _shortest(problem: Problem, limits: Limits | None) -> SearchResult:
    """The smallest k at which ``done`` holds (and at no earlier step), incrementally; the warm start of
    ``oracle.bmc.shortest``.

    "No plan" is proved as the interpreter proves it, when every path ends before the horizon: no path of m actions
    on which ``done`` held at no earlier step exists, so no plan of any length does (a longer plan would begin with
    one). The dead-state prune (``SoundEncoding._hopeless``) ends the paths that can never reach the goal, as it
    does the interpreter's. That check is asked after bounds 0, 1, 3, 7, ... (m a power of two), after the warm
    start's guess when the last problem had no plan, and after the horizon: whatever was asked before, the answer is
    "no plan" exactly when no such path of horizon + 1 actions exists. A warm start's guess after "no plan" is the m
    that proved it."""
    started = time.perf_counter()
    horizon, scenario = problem.horizon, problem.scenario
    with _solver_for(Shortest, problem) as kept:
        refused = _refused_start(kept, scenario)
        if refused is not None:
            return refused
        fixed, not_before, start = kept.fixing(scenario), list[z3.BoolRef](), 0

        def no_path(m: int) -> SearchResult | None:
            """"No plan" if no path of m actions avoids the goal before its end; "incomplete" if Z3 gave up."""
            verdict = kept.check(limits, started, *fixed, *kept.steps(m), *not_before)
            if verdict == z3.unknown:
                return SearchResult(Status.INCOMPLETE, (), m, f"z3: {kept.solver.reason_unknown()} on the paths of "
                                    f"{m} actions")
            if verdict == z3.sat:
                return None
            kept.last_bound, kept.last_proved = m, True
            return SearchResult(Status.NO_PLAN, (), m, f"proved: no plan of any length (no path of {m} action(s) "
                                "avoids the goal before its end, and no bound below is satisfiable)")

        expected = bmc.expected_length(problem, None)  # another engine's: a plan's bound, guessed as after a plan
        last, after_no_plan = (kept.last_bound, kept.last_proved) if expected is None else (expected, False)
        guess = None if last is None else min(last, horizon + 1)
        if guess is not None and guess > 1:
            verdict = kept.check(limits, started, *fixed, *kept.steps(guess - 1), kept.goal_before(guess))
            if verdict == z3.unknown:
                return SearchResult(Status.INCOMPLETE, (), 0, f"z3: {kept.solver.reason_unknown()} below bound {guess}")
            if verdict == z3.unsat:
                start, not_before = guess, [z3.Not(kept.goal(k)) for k in range(guess)]
                proved = no_path(guess) if after_no_plan else None  # after a plan, its bound comes first
                if proved is not None:
                    return proved
        for k in range(start, horizon + 1):
            reached = kept.goal(k)
            verdict = kept.check(limits, started, *fixed, *kept.steps(k), *not_before, reached)
            if verdict == z3.sat:
                kept.last_bound, kept.last_proved = k, False
                actions, states = kept.unrolling.decode(kept.checked_model(), k, scenario)
                return SearchResult(Status.PLAN, actions, k + 1, f"shortest: bound {k} satisfiable", states)
            if verdict == z3.unknown:
                return SearchResult(Status.INCOMPLETE, (), k, f"z3: {kept.solver.reason_unknown()} at bound {k}")
            not_before.append(z3.Not(reached))
            if k == horizon or (k + 1) & k == 0:
                proved = no_path(k + 1)
                if proved is not None:
                    return proved
        kept.last_bound, kept.last_proved = horizon + 1, True
    return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), horizon + 1,
                        f"proved: every bound up to {horizon} is unsatisfiable")


#: The last answers of ``shortest`` (a few problems: a pipeline's stages, a campaign's runs of one scenario).
_SHORTEST: OrderedDict[Problem, SearchResult] = OrderedDict()


def _remember(problem: Problem, found: SearchResult) -> SearchResult:
    """Keep ``shortest``'s answer on ``problem`` for ``optimal`` (an incomplete one is never kept)."""
    if found.status is not Status.INCOMPLETE:
        _SHORTEST[problem] = found
        while len(_SHORTEST) > 16:
            _SHORTEST.popitem(last=False)
    return found


def _shortest_answer(problem: Problem, limits: Limits | None) -> SearchResult:
    """``shortest``'s answer on ``problem``: the one it last gave, or a new one."""
    found = _SHORTEST.get(problem)
    return found if found is not None else shortest(problem, limits)


def optimal(problem: Problem, limits: Limits | None = None) -> SearchResult:
    """The plan of least cost (COST_DOC) among all plans of at most ``horizon`` actions: ``oracle.bmc.optimal``'s
    lexicographic bisection with its warm start, on this encoding.

    Whether a plan exists at all, and the fewest actions one takes, is ``shortest``'s answer on this encoding (its
    proofs of no plan are far cheaper than one check of the whole unrolling)."""
    started = time.perf_counter()
    scenario = problem.scenario
    least = _shortest_answer(problem, limits)
    if least.status is not Status.PLAN:
        return replace(least, detail=f"shortest (no plan to optimise): {least.detail}")
    limits = None if limits is None else limits.remaining(started, time.perf_counter())
    started = time.perf_counter()
    with _solver_for(Optimal, problem) as kept:
        solver, terms = kept.solver, kept.terms
        assumed = kept.fixing(scenario)
        guess, model, checks = bmc.expected_cost(problem, kept.last_cost), None, 0
        if guess is not None:  # the last problem's least cost (often this one's too)
            verdict, checks = kept.check(limits, started, *assumed, *kept.costing(guess)), 1
            if verdict == z3.unknown:
                return bmc._gave_up(solver, checks)
            model = kept.checked_model() if verdict == z3.sat else None
        if model is None:  # the shortest plan, its actions fixed: a check that propagates, never searches
            plan = [kept.literal(var == ACTION_ORDER.index(action))
                    for var, action in zip(kept.unrolling.actions, least.actions, strict=False)]
            verdict, checks = kept.check(limits, started, *assumed, *plan,
                                         kept.literal(kept.length == len(least.actions))), checks + 1
            if verdict == z3.unknown:
                return bmc._gave_up(solver, checks)
            if verdict == z3.unsat:
                raise EngineError(f"z3: the shortest plan {[a.value for a in least.actions]} is no plan of the "
                                  "bounded unrolling (the two unrollings of the sound model disagree)")
            model = kept.checked_model()
        floors = {"length": len(least.actions)}  # no plan is shorter than the shortest: proved, not asked again
        for index, name in enumerate(COST_TERMS):
            floor, best = floors.get(name, 0), _value(model, terms[name])
            tries = [] if guess is None else [guess[index], guess[index] - 1]
            while floor < best:
                middle = next((t for t in tries if floor <= t < best), (floor + best) // 2)
                tries = [t for t in tries if t != middle]
                verdict, checks = kept.check(limits, started, *assumed, kept.below(name, middle + 1)), checks + 1
                if verdict == z3.unknown:
                    return bmc._gave_up(solver, checks)
                if verdict == z3.unsat:
                    floor = middle + 1
                else:
                    model = kept.checked_model()
                    best = _value(model, terms[name])
            assumed.append(kept.equal(name, best))
        kept.last_cost = tuple(_value(model, terms[name]) for name in COST_TERMS)
        actions, states = kept.unrolling.decode(model, _value(model, kept.length), scenario)
    cost = dict(zip(COST_TERMS, total_cost(zip(actions, states[1:])), strict=True))
    return SearchResult(Status.PLAN, actions, checks, f"optimal under {COST_DOC}", states,
                        {"cost": cost, "cost_order": list(COST_TERMS)})


def _value(model: z3.ModelRef, term: z3.ArithRef) -> int:
    found = model.eval(term, model_completion=True)
    return int(found.as_long()) if z3.is_int_value(found) else int(found.as_fraction())


SOLVERS: dict[Strategy, Callable[[Problem, Limits | None], SearchResult]] = {
    Strategy.SHORTEST: shortest, Strategy.OPTIMAL: optimal}
