"""The sound model's windows as every engine translates them: one table per (assumptions, grid), no vehicle in it.

A step of the sound model is safe when every vehicle keeps its gap over the step's window
(``spec.sound``). Where over a piece of the window each condition binds (the worst instant of
the AV's reference against a vehicle's bound) does not depend on the vehicle: this table holds,
for each piece, the reference at the piece's start and at each condition's worst instant. An
engine translates the rest itself, from the same declarations the interpreter reads: a
vehicle's interval (its cell's extent, ``spec.cells``, widened by the sensing error; the
phantoms, ``spec.assumptions``), its growth with its lane's speed bounds, the AV's envelope
(``spec.envelope``) and the required gap (``spec.safety``):

- ``AHEAD`` (a stretch in the left lane, not entering it), per piece, per same-direction vehicle
  not a follower and held ahead at the piece's start (``lo + low t0 - L >= x0 + e_x``): refused
  when ``lo + low t < x + e_x + L + gap(v + e_v - low) + EPS_M`` at the piece's ``ahead`` instant;
- ``ONCOMING`` (a stretch in the right lane), per oncoming vehicle not passed at the piece's start
  (``hi - low_o t0 + L <= x0 - e_x - EPS_M``): refused when ``lo - high_o t < x + e_x + L +
  gap(v + e_v + high_o) + EPS_M`` at its ``oncoming`` instant;
- entering the left lane (``entering``), per same-direction vehicle: safe when it is ahead (the
  ``AHEAD`` test above, not refused) at every piece, or behind at every piece: ``hi + high t <= x
  - e_x - L - gap(high - v + e_v) - EPS_M`` at each ``behind`` instant (at the plan's start,
  ``at_start``, one short of ``spec.sound.follower_limit_m(x0)`` follows: ``hi <= limit - EPS_M``);
- followers: at the start, and at the boundary of a move into the left lane (``boundary``), the
  same-direction vehicles not held ahead there; they stay followers until the next such move; over
  a piece marked ``rear`` (``spec.sound.rear_binds``: followers keep their speed and the reference
  is slower than they may be), each follower must be behind as a cut-in must: ``hi + high t <= x -
  e_x - L - gap(high - v + e_v) - EPS_M`` at the piece's ``behind`` instant;
- the end of a plan: its continuation window (action None) as above, then at its ``end``: in the
  right lane every oncoming vehicle passed; in the left lane, when the reference closes in
  (``spec.envelope.MinimalRisk.closes_in``: ``v > low`` at the end),
  no same-direction vehicle but a follower held ahead; and when followers bind at the end speed
  (``rear_binds``), no follower at all;
- the goal, at the continuation window's ``boundary`` (``spec.sound.SoundRules.goal_holds``).

Lookup (``SoundTable.window``): a window while the first ramp still runs is in ``early`` under
the state's whole key; any other is its shape in ``relative`` (by the speed before the
boundary, the action, the lane and the lane the action before moved into) moved by ``t_units``
time units and ``d_cells`` cells plus the first ramp's gain (``gain_m``).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field, replace

from spec.actions import ACTION_RULES, Action
from spec.envelope import Reference
from spec.grid import Grid
from spec.lanes import Lane
from spec.motion import ramp_gain_m, ramp_s
from spec.sound import Bounded, Segment, Sound, SoundRules, SoundState, advance

NO_SPEED = -1  # a state's first or last speed before any action (``SoundState.first_mps`` None)


@dataclass(frozen=True, slots=True)
class Instant:
    """The AV's reference at one instant: time on the plan's clock, position from the AV's start, speed."""

    t_s: float
    x_m: float
    v_mps: float

    def shifted(self, dt_s: float, dx_m: float) -> Instant:
        return Instant(self.t_s + dt_s, self.x_m + dx_m, self.v_mps)


@dataclass(frozen=True, slots=True)
class Binding:
    """One piece of a window: the reference at its start, and at the instant each condition binds over it; and the
    piece itself (its end and its acceleration: with ``start`` its motion), for a vehicle measured to move by its own
    dynamics, whose thresholds an engine forms over the piece itself (``spec.sound.SoundRules._own_need``)."""

    start: Instant
    ahead: Instant
    oncoming: Instant
    behind: Instant
    rear: bool  # the followers are in conflict over this piece (``spec.sound.rear_binds``): ``behind`` holds them
    end_s: float
    acc_mps2: float

    def shifted(self, dt_s: float, dx_m: float) -> Binding:
        return Binding(self.start.shifted(dt_s, dx_m), self.ahead.shifted(dt_s, dx_m),
                       self.oncoming.shifted(dt_s, dx_m), self.behind.shifted(dt_s, dx_m), self.rear,
                       self.end_s + dt_s, self.acc_mps2)


