"""How tight the sound model is (issue #23, point 8; #58, point 6): is every step it refuses broken by some motion
within the bounds, or refused only because a cell was rounded outwards?

Usage: python -m ci.conformance.tightness [--count 60] [--seed 2026] [--space left=2@8..20,right=1@12..30,lanes=both]
                              [--jobs 2] [--max-states 20000] [--show 3] [--semantics commit|whole]

For a seeded sample of the conformance example sweep (paper grid; the same traffic cut finer for
10.5, 7 and 5.25 m cells, ``ci.shared.gen.refined``), under the ``paper`` and the ``default`` profile,
and for each problem of the pipeline, every refusal is classified. Under the **commitment semantics** (the
default, ``spec.escapes``): the start, when it already breaks the specification, and each enabled first action the
model does not commit to, checked under **every escape** the commitment allows after it (the action and the escape
as one sequence, then the minimal-risk manoeuvre: that escape's first refusal); each later step is another
snapshot's decision. Under the **whole-plan semantics** (``--semantics whole``) every sound state reachable within
the horizon by enabled, safe actions is walked (no search prune, not stopping at the goal: every state a search
could visit), and each refusal met is one:

- a **step** refusal: an enabled action whose ``step_violation`` is not None;
- a **start** refusal: the initial state's ``start_violation``;
- an **end** refusal: a state where the goal holds but ``continuation_violation`` forbids ending the plan there.

A refusal is ``EXHIBITED`` when a concrete motion within the bounds breaks the specification
inside the refused window; ``ROUNDING`` when none does, but the shortfall is at most one cell and
the binding vehicle, sensed one cell farther in its favour, would let the action through; else
``NEITHER``: a refusal nothing justifies, diagnosed (``Finding``) and counted, with examples
printed. The motions are checked from the declarations alone (``spec.safety``, the bounds, the
envelope through ``oracle.reach.Path``), never from ``spec.sound``'s thresholds: the binding
vehicle starts anywhere in its interval and keeps a constant speed within its lane's interval;
the AV is at a corner of its envelope (reference position and speed, each +- the tracking error)
at the instant of the breach, as the specification reads the envelope (the worst over it at each
instant, as ``oracle.reach.exact_check`` does). The first motion tried is the one the violation
names (its time, its vehicle's binding end, the worst speeds); then the whole window, sampled at
most 10 ms apart.
"""

from __future__ import annotations

import argparse
import enum
import math
import os
import random
import time
from collections import deque
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field, replace
from fractions import Fraction

import numpy as np
from rich.console import Console
from rich.table import Table

from ci.conformance.crossval import parse_space
from ci.shared.machine import machine
from oracle.planner import plan
from oracle.reach import MAX_DT_S, TOLERANCE_M, Path
from oracle.sound import _paper, rules_for, start
from spec.actions import Action
from spec.answers import Status, Strategy
from spec.assumptions import profile
from spec.commitment import lane_after
from spec.escapes import COMMIT, Escape, Semantics
from spec.grid import PAPER_GRID, STANDARD_CELLS_M, Grid
from spec.lanes import Lane
from spec.models import ModelKind, models_for
from spec.rules import disabled_guard
from spec.safety import Conflict
from spec.scenario import Problem, Scenario, problem_for, refined
from spec.sound import (
    Sound,
    SoundRules,
    SoundState,
    Vehicle,
    Violation,
    clear_ahead_from_m,
    follower_limit_m,
    rear_binds,
    vehicles,
)

DEFAULT_SPACE = "left=2@8..20,right=1@12..30,lanes=both"
#: The profiles measured: the paper's world stated as bounds, and the default one (``spec.assumptions``).
PROFILES = ("paper", "default")
#: States walked per problem at most: above the most any problem reached in a 20-scenario probe of the sweep
#: (13,146, paper profile); a problem that hits it is counted in the summary line.
MAX_STATES = 20_000
#: How long after a plan's end the "safe for ever" condition is followed: longer than the slowest meeting the
#: continuation can hold back (an oncoming vehicle 357 m away, the front-right sensor's range, at the slowest
#: oncoming speed of either profile, 4.9 m/s: 73 s; the AV itself never drives away from it).
FOREVER_S = 120.0
#: Scenarios drawn by default: what the measurement gets through in about 10 minutes on 2 cores (the whole sweep,
#: 8,680 scenarios, would take hours); the sample is a prefix of ``ci.bench.sound``'s (same seed, same draw).
SAMPLE = 60
#: Witness positions this far inside a boundary (metres): a vehicle just not past, or just not a follower.
NUDGE_M = 1e-6


class Tightness(enum.Enum):
    """How a refusal is justified."""

    EXHIBITED = "exhibited by a motion"  # a concrete motion within the bounds breaks the specification
    ROUNDING = "rounding only"  # no motion does; the shortfall is at most one cell and one cell more would do
    NEITHER = "neither"  # a refusal nothing justifies: a finding


class Where(enum.Enum):
    """What a refusal forbids."""

    START = "start"  # the initial state (``start_violation``): no plan at all
    STEP = "step"  # an enabled action (``step_violation``)
    END = "end"  # ending a plan where the goal holds (``continuation_violation``)


@dataclass(frozen=True, slots=True)
class Refusal:
    """One refusal of the sound model: where (the actions leading to the state), what, and the model's reason."""

    where: Where
    state: SoundState
    prefix: tuple[Action, ...]  # the actions from the start to ``state`` (the first found, breadth first)
    action: Action | None  # the refused action; None for a start or an end refusal
    violation: Violation

    def describe(self) -> str:
        what = {Where.START: "the start", Where.END: "ending the plan here",
                Where.STEP: f"{self.action.value if self.action else '-'}"}[self.where]
        prefix = ",".join(a.value for a in self.prefix) or "(start)"
        return f"after {prefix}: {what} refused, {self.violation.describe()}"


@dataclass(frozen=True, slots=True)
class Witness:
    """A concrete motion within the bounds that breaks the specification: the vehicle's true start and constant
    speed, the AV's deviation from its reference at the instant of the breach, and the breach."""

    start_m: float  # the vehicle's centre at the plan's start, metres ahead of the AV's reference
    speed_mps: float  # its constant speed (oncoming: towards the AV)
    av_offset_m: float  # the AV's position less its reference's, at the breach
    av_speed_offset_mps: float  # the AV's speed less its reference's, at the breach
    time_s: float
    conflict: Conflict
    gap_m: float
    required_m: float