@dataclass(frozen=True, slots=True)
class Stretch:
    """A stretch of a window with one occupancy: the lanes the AV is in, whether it is entering the left one (at the
    plan's start: already in it), and its pieces."""

    left: bool
    right: bool
    entering: bool
    at_start: bool
    pieces: tuple[Binding, ...]


@dataclass(frozen=True, slots=True)
class Window:
    """A step's window (or the continuation's, or the start's): its stretches, the reference at its boundary and at
    its end."""

    stretches: tuple[Stretch, ...]
    boundary: Instant
    end: Instant

    def shifted(self, dt_s: float, dx_m: float) -> Window:
        return Window(tuple(Stretch(s.left, s.right, s.entering, s.at_start,
                                    tuple(b.shifted(dt_s, dx_m) for b in s.pieces)) for s in self.stretches),
                      self.boundary.shifted(dt_s, dx_m), self.end.shifted(dt_s, dx_m))


ShapeKey = tuple[int, Action | None, Lane, Lane | None]  # speed before, action (None: continuation), lane, moved
EarlyKey = tuple[Lane, int, int, int, int, Lane | None, Action | None]  # lane, t, d, first, last, moved, action
CutKey = tuple[Action, Lane, Lane | None, float]  # action, lane, moved, the speed of the action that follows


@dataclass(frozen=True)
class SoundTable:
    """Every window of the sound model under one set of assumptions on one grid (see the module's docstring)."""

    sound: Sound
    grid: Grid
    unit_s: float  # one time unit
    cell_m: float  # one cell
    speeds_mps: tuple[float, ...]  # every speed a state records: the actions' and the start's, ascending
    action_speed: dict[Action, int]  # index into speeds_mps
    start_speed: int
    gain_m: tuple[float, ...]  # per first speed: how far the first ramp puts the AV ahead of its nominal position
    relative: dict[ShapeKey, Window]
    early: dict[EarlyKey, Window]
    start: dict[Lane, Window]  # the plan's start, an instant
    #: under the commitment semantics (a sequence known whole), each step window cut where the ramp into a following
    #: action of another speed starts (``SoundRules.step_violation``'s ``following``), by the following's speed index
    relative_cut: dict[tuple[ShapeKey, int], Window] = field(default_factory=dict)
    early_cut: dict[tuple[EarlyKey, int], Window] = field(default_factory=dict)
    #: the start lanes its early windows serve: both, or the one a sideways move under way at the start goes to
    starts: tuple[Lane, ...] = tuple(Lane)

    def speed_index(self, speed_mps: float | None) -> int:
        return NO_SPEED if speed_mps is None else self.speeds_mps.index(speed_mps)

    def window(self, lane: Lane, t_units: int, d_cells: int, first: int, last: int, moved: Lane | None,
               action: Action | None, following: int = NO_SPEED) -> Window:
        """The window of ``action`` (None: the continuation) from a state given by its lane, time, advance, first
        and last speed (indices, ``NO_SPEED``) and the lane its last action moved into; ``following``: the speed
        index of the action known to follow it (``NO_SPEED``: none known)."""
        cut = action is not None and following not in (NO_SPEED, self.action_speed[action])
        early_key = (lane, t_units, d_cells, first, last, moved, action)
        found = self.early_cut.get((early_key, following)) if cut else self.early.get(early_key)
        if found is not None:
            return found
        if first == NO_SPEED:
            first = self.start_speed if action is None else self.action_speed[action]
        before = first if last == NO_SPEED else last
        shape = self.relative_cut[(before, action, lane, moved), following] if cut else \
            self.relative[before, action, lane, moved]
        return shape.shifted(t_units * self.unit_s, d_cells * self.cell_m + self.gain_m[first])

    def state_window(self, state: SoundState, action: Action | None, following: Action | None = None) -> Window:
        return self.window(state.lane, state.t_units, state.d_cells, self.speed_index(state.first_mps),
                           self.speed_index(state.last_mps), state.moved, action,
                           NO_SPEED if following is None else self.action_speed[following])


def _instant(b: Bounded, t_s: float) -> Instant:
    return Instant(t_s, b.piece.x(t_s), b.piece.v(t_s))


def _binding(b: Bounded) -> Binding:
    p = b.piece
    return Binding(Instant(p.t0_s, p.x0_m, p.v0_mps), _instant(b, b.ahead[1]), _instant(b, b.oncoming[1]),
                   _instant(b, b.behind[1]), b.rear, p.t1_s, p.acc_mps2)


def declared(window: list[tuple[Segment, list[Bounded]]], boundary: Instant) -> Window:
    """A window of ``SoundRules`` as the table holds it."""
    stretches = tuple(Stretch(Lane.LEFT in seg.lanes, Lane.RIGHT in seg.lanes, seg.entering_left, seg.at_start,
                              tuple(_binding(b) for b in pieces)) for seg, pieces in window)
    tail = window[-1][1][-1].piece
    return Window(stretches, boundary, Instant(tail.t1_s, tail.x(tail.t1_s), tail.v(tail.t1_s)))


def sound_table(sound: Sound, grid: Grid, hold_floor_mps: float | None = None, lane: Lane | None = None) -> SoundTable:
    """The table of ``sound`` on ``grid``: every shape, every window while the first ramp runs (from either lane,
    every action order the lanes allow), the start. ``hold_floor_mps``: the speed the minimal-risk manoeuvre brakes to
    in the scenarios it serves (``spec.sound.slowest_ahead_mps``: a standstill where a same-direction vehicle's speed
    was measured; None: the lane's slowest); the windows never read the vehicles otherwise. ``lane``: the start's,
    read only while a sideways move is under way there (``Sound.sideways_s``: the windows it overlaps depend on the
    lane it moves into): the table's early windows then start from that lane alone."""
    if sound.sideways_s and lane is None:
        raise ValueError("a table with a sideways move under way at the start serves one start lane: name it")
    return _sound_table(sound, grid, hold_floor_mps, lane if sound.sideways_s else None)


def forget_tables() -> None:
    """Forget every table ``sound_table`` built (a benchmark's fresh start; the shapes stay)."""
    _sound_table.cache_clear()


@functools.lru_cache(maxsize=16)
def _sound_table(sound: Sound, grid: Grid, hold_floor_mps: float | None, moving_to: Lane | None) -> SoundTable:
    rules = _rules(sound, grid, hold_floor_mps, Lane.RIGHT if moving_to is None else moving_to)
    action_speeds = {a: rules.speeds[a] for a in Action}
    speeds = tuple(sorted({*action_speeds.values(), rules.start_mps}))
    index = {v: i for i, v in enumerate(speeds)}
    unstarted = replace(sound, start_mps=None, sideways_s=0.0)
    # after the start speed (when no action drives at it) only the continuation from the start is ever looked up
    relative: dict[ShapeKey, Window] = {
        (index[before], *key): w for before in speeds
        for key, w in shapes(unstarted, grid, before, before not in action_speeds.values(), hold_floor_mps).items()}
    cuts = sound.commitment is not None
    relative_cut: dict[tuple[ShapeKey, int], Window] = {} if not cuts else {
        ((index[before], action, lane, moved), index[v]): w for before in speeds if before in action_speeds.values()
        for (action, lane, moved, v), w in cut_shapes(unstarted, grid, before, hold_floor_mps).items()}
    early_windows: dict[EarlyKey, Window] = {}
    early_cut: dict[tuple[EarlyKey, int], Window] = {}
    first_end_s = max(ramp_s(rules.start_mps, v) for v in speeds)
    half_ramp_s = max(ramp_s(a, b) for a in speeds for b in speeds) / 2
    todo = [SoundState(lane, 0, 0, 0, 0, None, None) for lane in (Lane if moving_to is None else (moving_to,))]
    seen: set[tuple[object, ...]] = set()
    while todo:
        state = todo.pop()
        if state.key() in seen or state.t_units * rules.unit_s - half_ramp_s >= max(first_end_s, sound.sideways_s):
            continue
        seen.add(state.key())
        for action in (*Action, None):
            if action is not None and ACTION_RULES[action].from_lane not in (None, state.lane):
                continue
            ref = rules.reference(state, action)
            if rules.is_early(ref):
                key = (state.lane, state.t_units, state.d_cells, _index(index, state.first_mps),
                       _index(index, state.last_mps), state.moved, action)
                window, boundary = rules.window(state, action), _at_boundary(ref)
                early_windows[key] = declared(window, boundary)
                if cuts and action is not None:
                    for v, following in _other_speeds(rules, action).items():
                        cut_s = rules.cut_s(state.t_units, action, following)
                        assert cut_s is not None  # another speed: a ramp
                        early_cut[key, index[v]] = declared(rules.cut_window(window, cut_s), boundary)
            if action is not None:
                todo.append(advance(state, action, grid, action_speeds[action]))
    start = {}
    for lane in Lane:
        ref = rules.reference(SoundState(lane, 0, 0, 0, 0, None, None), None)
        seg = _rules(sound, grid, hold_floor_mps, lane).start_segment()
        start[lane] = declared([(seg, [rules._bounded(p) for p in ref.pieces(0.0, 0.0)])], _at_boundary(ref))
    gains = tuple(ramp_gain_m(rules.start_mps, v) for v in speeds)
    return SoundTable(sound, grid, rules.unit_s, rules.cell_m, speeds, {a: index[v] for a, v in action_speeds.items()},
                      index[rules.start_mps], gains, relative, early_windows, start, relative_cut, early_cut,
                      tuple(Lane) if moving_to is None else (moving_to,))