# -- the refusals ---------------------------------------------------------------------------------------------
def sound_rules(problem: Problem) -> SoundRules:
    """The sound model's rules on ``problem`` (the interpreter's cached ones), which must be the physical checks."""
    rules = rules_for(problem)
    if not isinstance(rules, SoundRules):
        raise ValueError(f"the scenario's sound model is not checked physically: {type(rules).__name__}")
    return rules


def refusals(problem: Problem, max_states: int = MAX_STATES) -> tuple[list[Refusal], int, bool]:
    """Every refusal of the sound model on ``problem``: the start's, then, breadth first over the states reachable
    by enabled, safe actions within the horizon (deduplicated by ``SoundState.key``), each refused enabled action
    and each refused end where the goal holds. Also the states walked and whether ``max_states`` stopped the walk."""
    rules, first = sound_rules(problem), start(problem)
    hit = rules.start_violation(first)
    if hit is not None:
        return [Refusal(Where.START, first, (), None, hit)], 1, False
    out: list[Refusal] = []
    prefix: dict[tuple[object, ...], tuple[Action, ...]] = {first.key(): ()}
    queue, capped = deque([first]), False
    while queue:
        state = queue.popleft()
        path = prefix[state.key()]
        if rules.goal_holds(state, problem.goal):
            end = rules.continuation_violation(state)
            if end is not None:
                out.append(Refusal(Where.END, state, path, None, end))
        if state.steps >= problem.horizon:
            continue
        for action in Action:
            if disabled_guard(_paper(state), action, problem.rules) is not None:
                continue
            found = rules.step_violation(state, action)
            if found is not None:
                out.append(Refusal(Where.STEP, state, path, action, found))
                continue
            nxt = rules.after(state, action)
            if nxt.key() in prefix:
                continue
            if len(prefix) >= max_states:
                capped = True
                continue
            prefix[nxt.key()] = (*path, action)
            queue.append(nxt)
    return out, len(prefix), capped


# -- the witness: a concrete motion, checked from the declarations --------------------------------------------
def plan_path(scenario: Scenario, refusal: Refusal) -> Path:
    """The AV's reference (``oracle.reach.Path``) through the actions to the refused state and the refused action,
    then the minimal-risk manoeuvre."""
    if scenario.sound is None:
        raise ValueError("the scenario has no sound model")
    actions = refusal.prefix + ((refusal.action,) if refusal.action is not None else ())
    return Path(actions, scenario.sound, scenario.grid, scenario.lane)


def window_s(refusal: Refusal, path: Path) -> tuple[float, float]:
    """The refused window on the plan's clock: a step's from the start of the ramp into it (centred on its boundary;
    the first action's starts at once) to its end; a start's, the instant 0, and for a vehicle behind the AV
    (``BEHIND``) the first sample after it too (``MAX_DT_S``: the envelope may put the AV anywhere within it at any
    instant, so its drift back reaches such a vehicle at once); an end's, from the plan's end on for ``FOREVER_S``."""
    if refusal.where is Where.START:
        return 0.0, MAX_DT_S if refusal.violation.conflict is Conflict.BEHIND else 0.0
    if refusal.where is Where.END:
        return path.end_s, path.end_s + FOREVER_S
    k = len(refusal.prefix)
    boundary, end = path.bounds_s[k], path.bounds_s[k + 1]
    ramp_from = [r.start_s for r in path.ramps
                 if r.start_s < boundary and math.isclose(r.start_s + r.duration_s / 2, boundary, abs_tol=1e-9)]
    return min([boundary, *ramp_from]), end


@dataclass(frozen=True, slots=True)
class _Chunk:
    """A stretch of the refused window with one occupancy of the AV (each boundary in both stretches)."""

    t0_s: float
    t1_s: float
    lanes: frozenset[Lane]
    entering: bool  # the AV is moving into the left lane
    entry_s: float | None  # in the left lane, not entering: when the AV got into it (started in it, or finished
    # moving into it); None otherwise


def _chunks(path: Path, lane: Lane, t0_s: float, t1_s: float) -> list[_Chunk]:
    """The window ``[t0_s, t1_s]`` cut where the AV's occupancy changes (``Path.lanes``, then its final lane)."""
    spans = [*path.lanes, (path.end_s, math.inf, frozenset({path.final_lane}), False)]
    entry: float | None = 0.0 if lane is Lane.LEFT else None
    out = []
    for a, b, lanes, entering in spans:
        lo, hi = max(a, t0_s), min(b, t1_s)
        if lo <= hi:
            follows = Lane.LEFT in lanes and not entering
            out.append(_Chunk(lo, hi, lanes, entering, entry if follows else None))
        if Lane.LEFT not in lanes:
            entry = None
        elif entering:
            entry = b
    return out


#: Once a plan and its minimal-risk manoeuvre have run their last ramp (the AV at a constant reference speed), the
#: "safe for ever" condition is sampled this far apart. A breach by a vehicle at a constant speed then lasts at least
#: the time gap (1.5 s): from the required gap, at least 1.5 s of closing, down to the bumpers' meeting (oncoming),
#: or for ever (one ahead that did not follow). A coarser scan could only miss a breach (leave a refusal
#: unexhibited), never invent one.
FAR_DT_S = 0.5


def _sample_times(t0_s: float, t1_s: float, dt_s: float, extra_s: float, path: Path) -> np.ndarray:
    """Samples of ``[t0_s, t1_s]`` at most ``dt_s`` apart (``FAR_DT_S`` once every ramp of ``path`` has run, after
    its plan), the ends, the last ramp's end and ``extra_s`` (when inside) among them."""
    settled = max([path.end_s, *(r.start_s + r.duration_s for r in path.ramps)])
    near = min(t1_s, max(t0_s, settled))
    parts = [np.linspace(t0_s, near, max(1, math.ceil((near - t0_s) / dt_s)) + 1)]
    if t1_s > near:
        parts.append(np.linspace(near, t1_s, max(1, math.ceil((t1_s - near) / FAR_DT_S)) + 1))
    if t0_s <= extra_s <= t1_s:
        parts.append(np.array([extra_s]))
    return np.unique(np.concatenate(parts))