def _rules(sound: Sound, grid: Grid, hold_floor_mps: float | None, lane: Lane = Lane.RIGHT) -> SoundRules:
    """The rules the table asks its windows of: no vehicle, the minimal-risk manoeuvre's hold speed given (None: the
    lane's slowest), from ``lane`` (only a sideways move under way at the start, ``Sound.sideways_s``, reads it)."""
    return SoundRules(sound, lane, (), (), grid, (), hold_floor_mps=hold_floor_mps)


@functools.lru_cache(maxsize=64)
def shapes(sound: Sound, grid: Grid, before_mps: float, continuation_only: bool = False,
           hold_floor_mps: float | None = None) -> dict[tuple[Action | None, Lane, Lane | None], Window]:
    """Every window's shape after the speed ``before_mps`` (``SoundRules.relative_window``), by action (None: the
    continuation), lane and the lane the action before moved into; ``continuation_only``: the continuation's alone
    (after a start speed no action drives at, the only shape ever looked up). A shape never reads the AV's start
    speed: the closed loop's every new measured speed reuses the shapes of the actions' speeds (``sound`` comes with
    ``start_mps`` None); ``hold_floor_mps`` as ``sound_table``'s."""
    rules = _rules(sound, grid, hold_floor_mps)
    found: dict[tuple[Action | None, Lane, Lane | None], Window] = {}
    for lane in Lane:
        for moved in (None, lane):
            for action in (None,) if continuation_only else (*Action, None):
                if action is not None and ACTION_RULES[action].from_lane not in (None, lane):
                    continue
                shape = rules.relative_window(before_mps, action, lane, moved)
                ref = rules._reference(0.0, 0.0, before_mps, before_mps, action, before_mps)
                found[action, lane, moved] = declared(shape, _at_boundary(ref))
    return found


@functools.lru_cache(maxsize=64)
def cut_shapes(sound: Sound, grid: Grid, before_mps: float, hold_floor_mps: float | None = None) -> dict[
        CutKey, Window]:
    """Every step window's shape after the speed ``before_mps`` cut where the ramp into a following action of another
    speed starts, centred on the step's end (``SoundRules.step_violation`` with ``following``): by action, lane,
    moved and the following action's speed. Only a sequence known whole (the commitment semantics) asks for them."""
    rules = _rules(sound, grid, hold_floor_mps)
    found: dict[CutKey, Window] = {}
    for lane in Lane:
        for moved in (None, lane):
            for action in Action:
                if ACTION_RULES[action].from_lane not in (None, lane):
                    continue
                shape = rules.relative_window(before_mps, action, lane, moved)
                ref = rules._reference(0.0, 0.0, before_mps, before_mps, action, before_mps)
                for v, following in _other_speeds(rules, action).items():
                    cut_s = rules.cut_s(0, action, following)  # a shape starts at time 0
                    assert cut_s is not None  # another speed: a ramp
                    found[action, lane, moved, v] = declared(rules.cut_window(shape, cut_s), _at_boundary(ref))
    return found


def _other_speeds(rules: SoundRules, action: Action) -> dict[float, Action]:
    """Each speed of an action but ``action``'s, with one action at it (a cut depends on the speeds alone)."""
    return {rules.speeds[a]: a for a in reversed(Action) if rules.speeds[a] != rules.speeds[action]}


def _index(index: dict[float, int], speed: float | None) -> int:
    return NO_SPEED if speed is None else index[speed]


def _at_boundary(ref: Reference) -> Instant:
    t_s = ref.boundary_s
    return Instant(t_s, ref.position_m(t_s), ref.speed_mps(t_s))