def _reference(path: Path, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``Path.position`` and ``Path.speed`` at many times at once (the same sum of ramps; every breach this screen
    finds is confirmed with ``Path``'s own functions)."""
    x, v = path.start_mps * times, np.full(times.shape, path.start_mps)
    for r in path.ramps:
        if r.duration_s <= 0:
            continue
        u = np.clip(times - r.start_s, 0.0, r.duration_s)
        v = v + r.dv_mps * u / r.duration_s
        x = x + r.dv_mps * (u * u / (2 * r.duration_s) + np.maximum(times - r.start_s - r.duration_s, 0.0)) \
            - r.integral_m(0.0)
    return x, v


def _follow_limit_m(scenario: Scenario, path: Path, entry_s: float) -> float:
    """Where a same-direction vehicle must be, at most, when the AV got into the left lane at ``entry_s`` to follow
    it: in the lane from the start, short of ``spec.sound.follower_limit_m``; else behind every position of the AV,
    bumpers clear."""
    assert scenario.sound is not None
    tr, length = scenario.sound.tracking, scenario.sound.safety.vehicle_length_m
    if entry_s == 0.0 and scenario.lane is Lane.LEFT:
        return follower_limit_m(0.0, scenario.sound)
    return path.position(entry_s) - tr.position_m - length


def _touch_reach_m(sound: Sound) -> float:
    """How near the AV's reference at the snapshot a same-lane vehicle's start touches the AV wherever its envelope
    puts it: bumper to bumper with the AV's nearest position, short of where it can be clear ahead of one
    (``spec.sound.clear_ahead_from_m``)."""
    return clear_ahead_from_m(0.0, sound)


def _touches(scenario: Scenario, path: Path, start_m: float, av_offset_m: float, t_s: float) -> bool:
    """Whether a left-lane vehicle starting at ``start_m`` touches the AV, in the left lane too, at the snapshot: the
    AV ``av_offset_m`` off its reference when the instant judged is the snapshot's, else wherever its envelope puts
    it (``_touch_reach_m``)."""
    assert scenario.sound is not None
    if scenario.lane is not Lane.LEFT:
        return False
    if t_s == 0.0:
        return abs(start_m - (path.position(0.0) + av_offset_m)) < scenario.sound.safety.vehicle_length_m
    return abs(start_m - path.position(0.0)) < _touch_reach_m(scenario.sound)


def judge(scenario: Scenario, path: Path, car: Vehicle, chunk: _Chunk, start_m: float, speed_mps: float,
          av_offset_m: float, av_speed_offset_mps: float, t_s: float) -> tuple[Conflict, float, float] | None:
    """The specification at one instant for one concrete motion (the vehicle from ``start_m`` at a constant
    ``speed_mps``; the AV off its reference by the offsets): the conflict, the gap and the required gap, or None when
    the vehicle is in no conflict then. A vehicle behind the AV that follows no rule of followers (short of none,
    yet unable to be clear ahead of the AV at the start) is ``BEHIND``, its required gap 0 where the specification
    names no conflict: a collision then is still a breach."""
    assert scenario.sound is not None
    spec = scenario.sound.safety
    length = spec.vehicle_length_m
    x, v = path.position(t_s) + av_offset_m, path.speed(t_s) + av_speed_offset_mps
    if car.lane is Lane.RIGHT:
        if Lane.RIGHT not in chunk.lanes:
            return None
        y = start_m - speed_mps * t_s
        if y + length <= x:
            return None  # past the AV, bumpers clear
        return Conflict.ONCOMING, y - x - length, spec.required_gap_m(v + speed_mps)
    if Lane.LEFT not in chunk.lanes:
        return None
    if _touches(scenario, path, start_m, av_offset_m, t_s):
        return None  # outside the assumptions: nothing touches the AV at a snapshot
    y = start_m + speed_mps * t_s
    if chunk.entry_s is not None:
        if start_m + speed_mps * chunk.entry_s <= _follow_limit_m(scenario, path, chunk.entry_s):
            # a follower: a conflict only where it keeps its speed and the AV is slower (BEHIND)
            if rear_binds(scenario.sound.bounds, path.speed(t_s)):
                return Conflict.BEHIND, x - y - length, spec.required_gap_m(speed_mps - v)
            return None
        if chunk.entry_s == 0.0 and scenario.lane is Lane.LEFT and \
                start_m < clear_ahead_from_m(path.position(0.0), scenario.sound):
            # short of no follower, yet it cannot be clear ahead of any position of the AV at the start: behind it (a
            # lane keeps its order), held to the cut-in's gap while the AV is slower than it may be, else bumpers clear
            binds = rear_binds(scenario.sound.bounds, path.speed(t_s))
            return Conflict.BEHIND, x - y - length, spec.required_gap_m(speed_mps - v) if binds else 0.0
        return Conflict.AHEAD, y - x - length, spec.required_gap_m(v - speed_mps)
    if y >= x:
        return Conflict.AHEAD, y - x - length, spec.required_gap_m(v - speed_mps)
    return Conflict.CUT_IN, x - y - length, spec.required_gap_m(speed_mps - v)


def witness(scenario: Scenario, refusal: Refusal, dt_s: float = MAX_DT_S, path: Path | None = None) -> Witness | None:
    """The first motion of the refusal's binding vehicle within the bounds that breaks the specification in the
    refused window (``_witness``), searched over each part of the vehicle's interval whose start does not touch the
    AV at the snapshot wherever its envelope puts it (``_apart``): the assumptions allow no other."""
    path = path or plan_path(scenario, refusal)
    for part in _apart(scenario, refusal.violation.vehicle):
        found = _witness(scenario, replace(refusal, violation=replace(refusal.violation, vehicle=part)), dt_s, path)
        if found is not None:
            return found
    return None


def _apart(scenario: Scenario, car: Vehicle) -> list[Vehicle]:
    """``car``'s interval less the starts that touch the AV at the snapshot wherever it is (``_touches``): behind and
    ahead of them, each part that is left, or the whole where the AV starts in the other lane."""
    assert scenario.sound is not None
    if scenario.lane is not Lane.LEFT or car.lane is not Lane.LEFT:
        return [car]
    reach_m = _touch_reach_m(scenario.sound)  # the AV's reference is at 0 at the snapshot (``oracle.reach.Path``)
    parts = [replace(car, hi_m=min(car.hi_m, -reach_m)), replace(car, lo_m=max(car.lo_m, reach_m))]
    return [p for p in parts if p.lo_m <= p.hi_m]


def _witness(scenario: Scenario, refusal: Refusal, dt_s: float, path: Path) -> Witness | None:
    """The first motion of the refusal's binding vehicle within the bounds that breaks the specification in the
    refused window, sampled at most ``dt_s`` apart (``FAR_DT_S`` far after a plan) and at the violation's own time.

    The motions: the vehicle at a constant speed within its lane's interval, starting anywhere in its interval; at
    each instant the candidates are its nearest and farthest positions at either extreme speed, and the position
    nearest the AV that is still in conflict (at either extreme speed, and at whichever constant speed puts it
    nearest, the worst such speed); the AV at a corner of its envelope at that instant. Conflicts as ``judge``
    states them (the specification: ``spec.safety``); a vectorised screen finds the candidates, ``judge`` confirms
    each."""
    sound = scenario.sound
    if sound is None:
        raise ValueError("the scenario has no sound model")
    car = refusal.violation.vehicle
    w0, w1 = window_s(refusal, path)
    at_s = refusal.violation.time_s
    spec, tr, b = sound.safety, sound.tracking, sound.bounds
    length, ex, ev = spec.vehicle_length_m, tr.position_m, tr.speed_mps
    if refusal.violation.conflict is Conflict.BEHIND:  # a follower: its worst motion is the corner, at every instant
        for chunk in _chunks(path, scenario.lane, w0, w1):
            if Lane.LEFT in chunk.lanes and math.isfinite(car.hi_m):
                for t_s in _sample_times(chunk.t0_s, chunk.t1_s, dt_s, at_s, path):
                    found = _judged(scenario, path, car, chunk, car.hi_m, b.same_mps.high_mps, -ex, -ev, float(t_s))
                    if found is not None:
                        return found
        return None
    same = car.lane is Lane.LEFT
    low, high = (b.same_mps.low_mps, b.same_mps.high_mps) if same else (b.oncoming_mps.low_mps,
                                                                        b.oncoming_mps.high_mps)
    sign = 1.0 if same else -1.0  # a same-direction vehicle moves with the AV, an oncoming one against it
    # One column per motion: (speed: 0 low, 1 high, 2 free; AV position offset; position: 0 the nearest end, 1 the
    # farthest, 2 the nearest in conflict). The AV's speed offset is the worst for the conflict (it moves nothing).
    combos = np.array([(m, dx, k) for dx in (ex, -ex)
                       for m, k in ((0, 0), (0, 1), (0, 2), (1, 0), (1, 1), (1, 2), (2, 2))])
    mode, dx, which = (combos[:, j][None, :] for j in range(3))
    fixed = np.where(mode == 1, high, low)
    for chunk in _chunks(path, scenario.lane, w0, w1):
        if (Lane.LEFT if same else Lane.RIGHT) not in chunk.lanes:
            continue
        times = _sample_times(chunk.t0_s, chunk.t1_s, dt_s, at_s, path)
        t = times[:, None]
        x_ref, v_ref = _reference(path, times)
        x, v = x_ref[:, None] + dx, v_ref[:, None]
        with np.errstate(invalid="ignore", divide="ignore"):
            lo, hi = car.lo_m + sign * fixed * t, car.hi_m + sign * fixed * t
            reach_lo, reach_hi = (car.lo_m + low * t, car.hi_m + high * t) if same else (car.lo_m - high * t,
                                                                                         car.hi_m - low * t)
            follow_m = math.nan
            if not same:  # the nearest position not yet past
                target, free_target = x - length + NUDGE_M, x - length + NUDGE_M
            elif chunk.entry_s is not None:  # the nearest position that did not follow when the AV got into the lane
                follow_m = _follow_limit_m(scenario, path, chunk.entry_s)
                target = follow_m + fixed * (t - chunk.entry_s) + NUDGE_M
                free_target = follow_m + low * (t - chunk.entry_s) + NUDGE_M
            else:  # level with the AV: the worst of ahead and behind
                target, free_target = x, x
            near = np.clip(target, lo, hi)
            free_y = np.clip(free_target, reach_lo, reach_hi)
            # The constant speed that puts a start of the interval at free_y, the worst for the conflict it is in.
            if same:
                s_min, s_max = (free_y - car.hi_m) / t, (free_y - car.lo_m) / t
                prefer = np.where((free_y >= x) | (chunk.entry_s is not None), low, high)
            else:
                s_min, s_max = (car.lo_m - free_y) / t, (car.hi_m - free_y) / t
                prefer = np.full(free_y.shape, high)
            s_min = np.where(t > 0, np.maximum(low, np.nan_to_num(s_min, nan=low)), low)
            s_max = np.where(t > 0, np.minimum(high, np.nan_to_num(s_max, nan=high)), high)
            free_s = np.clip(prefer, s_min, s_max)
            free_start = np.clip(free_y - sign * free_s * t, car.lo_m, car.hi_m)
            s = np.where(mode == 2, free_s, fixed)
            y = np.where(which == 0, lo, np.where(which == 1, hi, near))
            y = np.where(mode == 2, free_start + sign * free_s * t, y)
            start_m = y - sign * s * t
            ok = np.isfinite(y)
            behind = np.zeros(y.shape, dtype=bool)
            if not same:
                conflict = ok & (y + length > x)
                gap, closing = y - x - length, v + ev + s
            elif chunk.entry_s is not None:
                conflict = ok & (start_m + s * chunk.entry_s > follow_m)
                gap, closing = y - x - length, v + ev - s
            else:
                behind = y < x
                conflict = ok
                gap = np.where(behind, x - y - length, y - x - length)
                closing = np.where(behind, s - v + ev, v + ev - s)
            screen = conflict & (gap < np.maximum(spec.min_gap_m, spec.time_gap_s * closing) - TOLERANCE_M)
        for i, j in np.argwhere(screen):  # row-major: the earliest instant first
            dv = -ev if behind[i, j] else ev
            shown = _judged(scenario, path, car, chunk, float(start_m[i, j]), float(s[i, j]), float(dx[0, j]), dv,
                            float(times[i]))
            if shown is not None:
                return shown
    return None


def _judged(scenario: Scenario, path: Path, car: Vehicle, chunk: _Chunk, start_m: float, speed_mps: float,
            av_offset_m: float, av_speed_offset_mps: float, t_s: float) -> Witness | None:
    """The motion as a witness if ``judge`` finds it breaking the specification (beyond ``TOLERANCE_M``)."""
    found = judge(scenario, path, car, chunk, start_m, speed_mps, av_offset_m, av_speed_offset_mps, t_s)
    if found is None or not found[1] < found[2] - TOLERANCE_M:
        return None
    return Witness(start_m, speed_mps, av_offset_m, av_speed_offset_mps, t_s, *found)


def corner_witness(scenario: Scenario, refusal: Refusal, path: Path | None = None) -> Witness | None:
    """The motion the violation names, if it breaks the specification: at the violation's time, the vehicle from the
    end of its interval that binds (the nearer for AHEAD and ONCOMING, the farther for CUT_IN) at the worst constant
    speed of its lane, the AV at the worst corner of its envelope."""
    sound, v = scenario.sound, refusal.violation
    assert sound is not None
    b, tr, car = sound.bounds, sound.tracking, v.vehicle
    speeds = b.same_mps if car.lane is Lane.LEFT else b.oncoming_mps
    start_m, speed, dx, dv = {
        Conflict.AHEAD: (car.lo_m, speeds.low_mps, tr.position_m, tr.speed_mps),
        Conflict.ONCOMING: (car.lo_m, speeds.high_mps, tr.position_m, tr.speed_mps),
        Conflict.CUT_IN: (car.hi_m, speeds.high_mps, -tr.position_m, -tr.speed_mps),
        Conflict.BEHIND: (car.hi_m, speeds.high_mps, -tr.position_m, -tr.speed_mps)}[v.conflict]
    if not math.isfinite(start_m):
        return None
    path = path or plan_path(scenario, refusal)
    w0, w1 = window_s(refusal, path)
    if not w0 <= v.time_s <= w1:
        return None
    for chunk in _chunks(path, scenario.lane, v.time_s, v.time_s):
        found = _judged(scenario, path, car, chunk, start_m, speed, dx, dv, v.time_s)
        if found is not None:
            return found
    return None


# -- rounding ---------------------------------------------------------------------------------------------------
def shifted_rules(problem: Problem, vehicle: Vehicle, by_m: float) -> SoundRules:
    """The problem's rules with one vehicle's interval moved ``by_m`` metres (positive: farther ahead)."""
    sc = problem.scenario
    assert sc.sound is not None
    moved = replace(vehicle, lo_m=vehicle.lo_m + by_m, hi_m=vehicle.hi_m + by_m)
    given = tuple(moved if v == vehicle else v for v in vehicles(sc.lane, sc.left_lane, sc.right_lane, sc.grid,
                                                                 sc.sound, sc.left_m, sc.right_m))
    return SoundRules(sc.sound, sc.lane, sc.left_lane, sc.right_lane, sc.grid, sc.target_indices, given)


def rounding_only(problem: Problem, refusal: Refusal) -> bool:
    """Whether the refusal comes from the outward rounding of a cell alone: a sensed vehicle (not a phantom), a
    shortfall of at most one cell, and the same question allowed with that vehicle one cell farther in its favour
    (ahead for AHEAD and ONCOMING, behind for CUT_IN)."""
    v, cell = refusal.violation, problem.grid.cell
    if v.vehicle.index is None or not v.required_m - v.gap_m <= cell + 1e-9:
        return False
    rules = shifted_rules(problem, v.vehicle, -cell if v.conflict in (Conflict.CUT_IN, Conflict.BEHIND) else cell)
    if refusal.where is Where.START:
        return rules.start_violation(refusal.state) is None
    if refusal.where is Where.END:
        return rules.continuation_violation(refusal.state) is None
    assert refusal.action is not None
    return rules.step_violation(refusal.state, refusal.action) is None


# -- why no motion justifies a refusal ------------------------------------------------------------------------------
class Finding(enum.Enum):
    """A diagnosis of a refusal no motion justifies (``Tightness.NEITHER``), read off the declarations."""

    NOTHING_CLOSES_IN = "a plan's end where nothing can close in after the minimal-risk manoeuvre"
    FOLLOWER_AHEAD = "a vehicle that followed the AV into the left lane is taken as ahead of it"
    OTHER = "other"


def diagnose(scenario: Scenario, refusal: Refusal, path: Path | None = None) -> Finding:
    """Why the refusal is unjustified: the plan's end is refused for a vehicle ahead though after the manoeuvre the
    AV's fastest speed is not above the slowest speed ahead (``NOTHING_CLOSES_IN``); or the binding vehicle was
    behind every position of the AV (bumpers clear, at every motion) when the AV got into the left lane, so it
    follows (``FOLLOWER_AHEAD``); else ``OTHER``. The first that applies."""
    sound, v = scenario.sound, refusal.violation
    assert sound is not None
    path = path or plan_path(scenario, refusal)
    b, tr, length = sound.bounds, sound.tracking, sound.safety.vehicle_length_m
    if refusal.where is Where.END and v.conflict is Conflict.AHEAD and path.final_lane is Lane.LEFT:
        _, end_s = window_s(refusal, path)
        if not sound.minimal_risk.closes_in(path.speed(end_s) - TOLERANCE_M, b.same_mps.low_mps):
            return Finding.NOTHING_CLOSES_IN
    if v.conflict is Conflict.AHEAD and v.vehicle.lane is Lane.LEFT:
        for chunk in _chunks(path, scenario.lane, v.time_s, v.time_s):
            if chunk.entry_s is not None and v.vehicle.hi_m + b.same_mps.high_mps * chunk.entry_s + length <= \
                    path.position(chunk.entry_s) - tr.position_m:
                return Finding.FOLLOWER_AHEAD
    return Finding.OTHER


@dataclass(frozen=True, slots=True)
class Verdict:
    """A refusal's class, the motion that exhibits it (if any) and, for one nothing justifies, the diagnosis."""

    tightness: Tightness
    witness: Witness | None = None
    corner: bool = False  # the corner motion at the violation's own time exhibits it (``corner_witness``)
    finding: Finding | None = None


def classify(problem: Problem, refusal: Refusal) -> Verdict:
    """The refusal's class: exhibited by a motion (the violation's corner motion first, then the whole window), else
    rounding only, else neither (diagnosed)."""
    sc = problem.scenario
    path = plan_path(sc, refusal)
    corner = corner_witness(sc, refusal, path)
    found = corner or witness(sc, refusal, path=path)
    if found is not None:
        return Verdict(Tightness.EXHIBITED, found, corner is not None)
    if rounding_only(problem, refusal):
        return Verdict(Tightness.ROUNDING)
    return Verdict(Tightness.NEITHER, finding=diagnose(sc, refusal, path))


# -- the commitment semantics: refused first steps, each under every escape ---------------------------------------
def escape_refusal(rules: SoundRules, first: SoundState, action: Action, escape: Escape) -> Refusal | None:
    """The sound model's first refusal of ``action`` then ``escape`` as one sequence (``oracle.commit``: each step's
    window ending where the ramp into the next starts), or None when they are proved: a step's (the state before it
    and the actions before it), or the end's (safe for ever under the minimal-risk manoeuvre)."""
    sequence = (action, *escape.actions)
    state = first
    for k, step in enumerate(sequence):
        following = sequence[k + 1] if k + 1 < len(sequence) else None
        found = rules.step_violation(state, step, following)
        if found is not None:
            return Refusal(Where.STEP, state, sequence[:k], step, found)
        state = rules.after(state, step)
    end = rules.continuation_violation(state)
    return None if end is None else Refusal(Where.END, state, sequence, None, end)


def classify_escape(problem: Problem, first: SoundState, action: Action, escape: Escape,
                    refusal: Refusal) -> Verdict:
    """One escape's refusal after ``action``, classified as ``classify`` does a plan's, on the AV's reference through
    the action, the escape and the minimal-risk manoeuvre after it (what the AV would drive): exhibited by a motion in
    the refused window, else rounding only (the binding sensed vehicle one cell farther in its favour, and the action
    and this escape are proved), else neither (diagnosed)."""
    sc = problem.scenario
    assert sc.sound is not None
    sequence = (action, *escape.actions)
    path = Path(sequence, sc.sound, sc.grid, sc.lane)
    corner = corner_witness(sc, refusal, path)
    found = corner or witness(sc, refusal, path=path)
    if found is not None:
        return Verdict(Tightness.EXHIBITED, found, corner is not None)
    v, cell = refusal.violation, problem.grid.cell
    if v.vehicle.index is not None and v.required_m - v.gap_m <= cell + 1e-9:
        shifted = shifted_rules(problem, v.vehicle, -cell if v.conflict in (Conflict.CUT_IN, Conflict.BEHIND)
                                else cell)
        if escape_refusal(shifted, first, action, escape) is None:
            return Verdict(Tightness.ROUNDING)
    return Verdict(Tightness.NEITHER, finding=diagnose(sc, refusal, path))


#: A refused step's class is its least justified escape's: exhibited only if every escape is, neither if any is.
_ORDER = (Tightness.EXHIBITED, Tightness.ROUNDING, Tightness.NEITHER)


def measure_commit(scenario: Scenario, keep: int = 3) -> Counts:
    """Under the commitment semantics (``spec.escapes``), every refusal the AV meets at this snapshot, classified:
    the start, when it already breaks the specification (``unsafe_start``); else each enabled first action the sound
    model does not commit to (``oracle.commit.committable``), justified only if every escape the commitment allows
    after it is: a motion inside the bounds that breaks the specification in that escape's refused window, or
    rounding. Later steps are decided again from later snapshots (each one a scenario of its own), so a first action
    is the whole of what one decision refuses. Also whether the answer moves and overtakes."""
    counts = Counts(scenarios=1)
    assert scenario.sound is not None
    allowed = scenario.sound.commitment or COMMIT
    seen: dict[tuple[object, ...], Verdict] = {}
    for kind in models_for(scenario.model):
        problem = problem_for(scenario, kind)
        rules, first = sound_rules(problem), start(problem)
        counts.problems += 1
        counts.states += 1
        hit = rules.start_violation(first)
        if hit is not None:
            counts.by_where[Where.START][classify(problem, Refusal(Where.START, first, (), None, hit)).tightness] += 1
            continue
        for action in Action:
            if disabled_guard(_paper(first), action, problem.rules) is not None:
                continue
            counts.enabled += 1
            escapes = allowed.allowed(lane_after(first.lane, (action,)))
            found = [(e, escape_refusal(rules, first, action, e)) for e in escapes]
            if not escapes or any(r is None for _, r in found):
                counts.committable += int(bool(escapes))
                counts.no_escape += int(not escapes)
                continue
            verdicts = []
            for escape, r in found:
                assert r is not None
                key = (action, escape, r.where, r.state.key())
                verdict = seen.get(key)
                if verdict is None:
                    verdict = seen[key] = classify_escape(problem, first, action, escape, r)
                    shown = verdict.witness
                    counts.late += int(shown is not None and not verdict.corner)
                    counts.thin += int(shown is not None and shown.required_m - shown.gap_m < 1e-3)
                    if verdict.finding is not None and len(counts.examples[verdict.finding]) < keep:
                        counts.examples[verdict.finding].append(
                            f"{scenario_name(scenario)}, {scenario.sound.bounds.name}, {kind.value} model: "
                            f"{action.value} with escape {escape.kind.value} "
                            f"({', '.join(a.value for a in escape.actions) or 'in lane'}): {r.describe()}")
                    if verdict.finding is not None:
                        counts.findings[verdict.finding][r.where] += 1
                counts.escapes[verdict.tightness] += 1
                verdicts.append(verdict.tightness)
            counts.by_where[Where.STEP][max(verdicts, key=_ORDER.index)] += 1
    _answer(scenario, counts)
    return counts


# -- the measurement ----------------------------------------------------------------------------------------------
@dataclass
class Counts:
    """One row's tallies (a cell size and a profile)."""

    by_where: dict[Where, dict[Tightness, int]] = field(
        default_factory=lambda: {w: dict.fromkeys(Tightness, 0) for w in Where})
    findings: dict[Finding, dict[Where, int]] = field(
        default_factory=lambda: {f: dict.fromkeys(Where, 0) for f in Finding})
    examples: dict[Finding, list[str]] = field(default_factory=lambda: {f: [] for f in Finding})
    with_targets: int = 0
    overtakes: int = 0  # scenarios with targets whose plan is a non-empty plan of the final (overtaking) model
    moves: int = 0  # scenarios whose plan is not empty, under either model of the pipeline
    scenarios: int = 0
    problems: int = 0
    states: int = 0
    capped: int = 0  # problems whose walk stopped at the state limit
    thin: int = 0  # exhibited refusals whose witness breaks the specification by less than a millimetre
    late: int = 0  # exhibited refusals the corner motion at the violation's own time does not exhibit
    enabled: int = 0  # commitment semantics: enabled first actions
    committable: int = 0  # commitment semantics: first actions committed to (safe, an escape proved after them)
    no_escape: int = 0  # commitment semantics: first actions into a lane the commitment allows no escape from
    escapes: dict[Tightness, int] = field(default_factory=lambda: dict.fromkeys(Tightness, 0))  # per escape tried

    def add(self, other: Counts, keep: int) -> None:
        """Add ``other``'s tallies, keeping at most ``keep`` examples per finding."""
        for w in Where:
            for k in Tightness:
                self.by_where[w][k] += other.by_where[w][k]
            for f in Finding:
                self.findings[f][w] += other.findings[f][w]
        for f in Finding:
            self.examples[f] = (self.examples[f] + other.examples[f])[:keep]
        for k in Tightness:
            self.escapes[k] += other.escapes[k]
        for name in ("with_targets", "overtakes", "moves", "scenarios", "problems", "states", "capped", "thin",
                     "late", "enabled", "committable", "no_escape"):
            setattr(self, name, getattr(self, name) + getattr(other, name))


def scenario_name(sc: Scenario) -> str:
    """A scenario as the findings print it."""
    return (f"lane={sc.lane.value} left={list(sc.left_lane)} right={list(sc.right_lane)} targets={sc.targets} "
            f"cell={float(sc.grid.cell_m):g} m")


def measure(scenario: Scenario, max_states: int = MAX_STATES, keep: int = 3) -> Counts:
    """Every refusal of one scenario (with its sound model), classified, and whether its plan moves and overtakes.

    The pipeline's problems share the scenario's rules (only guards and goals differ), so a refusal met in both
    (the same state key, the same question) is classified once and counted in each."""
    counts = Counts(scenarios=1)
    seen: dict[tuple[object, ...], Verdict] = {}
    for kind in models_for(scenario.model):
        problem = problem_for(scenario, kind)
        found, states, capped = refusals(problem, max_states)
        counts.problems += 1
        counts.states += states
        counts.capped += int(capped)
        for r in found:
            key = (r.where, r.action, r.state.key())
            verdict = seen.get(key)
            if verdict is None:
                verdict = seen[key] = classify(problem, r)
                shown = verdict.witness
                counts.late += int(shown is not None and not verdict.corner)
                counts.thin += int(shown is not None and shown.required_m - shown.gap_m < 1e-3)
                if verdict.finding is not None and len(counts.examples[verdict.finding]) < keep:
                    assert scenario.sound is not None
                    counts.examples[verdict.finding].append(
                        f"{scenario_name(scenario)}, {scenario.sound.bounds.name}, {kind.value} model: "
                        f"{r.describe()}")
            counts.by_where[r.where][verdict.tightness] += 1
            if verdict.finding is not None:
                counts.findings[verdict.finding][r.where] += 1
    _answer(scenario, counts)
    return counts


def _answer(scenario: Scenario, counts: Counts) -> None:
    """Count whether the scenario's answer (the pipeline's, shortest) moves, and whether it overtakes."""
    answer = plan(scenario, Strategy.SHORTEST)
    moved = answer.status is Status.PLAN and bool(answer.actions)
    counts.moves += int(moved)
    if scenario.targets:
        counts.with_targets += 1
        counts.overtakes += int(moved and answer.model is ModelKind.FINAL)


def _work(item: tuple[Scenario, Fraction, str, Semantics, int, int]) -> tuple[Fraction, str, Counts]:
    base, cell, name, semantics, max_states, keep = item
    grid = Grid(cell)
    scenario = base if grid == PAPER_GRID else refined(base, grid)
    if semantics is Semantics.COMMIT:
        return cell, name, measure_commit(replace(scenario, sound=Sound(profile(name), commitment=COMMIT)), keep)
    return cell, name, measure(replace(scenario, sound=Sound(profile(name))), max_states, keep)


def run(sample: Sequence[Scenario], jobs: int, max_states: int = MAX_STATES, keep: int = 3,
        semantics: Semantics = Semantics.COMMIT) -> dict[tuple[Fraction, str], Counts]:
    """The tallies per (cell, profile) over ``sample`` under ``semantics``, in ``jobs`` processes."""
    items = [(s, cell, name, semantics, max_states, keep) for cell in STANDARD_CELLS_M for name in PROFILES
             for s in sample]
    rows = {(cell, name): Counts() for cell in STANDARD_CELLS_M for name in PROFILES}
    if jobs <= 1:
        for cell, name, counts in map(_work, items):
            rows[(cell, name)].add(counts, keep)
        return rows
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        for cell, name, counts in pool.map(_work, items, chunksize=2):
            rows[(cell, name)].add(counts, keep)
    return rows


def _share(part: int, whole: int) -> str:
    return f"{part} ({part / whole:.1%})" if whole else "0"


def _split(tally: dict[Tightness, int]) -> str:
    return "/".join(str(tally[k]) for k in Tightness)


def table(rows: dict[tuple[Fraction, str], Counts]) -> Table:
    """The measured table: step refusals by class; start and end refusals as exhibited/rounding/neither; plans."""
    out = Table(title="sound model: is every refusal justified by a motion, or by rounding alone?",
                caption="refusals, exhibited, rounding, neither: refused actions; start, end: refused starts and plan "
                        "ends as exhibited/rounding/neither; overtakes: non-empty plans of the final model / scenarios "
                        "with targets; moving: non-empty plans / scenarios")
    for col in ("cell", "profile", "refusals", "exhibited", "rounding", "neither", "start", "end", "overtakes",
                "moving"):
        out.add_column(col, justify="left" if col in ("cell", "profile") else "right", no_wrap=True)
    for (cell, name), c in rows.items():
        steps = c.by_where[Where.STEP]
        total = sum(steps.values())
        out.add_row(f"{float(cell):g} m", name, str(total), _share(steps[Tightness.EXHIBITED], total),
                    _share(steps[Tightness.ROUNDING], total), str(steps[Tightness.NEITHER]),
                    _split(c.by_where[Where.START]), _split(c.by_where[Where.END]),
                    f"{c.overtakes}/{c.with_targets}", f"{c.moves}/{c.scenarios}")
    return out


def commit_table(rows: dict[tuple[Fraction, str], Counts]) -> Table:
    """The measured table under the commitment semantics: each snapshot's enabled first actions, those committed to,
    the refused ones by class (the least justified of their escapes), the escapes' own classes, unsafe starts, and
    the answers."""
    out = Table(title="sound model, commitment semantics: is every refused first step justified under every escape?",
                caption="first actions: enabled at the snapshot (both problems of the pipeline); committed: with a "
                        "proved escape; refused, by class: exhibited under every escape / rounding / neither; "
                        "escapes: each refused step's escapes as exhibited/rounding/neither; unsafe start: starts "
                        "already breaking the specification, exhibited/rounding/neither; overtakes: non-empty answers "
                        "of the final model / scenarios with targets; moving: non-empty answers / scenarios")
    for col in ("cell", "profile", "first actions", "committed", "refused", "exhibited", "rounding", "neither",
                "escapes", "unsafe start", "overtakes", "moving"):
        out.add_column(col, justify="left" if col in ("cell", "profile") else "right", no_wrap=True)
    for (cell, name), c in rows.items():
        steps = c.by_where[Where.STEP]
        total = sum(steps.values())
        out.add_row(f"{float(cell):g} m", name, str(c.enabled), str(c.committable), str(total),
                    _share(steps[Tightness.EXHIBITED], total), _share(steps[Tightness.ROUNDING], total),
                    str(steps[Tightness.NEITHER]), _split(c.escapes), _split(c.by_where[Where.START]),
                    f"{c.overtakes}/{c.with_targets}", f"{c.moves}/{c.scenarios}")
    return out


def findings_table(rows: dict[tuple[Fraction, str], Counts]) -> Table:
    """The refusals no motion justifies, by diagnosis: step, end and start refusals per row."""
    out = Table(title="'neither' by diagnosis (step/end/start)")
    out.add_column("cell")
    out.add_column("profile")
    for f in Finding:
        out.add_column(f.name.lower(), justify="right")
    for (cell, name), c in rows.items():
        out.add_row(f"{float(cell):g} m", name, *("/".join(str(c.findings[f][w]) for w in (Where.STEP, Where.END,
                                                                                             Where.START))
                                                  for f in Finding))
    return out


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--count", type=int, default=SAMPLE, help="scenarios drawn from the sweep (0: all of it)")
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--space", default=DEFAULT_SPACE)
    parser.add_argument("--jobs", type=int, default=min(2, os.cpu_count() or 1))
    parser.add_argument("--max-states", type=int, default=MAX_STATES, help="states walked per problem at most")
    parser.add_argument("--show", type=int, default=3, help="examples printed per diagnosis of 'neither'")
    parser.add_argument("--semantics", type=Semantics, choices=list(Semantics), default=Semantics.COMMIT,
                        metavar="{" + ",".join(m.value for m in Semantics) + "}",
                        help="commit (the default): each snapshot's refused first steps, under every escape; whole: "
                             "every refusal of the whole-plan model, over every state within the horizon")
    args = parser.parse_args(argv)
    console = Console(width=150 if args.semantics is Semantics.COMMIT else 120)
    everything = list(parse_space(args.space, PAPER_GRID).scenarios(PAPER_GRID, None))
    n = len(everything) if args.count <= 0 else min(args.count, len(everything))
    sample = everything if n == len(everything) else random.Random(args.seed).sample(everything, n)
    console.print(f"seed {args.seed}; {len(sample)} of the {len(everything)} scenarios of {args.space}; the same "
                  f"traffic at {', '.join(f'{float(c):g}' for c in STANDARD_CELLS_M)} m; profiles "
                  f"{', '.join(PROFILES)}; every problem of the pipeline; {args.semantics.value} semantics; "
                  f"{args.jobs} process(es); {machine()}")
    started = time.perf_counter()
    rows = run(sample, args.jobs, args.max_states, args.show, args.semantics)
    total = Counts()
    for c in rows.values():
        total.add(c, args.show)
    if args.semantics is Semantics.COMMIT:
        console.print(commit_table(rows))
        none = f", {total.no_escape} first actions with no escape allowed" if total.no_escape else ""
        walked = f"{total.problems} problems{none}"
    else:
        console.print(table(rows))
        walked = (f"{total.problems} problems, {total.states:,} states walked, {total.capped} stopped at "
                  f"{args.max_states:,} states")
    console.print(f"{walked}; exhibited: {total.late:,} only off the violation's own corner motion, {total.thin} by "
                  f"less than 1 mm; {time.perf_counter() - started:.0f} s")
    if any(total.findings[f][w] for f in Finding for w in Where):
        console.print(findings_table(rows))
        for f in Finding:
            for line in total.examples[f]:
                console.print(f"{f.name.lower()}: {line}", soft_wrap=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
