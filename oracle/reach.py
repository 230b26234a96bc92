"""Soundness against continuous motion: the sound model's plans checked by sampling time, not by its own algebra.

Two checks, both pure kinematics (no PyBullet), both built from the declarations alone (the bounds,
the safety specification, the AV's envelope, the discretiser, the executor's speed ramps) and
never from ``spec.sound``'s thresholds:

- ``exact_check``: every vehicle's reachable interval (its start interval, widened by its speed
  interval times the time) against the AV's envelope, at samples at most ``MAX_DT_S`` apart, each
  vehicle's margin between two samples bounded below by how fast it can change there (the larger of
  the two speeds, plus the time gap times how fast the closing speed can change), the interval cut
  in two while that bound is unsure;
- ``sampled_motions``: motions that keep to the bounds: each vehicle's true start anywhere the
  discretiser would have put into its cell, its reading off by at most the sensing error, its
  speed anywhere in its interval and changing at random instants; the AV off its reference by at
  most the tracking error and moving sideways for the whole stated time; with the corner motions
  always included (constant extremes, readings at the ends of the error, one switch).

A violation names the conflict, the vehicle, the time and the gaps. Under the same bounds both
checks find violations in plans of the paper's rules: they bite.
"""

from __future__ import annotations

import functools
import math
import random
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from spec.actions import ACTION_RULES, Action
from spec.assumptions import Bounds
from spec.cells import left_cell, oncoming_cell, oncoming_extent_m
from spec.dynamics import Dynamics, Phase
from spec.grid import Grid
from spec.lanes import Lane
from spec.models import GoalRule
from spec.motion import Ramp, action_speed_mps, ramp_s
from spec.physical import LOOP
from spec.safety import Conflict, SafetySpec
from spec.scenario import Scenario
from spec.sound import (
    Sound,
    Vehicle,
    follower_limit_m,
    held_vehicle,
    held_windows_s,
    measured_dynamics,
    reach_m,
    slowest_ahead_mps,
    top_mps,
    vehicles,
)

#: The longest step between two samples of the exact check (the issue's 10 ms).
MAX_DT_S = 0.01
#: The step of a sampled motion: the executor's control step (the simulator moves the AV no more often).
MOTION_DT_S = LOOP.physics_dt_s * LOOP.control_every_steps
#: How long after a plan the minimal-risk manoeuvre is followed in the left lane (it reaches its hold speed well within
#: this, and nothing closes in on it after); in the right lane it is followed until the farthest oncoming vehicle could
#: have reached the AV at its fastest (``Path.continuation_s``): the manoeuvre stays in that lane for ever.
CONTINUATION_S = 10.0
#: The corner motions' phantom starts: at the edge, and this many steps into the unseen stretch up to the farthest
#: a vehicle there can still meet the AV from (``motions``).
HIDDEN_STEPS = 8


@dataclass(frozen=True, slots=True)
class Breach:
    """A motion within the bounds that breaks the specification (or a goal field) of a plan."""

    conflict: Conflict | None  # None: a goal field, not a conflict
    vehicle: str
    time_s: float
    gap_m: float
    required_m: float
    motion: str  # which motion: "exact", "corner: ...", "sampled #k"

    def describe(self) -> str:
        what = self.conflict.value if self.conflict else "goal"
        return (f"{self.motion}: {what} with {self.vehicle} at t = {self.time_s:.2f} s: gap {self.gap_m:.2f} m, "
                f"required {self.required_m:.2f} m")


class Path:
    """The AV's reference through a plan and the minimal-risk manoeuvre after it: speed, position, lanes."""

    def __init__(self, actions: Sequence[Action], sound: Sound, grid: Grid, lane: Lane,
                 oncoming_far_m: float = 0.0, hold_floor_mps: float | None = None) -> None:
        """``oncoming_far_m``: where the farthest oncoming vehicle may start (a phantom's edge included), for how long
        a path that ends in the right lane is followed; ``hold_floor_mps``: the slowest a vehicle ahead may come to
        drive (``spec.sound.slowest_ahead_mps``; None: its lane's slowest), what the manoeuvre brakes to."""
        floor = sound.bounds.same_mps.low_mps if hold_floor_mps is None else hold_floor_mps
        self.sound, self.grid = sound, grid
        start_mps = grid.speed if sound.start_mps is None else sound.start_mps
        speeds = [action_speed_mps(a, grid) for a in actions]
        self.bounds_s, t = [0.0], 0.0
        for a in actions:
            t += float(ACTION_RULES[a].duration_s)
            self.bounds_s.append(t)
        self.end_s = t
        ramps = []
        first = speeds[0] if speeds else start_mps
        if first != start_mps:
            ramps.append(Ramp(0.0, ramp_s(start_mps, first), first - start_mps))
        for k in range(1, len(speeds)):
            if speeds[k] != speeds[k - 1]:
                r = ramp_s(speeds[k - 1], speeds[k])
                ramps.append(Ramp(self.bounds_s[k] - r / 2, r, speeds[k] - speeds[k - 1]))
        last = speeds[-1] if speeds else start_mps
        hold = sound.minimal_risk.hold_mps(last, floor)
        brake = sound.minimal_risk.ramp(t, last, hold)  # the manoeuvre as spec.envelope declares it
        if brake is not None:
            ramps.append(brake)
        self.start_mps, self.ramps = start_mps, tuple(ramps)
        self.lanes: list[tuple[float, float, frozenset[Lane], bool]] = []  # (from, to, lanes, entering the left)
        current = lane
        for k, a in enumerate(actions):
            rule = ACTION_RULES[a]
            t0, t1 = self.bounds_s[k], self.bounds_s[k + 1]
            if rule.to_lane is None:
                self.lanes.append((t0, t1, frozenset({current}), False))
                continue
            move = t0 + min(sound.tracking.lateral_s, t1 - t0)
            self.lanes.append((t0, move, frozenset(Lane), rule.to_lane is Lane.LEFT))
            self.lanes.append((move, t1, frozenset({rule.to_lane}), False))
            current = rule.to_lane
        if sound.sideways_s > 0:
            self.lanes = _under_way(self.lanes, sound.sideways_s, lane)
        self.final_lane = current
        self.continuation_s = CONTINUATION_S
        if current is Lane.RIGHT:
            closing = sound.bounds.oncoming_mps.high_mps + hold
            # an oncoming vehicle that starts behind the AV (already past) adds no time: it cannot reach it
            self.continuation_s += max(0.0, oncoming_far_m) / closing if closing > 0 else 0.0
        #: The most the reference ever accelerates or brakes: ramps under way together add up (a measured start speed's
        #: ramp may still run when the ramp into the second action starts), so for each ramp, all that overlap it.
        spans = [(r.start_s, r.start_s + r.duration_s, abs(r.dv_mps) / r.duration_s) for r in self.ramps
                 if r.duration_s > 0]
        self.max_accel = max((sum(a for s0, s1, a in spans if s0 < end and s1 > start) for start, end, _ in spans),
                             default=0.0)
        #: The fastest the reference ever goes: ramps only move it between the speeds they join, so one of those.
        self.max_speed = max([start_mps, *speeds])

    def speed(self, t_s: float) -> float:
        return self.start_mps + sum(r.at(t_s) for r in self.ramps)

    def rates(self, t0_s: float, t1_s: float) -> tuple[float, float]:
        """The fastest the reference goes over ``[t0_s, t1_s]`` (its speed is linear between the ramps' ends) and the
        most it accelerates or brakes there (the ramps under way then, together)."""
        ends = [t for r in self.ramps for t in (r.start_s, r.start_s + r.duration_s) if t0_s < t < t1_s]
        fastest = max(self.speed(t) for t in (t0_s, t1_s, *ends))
        accel = sum(abs(r.dv_mps) / r.duration_s for r in self.ramps
                    if r.duration_s > 0 and r.start_s < t1_s and r.start_s + r.duration_s > t0_s)
        return fastest, accel

    def position(self, t_s: float) -> float:
        return self.start_mps * t_s + sum(r.integral_m(t_s) - r.integral_m(0.0) for r in self.ramps)

    def occupancy(self, t_s: float) -> tuple[frozenset[Lane], bool]:
        """The lanes the AV is in at ``t_s`` and whether it is moving into the left one (after the plan: its lane)."""
        for t0, t1, lanes, entering in self.lanes:
            if t0 <= t_s <= t1:
                return lanes, entering
        return frozenset({self.final_lane}), False

    def times(self, dt_s: float) -> list[float]:
        """Samples at most ``dt_s`` apart over the plan and the continuation, every boundary among them: the actions',
        the lanes', and the ends of every ramp, so that between two samples the reference speed is monotone (a
        follower's conflict, which holds while the reference is slower than it may be, then holds at one end of any
        interval it holds in)."""
        horizon = self.end_s + self.continuation_s
        n = max(1, math.ceil(horizon / dt_s))
        out = {horizon * k / n for k in range(n + 1)}
        out.update(self.bounds_s)
        for t0, t1, _, _ in self.lanes:
            out.update((t0, t1))
        out.update(t for r in self.ramps for t in (r.start_s, r.start_s + r.duration_s) if 0.0 <= t <= horizon)
        return sorted(out)


def _under_way(lanes: list[tuple[float, float, frozenset[Lane], bool]], move_s: float, lane: Lane) -> list[
        tuple[float, float, frozenset[Lane], bool]]:
    """The AV's lanes with a sideways move under way at the start into ``lane`` for ``move_s``: in both lanes until
    then (moving into the left one when that is ``lane``), however short the plan."""
    out = []
    for t0, t1, occupied, entering in lanes:
        if t0 < move_s:
            out.append((t0, min(t1, move_s), frozenset(Lane), entering or lane is Lane.LEFT))
        if t1 > move_s:
            out.append((max(t0, move_s), t1, occupied, entering))
    reached = out[-1][1] if out else 0.0
    if reached < move_s:
        out.append((reached, move_s, frozenset(Lane), lane is Lane.LEFT))
    return out


def _gap_breach(sound: Sound, motion: str, conflict: Conflict, name: str, t_s: float, gap_m: float,
                closing_mps: float) -> Breach | None:
    """The breach of one motion at one instant, if its gap to one vehicle is below the specification's."""
    required = sound.safety.required_gap_m(closing_mps)
    return Breach(conflict, name, t_s, gap_m, required, motion) if gap_m < required else None


#: A gap this close to the required one (metres) is taken as meeting it: the model's own slack is far smaller.
TOLERANCE_M = 1e-6


def exact_check(scenario: Scenario, actions: Sequence[Action], dt_s: float = MAX_DT_S) -> Breach | None:
    """The first instant at which some motion within the bounds breaks the specification, or None.

    Conflicts as the specification states them: a same-direction vehicle ahead in the left lane while the AV
    occupies it (one behind since the AV entered, or started, follows it: where followers keep their speed, it is
    held to the cut-in's gap while the reference is slower than it may be); an oncoming vehicle not yet past while
    the AV occupies the right lane; while the AV moves into the left lane, every same-direction vehicle certainly
    ahead, or certainly behind with the cut-in gap. Between two samples the margin (gap less required gap) changes
    at most at the largest relative speed plus the time gap times the largest accelerations, and each vehicle's at
    its own rate there (``Path.rates``' bounds on the AV, the vehicle's speed bounds: ``_rate``): an interval where
    some vehicle's samples leave less margin than that could lose is cut in two, down to a microsecond.

    Every sample's margins are computed at once (``_Sweep``); the instants and intervals the sweep cannot clear by far
    more than rounding are decided one at a time (``_Walk``), so an answer and its breach are the walk's."""
    walk = _Walk(scenario, actions)
    times = walk.path.times(dt_s)
    swept = _Sweep(walk, np.asarray(times))

    @functools.cache
    def at(k: int) -> tuple[float, Breach | None, list[float]]:
        """The walk at sample ``k`` (an unsure instant is often the end of an unsure interval too)."""
        return walk.worst(times[k], *walk.path.occupancy(times[k]), swept.behind(k))

    # every instant and interval the sweep cannot clear, in order (an instant before the interval that ends there)
    for k, is_instant in swept.unsure(walk.rate):
        if is_instant:
            margin, found, _ = at(k)
            if margin < -TOLERANCE_M:
                return found
            continue
        t0, t1 = times[k - 1], times[k]
        found = walk.interval_ok(t0, t1, at(k - 1)[2], at(k)[2], *walk.path.occupancy((t0 + t1) / 2),
                                 swept.behind(k))
        if found is not None:
            return found
    return None


class _Walk:
    """``exact_check`` one instant, or one interval, at a time: the reference the vectorised sweep (``_Sweep``) is
    held to, and what decides every instant and interval the sweep cannot clear."""

    def __init__(self, scenario: Scenario, actions: Sequence[Action]) -> None:
        self.sound = sound = _sound(scenario)
        self.path = scenario_path(scenario, actions)
        self.windows = held_windows_s(sound, scenario.lane, actions)
        self.cars = vehicles(scenario.lane, scenario.left_lane, scenario.right_lane, scenario.grid, sound,
                             scenario.left_m, scenario.right_m, scenario.left_mps, scenario.right_mps)
        b = sound.bounds
        measured = [c.dynamics for c in self.cars if c.dynamics is not None]
        fastest_vehicle = max([b.same_mps.high_mps, b.oncoming_mps.high_mps] + [d.highest_mps for d in measured])
        vehicle_accel = max([0.0] + [max(d.change.accel_mps2, d.change.brake_mps2) for d in measured])
        #: the fastest any margin changes anywhere in the plan
        self.rate = self.path.max_speed + fastest_vehicle + sound.safety.time_gap_s * (self.path.max_accel
                                                                                      + vehicle_accel)
        #: at the start in the left lane (or moving sideways: partly in it), one short of
        #: ``spec.sound.follower_limit_m`` follows
        in_left = scenario.lane is Lane.LEFT or sound.sideways_s > 0
        self.first = {i for i, c in enumerate(self.cars) if in_left and c.lane is Lane.LEFT
                      and c.hi_m <= follower_limit_m(0.0, sound) - TOLERANCE_M}

    def speeds(self, c: Vehicle, t: float) -> tuple[float, float]:
        if c.dynamics is not None:
            return c.dynamics.speeds_mps(t)
        sp = self.sound.bounds.same_mps if c.lane is Lane.LEFT else self.sound.bounds.oncoming_mps
        return sp.low_mps, sp.high_mps

    def worst(self, t: float, lanes: frozenset[Lane], entering: bool, behind: set[int]) -> tuple[
            float, Breach | None, list[float]]:
        """The least margin over the conflicts at ``t``, the breach it would be, and each vehicle's margin (infinite:
        in no conflict)."""
        sound, path, speeds = self.sound, self.path, self.speeds
        tr, b, length = sound.tracking, sound.bounds, sound.safety.vehicle_length_m
        x, v = path.position(t), path.speed(t)
        least: tuple[float, Breach | None] = (math.inf, None)
        each = [math.inf] * len(self.cars)
        for i, c in enumerate(self.cars):
            options = []
            low, high = reach_m(c, b, t)
            slow, fast = speeds(c, t)
            rear = not b.followers_react and v < top_mps(b, c) - TOLERANCE_M  # a follower closing in: BEHIND
            if rear and c.lane is Lane.LEFT and Lane.LEFT in lanes and i in behind:
                options.append((Conflict.BEHIND, (x - tr.position_m) - high - length, fast - v + tr.speed_mps))
            if c.lane is Lane.LEFT and Lane.LEFT in lanes and i not in behind:
                options.append((Conflict.AHEAD, low - (x + tr.position_m) - length, v + tr.speed_mps - slow))
                if entering:
                    held = held_vehicle(c, self.windows, t)
                    cut_high, cut_fast = reach_m(held, b, t)[1], speeds(held, t)[1]
                    options.append((Conflict.CUT_IN, (x - tr.position_m) - cut_high - length,
                                    cut_fast - v + tr.speed_mps))
            if c.lane is Lane.RIGHT and Lane.RIGHT in lanes and high + length > x - tr.position_m:
                options.append((Conflict.ONCOMING, low - (x + tr.position_m) - length, v + tr.speed_mps + fast))
            if not options:
                continue
            margins = [(gap - sound.safety.required_gap_m(closing), conflict, gap, closing)
                       for conflict, gap, closing in options]
            best = max(margins, key=lambda m: m[0])  # one safe way out (ahead, or behind) is enough
            each[i] = best[0]
            if best[0] < least[0]:
                required = sound.safety.required_gap_m(best[3])
                least = (best[0], Breach(best[1], c.name, t, best[2], required, "exact"))
        return least[0], least[1], each

    def interval_ok(self, t0: float, t1: float, m0: list[float], m1: list[float], lanes: frozenset[Lane],
                    entering: bool, behind: set[int]) -> Breach | None:
        """Whether every vehicle's margin stays non-negative over ``[t0, t1]`` (each bounded below from its samples
        and its rate there), cutting the interval while a bound is unsure."""
        span = t1 - t0
        if span < 1e-6 or _least_between(min(m0, default=math.inf), min(m1, default=math.inf), span * self.rate) \
                >= -TOLERANCE_M:  # every margin, at the fastest any changes anywhere
            return None
        v_max_mps, a_max_mps2 = self.path.rates(t0, t1)
        if all(_least_between(a, z, span * _rate(self.sound, c, i in behind, lanes, entering, self.speeds(c, t0),
                                                 self.speeds(c, t1), v_max_mps, a_max_mps2))
               >= -TOLERANCE_M for i, (c, a, z) in enumerate(zip(self.cars, m0, m1, strict=True))):
            return None
        mid = (t0 + t1) / 2
        m_mid, found, each = self.worst(mid, lanes, entering, behind)
        if m_mid < -TOLERANCE_M:
            return found
        return self.interval_ok(t0, mid, m0, each, lanes, entering, behind) or \
            self.interval_ok(mid, t1, each, m1, lanes, entering, behind)


#: How far above the tolerance a margin the sweep computed must be to be cleared without the scalar walk: far more
#: than the two computations' rounding can differ by (the same operations in the same order, on array elements).
CLEAR_M = 1e-9


class _Sweep:
    """``exact_check``'s samples all at once: at each instant the AV's reference, its occupancy, which vehicles follow
    it, and each vehicle's margin over the conflicts it is in, as ``exact_check``'s ``worst`` takes them one instant at
    a time (each expression the same, in the same order). ``unsure`` names the instants and intervals it cannot clear;
    the scalar walk decides those, so an answer and its breach are the walk's own."""

    def __init__(self, walk: _Walk, t: np.ndarray) -> None:
        sound, path, cars, windows, first = walk.sound, walk.path, walk.cars, walk.windows, walk.first
        tr, b, length, safety = sound.tracking, sound.bounds, sound.safety.vehicle_length_m, sound.safety
        self.t = t
        x, v = _positions(path, t), _speeds(path, t)
        has_left, has_right, entering = _occupancies(path, t)
        in_lane = has_left & ~entering
        # the last instant at or before each where the AV was out of the left lane or moving into it: followers reset
        index = np.arange(len(t))
        last_reset = np.maximum.accumulate(np.where(in_lane, -1, index))
        self.follows = np.zeros((len(cars), len(t)), dtype=bool)
        self.margins = np.full((len(cars), len(t)), math.inf)
        for i, c in enumerate(cars):
            low, high, slow, fast = unheld = _reach(c, b, t)
            held = _held(c, b, t, windows, unheld)
            if c.lane is Lane.LEFT:
                joins = in_lane & (held[1] + length <= x - tr.position_m)
                count = np.cumsum(joins)
                before = np.where(last_reset >= 0, count[np.maximum(last_reset, 0)], 0)
                self.follows[i] = in_lane & ((count - before > 0) | ((last_reset < 0) & (i in first)))
            follows = self.follows[i]
            options: list[tuple[np.ndarray, np.ndarray]] = []  # (where the conflict applies, its margin there)
            if c.lane is Lane.LEFT:
                if not b.followers_react:
                    rear = v < top_mps(b, c) - TOLERANCE_M
                    options.append((rear & has_left & follows,
                                    _margin(safety, (x - tr.position_m) - high - length, fast - v + tr.speed_mps)))
                ahead = has_left & ~follows
                options.append((ahead, _margin(safety, low - (x + tr.position_m) - length, v + tr.speed_mps - slow)))
                options.append((ahead & entering,
                                _margin(safety, (x - tr.position_m) - held[1] - length, held[3] - v + tr.speed_mps)))
            else:
                options.append((has_right & (high + length > x - tr.position_m),
                                _margin(safety, low - (x + tr.position_m) - length, v + tr.speed_mps + fast)))
            best = np.full(len(t), -math.inf)
            any_option = np.zeros(len(t), dtype=bool)
            for applies, margin in options:
                best = np.where(applies, np.maximum(best, margin), best)
                any_option |= applies
            self.margins[i] = np.where(any_option, best, math.inf)

    def behind(self, k: int) -> set[int]:
        """The vehicles that follow the AV at sample ``k``."""
        return {int(i) for i in np.flatnonzero(self.follows[:, k])}

    def unsure(self, rate: float) -> list[tuple[int, bool]]:
        """The samples whose least margin, and the intervals (named by their later sample) whose bound at ``rate``
        over every vehicle's margin, come within ``CLEAR_M`` of breaking the tolerance; in the walk's order."""
        least = self.margins.min(axis=0) if len(self.margins) else np.full(len(self.t), math.inf)
        instants = least < -TOLERANCE_M + CLEAR_M
        m0, m1 = least[:-1], least[1:]
        span = np.diff(self.t)
        reach = span * rate
        with np.errstate(invalid="ignore"):  # inf - inf where neither end is in a conflict: no bound needed
            bound = np.where(np.isinf(m0) | np.isinf(m1), np.minimum(m0, m1) - reach, (m0 + m1) / 2 - reach / 2)
        bound = np.where(np.isinf(m0) & np.isinf(m1), math.inf, bound)
        intervals = np.concatenate(([False], (span >= 1e-6) & (bound < -TOLERANCE_M + CLEAR_M)))
        return [(int(k), kind) for k in np.flatnonzero(instants | intervals)
                for kind in (True, False) if (instants[k] if kind else intervals[k])]


def _margin(safety: SafetySpec, gap_m: np.ndarray, closing_mps: np.ndarray) -> np.ndarray:
    return gap_m - np.maximum(safety.min_gap_m, safety.time_gap_s * closing_mps)


def _ramp_at(r: Ramp, t: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore"):
        inside = r.dv_mps * (t - r.start_s) / r.duration_s
    return np.where(t <= r.start_s, 0.0, np.where(t >= r.start_s + r.duration_s, r.dv_mps, inside))


def _ramp_integral(r: Ramp, t: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore"):
        inside = r.dv_mps * (t - r.start_s) ** 2 / (2 * r.duration_s)
    after = r.dv_mps * (t - r.start_s - r.duration_s / 2)
    return np.where(t <= r.start_s, 0.0, np.where(t >= r.start_s + r.duration_s, after, inside))


def _speeds(path: Path, t: np.ndarray) -> np.ndarray:
    """``Path.speed`` at every sample."""
    total = np.zeros(len(t))
    for r in path.ramps:
        total = total + _ramp_at(r, t)
    return path.start_mps + total


def _positions(path: Path, t: np.ndarray) -> np.ndarray:
    """``Path.position`` at every sample."""
    total = np.zeros(len(t))
    for r in path.ramps:
        total = total + (_ramp_integral(r, t) - r.integral_m(0.0))
    return path.start_mps * t + total


def _occupancies(path: Path, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``Path.occupancy`` at every sample: whether the AV is in the left lane, in the right one, moving into the left
    one (the first of the path's stretches that holds an instant, as ``occupancy`` takes it)."""
    left = np.full(len(t), Lane.LEFT is path.final_lane)
    right = np.full(len(t), Lane.RIGHT is path.final_lane)
    entering = np.zeros(len(t), dtype=bool)
    for t0, t1, lanes, moving in reversed(path.lanes):
        here = (t >= t0) & (t <= t1)
        left, right = np.where(here, Lane.LEFT in lanes, left), np.where(here, Lane.RIGHT in lanes, right)
        entering = np.where(here, moving, entering)
    return left, right, entering


def _phases_at(phases: tuple[Phase, ...], t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The travel and the speed of a bound made of ``phases`` at every sample (``Phase.travel``, ``Phase.speed``)."""
    travel, speed = np.zeros(len(t)), np.zeros(len(t))
    taken = np.zeros(len(t), dtype=bool)
    for k, p in enumerate(phases):
        here = ~taken & ((t < p.t1_s) | (k == len(phases) - 1))
        s = t - p.t0_s
        travel = np.where(here, p.travel_m + p.speed_mps * s + p.accel_mps2 * s * s / 2, travel)
        speed = np.where(here, p.speed_mps + p.accel_mps2 * s, speed)
        taken |= here
    return travel, speed


def _reach(c: Vehicle, bounds: Bounds, t: np.ndarray, dynamics: Dynamics | None = None) -> tuple[
        np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``reach_m`` and ``exact_check``'s speed bounds of ``c`` (with ``dynamics`` for its own) at every sample: its
    lowest and highest position, its lowest and highest speed."""
    d = c.dynamics if dynamics is None else dynamics
    if d is not None:
        least, slow = _phases_at(d.slowest, t)
        most, fast = _phases_at(d.fastest, t)
        if c.lane is Lane.LEFT:
            return c.lo_m + least, c.hi_m + most, slow, fast
        return c.lo_m - most, c.hi_m - least, slow, fast
    if c.lane is Lane.LEFT:
        same = bounds.same_mps
        return (c.lo_m + same.low_mps * t, c.hi_m + same.high_mps * t, np.full(len(t), same.low_mps),
                np.full(len(t), same.high_mps))
    onc = bounds.oncoming_mps
    return (c.lo_m - onc.high_mps * t, c.hi_m - onc.low_mps * t, np.full(len(t), onc.low_mps),
            np.full(len(t), onc.high_mps))


def _held(c: Vehicle, bounds: Bounds, t: np.ndarray, windows: tuple[tuple[float, float], ...],
          unheld: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]) -> tuple[
        np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``_reach`` of ``held_vehicle(c, windows, t)`` at every sample, from ``c``'s own (``unheld``): within a window
    (the first that holds it) a measured same-direction vehicle does not speed up from the window's start."""
    low, high, slow, fast = unheld
    if c.dynamics is None or c.lane is not Lane.LEFT:
        return low, high, slow, fast
    for t0, t1 in reversed(windows):
        here = (t >= t0) & (t <= t1)
        if here.any():
            h_low, h_high, h_slow, h_fast = _reach(c, bounds, t, c.dynamics.held_from(t0))
            low, high = np.where(here, h_low, low), np.where(here, h_high, high)
            slow, fast = np.where(here, h_slow, slow), np.where(here, h_fast, fast)
    return low, high, slow, fast


def _least_between(m0: float, m1: float, reach_m: float) -> float:
    """The least a margin can be between two samples ``m0`` and ``m1`` when it changes by at most ``reach_m`` over
    the interval (infinite at an end: in no conflict there; the other end's less the whole reach)."""
    if m0 == math.inf and m1 == math.inf:
        return math.inf
    if m0 == math.inf or m1 == math.inf:
        return min(m0, m1) - reach_m
    return (m0 + m1) / 2 - reach_m / 2


def _rate(sound: Sound, c: Vehicle, follows: bool, lanes: frozenset[Lane], entering: bool,
          speeds0: tuple[float, float], speeds1: tuple[float, float], v_max_mps: float, a_max_mps2: float) -> float:
    """The most ``c``'s margin changes per second over an interval of one occupancy (``lanes``, ``entering``), from
    its speed bounds at the interval's ends (each monotone: the lowest never rises, the highest never falls) and the
    AV's fastest speed and largest acceleration there. A gap changes at the difference of two speeds, at most the
    larger (both at least 0; an oncoming vehicle's, their sum); the required gap at the time gap times how fast the
    closing speed changes (the AV's acceleration and the vehicle's speed bound's). Only the conflicts ``c`` can be in
    count: ahead (and cut in while entering) or, following where followers keep their speed, behind; oncoming."""
    tau = sound.safety.time_gap_s
    change = c.dynamics.change if c.dynamics is not None else None
    slow_hi, fast_hi = max(speeds0[0], speeds1[0]), max(speeds0[1], speeds1[1])
    slow_rate = 0.0 if change is None or speeds0[0] == speeds1[0] else change.brake_mps2
    fast_rate = 0.0 if change is None or speeds0[1] == speeds1[1] else change.accel_mps2
    ahead = max(v_max_mps, slow_hi) + tau * (a_max_mps2 + slow_rate)
    behind = max(v_max_mps, fast_hi) + tau * (a_max_mps2 + fast_rate)
    if c.lane is Lane.LEFT and Lane.LEFT in lanes:
        if follows:
            return 0.0 if sound.bounds.followers_react else behind
        return max(ahead, behind) if entering else ahead
    if c.lane is Lane.RIGHT and Lane.RIGHT in lanes:
        return v_max_mps + fast_hi + tau * (a_max_mps2 + fast_rate)
    return 0.0


def scenario_path(scenario: Scenario, actions: Sequence[Action]) -> Path:
    """The AV's reference through ``actions`` from ``scenario``'s start, followed after them as long as an oncoming
    vehicle of the scenario (its cell's far end, or a phantom's edge) could still reach it."""
    far = max([oncoming_extent_m(c, scenario.grid)[1] for c in scenario.right_lane]
              + [hi for _, hi in scenario.right_m or ()]
              + [p.dx_m for p in _sound(scenario).phantoms() if p.lane is Lane.RIGHT], default=0.0)
    return Path(actions, _sound(scenario), scenario.grid, scenario.lane, far,
                slowest_ahead_mps(_sound(scenario), _drivers(scenario)))


def _sound(scenario: Scenario) -> Sound:
    if scenario.sound is None:
        raise ValueError("the scenario has no sound model to check against")
    return scenario.sound


@dataclass(frozen=True, slots=True)
class Motion:
    """One motion within the bounds: each vehicle's true start and speed schedule, the AV's deviation schedule."""

    name: str
    starts_m: tuple[float, ...]  # true start of each vehicle, metres ahead of the AV (phantoms: their edge or beyond)
    #: per vehicle: (from time, speed) steps, first from 0; for a vehicle with its own dynamics (``Vehicle.dynamics``)
    #: the speed it heads for from then, at most at its acceleration bounds, from its ``start_mps``
    speeds: tuple[tuple[tuple[float, float], ...], ...]
    av_offset: tuple[tuple[float, float], ...]  # (from time, deviation rate m/s); the deviation stays within e_x
    start_mps: tuple[float | None, ...] = ()  # per vehicle: its speed at the start when it has its own dynamics


def _drivers(scenario: Scenario) -> tuple[Vehicle, ...]:
    """The vehicles a motion drives, from the declarations alone (not ``spec.sound.vehicles``, whose extents and
    phantoms are what the motions check): the scenario's vehicles (their starts are drawn through the discretiser)
    and a vehicle for each phantom as the snapshot declares them (``motions`` starts it at the edge or beyond)."""
    sound = _sound(scenario)

    def own(lane: Lane, i: int) -> Dynamics | None:
        measured = scenario.left_mps if lane is Lane.LEFT else scenario.right_mps
        return None if measured is None else measured_dynamics(sound, lane, measured[i]).aged(sound.bounds.latency_s)

    cars = [Vehicle(Lane.LEFT, i, math.nan, math.nan, f"left_lane[{i}] (cell {c})", own(Lane.LEFT, i))
            for i, c in enumerate(scenario.left_lane)]
    cars += [Vehicle(Lane.RIGHT, i, math.nan, math.nan, f"right_lane[{i}] (cell {c})", own(Lane.RIGHT, i))
             for i, c in enumerate(scenario.right_lane)]
    cars += [Vehicle(p.lane, None, p.dx_m, p.dx_m, f"phantom ({p.why}, {p.dx_m:+g} m)")
             for p in _sound(scenario).phantoms()]
    return tuple(cars)


def _sensed_start(rng: random.Random, cell: int, lane: Lane, av_lane: Lane, grid: Grid) -> float:
    """A reading the discretiser puts into ``cell`` (by its own rule, not by the cell's extent), drawn uniformly."""
    width = grid.cell
    offset = (cell - grid.av_cell) * width
    for _ in range(1000):
        dx = offset + rng.uniform(-1.5, 1.5) * width
        got = left_cell(dx, av_lane, grid) if lane is Lane.LEFT else oncoming_cell(dx, grid)
        if got == cell:
            return dx
    raise ValueError(f"no reading falls into cell {cell}")


def motions(scenario: Scenario, actions: Sequence[Action], rng: random.Random, count: int) -> list[Motion]:
    """The corner motions (the phantoms' vehicles at their edges, then into their stretches), then ``count`` random
    ones, all within the scenario's bounds."""
    sound = _sound(scenario)
    cars = _drivers(scenario)
    path = scenario_path(scenario, actions)
    end_s = path.end_s + path.continuation_s
    b = sound.bounds
    ev = sound.tracking.speed_mps

    def interval(c: Vehicle) -> tuple[float, float]:
        """The speeds a vehicle drives (its lane's), or heads for (its own dynamics: a standstill up to its top)."""
        if c.dynamics is not None:
            return 0.0, c.dynamics.highest_mps
        sp = b.same_mps if c.lane is Lane.LEFT else b.oncoming_mps
        return sp.low_mps, sp.high_mps

    def start_speeds(which: int | None) -> tuple[float | None, ...]:
        """A measured vehicle's speed at the start: the low (0) or high (1) end of its interval, or anywhere."""
        return tuple(None if c.dynamics is None else (c.dynamics.speed_mps[which] if which is not None
                                                      else rng.uniform(*c.dynamics.speed_mps)) for c in cars)

    # a phantom's vehicle: at its edge, or into its unseen stretch, as far as it can still meet the AV within the plan
    # (closing at most at its lane's top speed and the AV's): a vehicle farther off may meet a later step
    av_top_mps = max(action_speed_mps(a, scenario.grid) for a in ACTION_RULES)

    def starts(pick: str, into: float | None = 0.0) -> tuple[float, ...]:
        """Each vehicle's start: a sensed one's reading (low, high or any within the error), a phantom's ``into``
        its stretch (a fraction of the farthest that matters; None: anywhere there)."""
        out = []
        for c in cars:
            if c.index is None:
                far = (rng.random() if into is None else into) * (interval(c)[1] + av_top_mps) * end_s
                out.append(c.lo_m + far if c.lo_m > 0 else c.lo_m - far)
                continue
            cells = scenario.left_lane if c.lane is Lane.LEFT else scenario.right_lane
            measured = scenario.left_m if c.lane is Lane.LEFT else scenario.right_m
            if measured is not None:  # what the snapshot measured: a reading anywhere in it
                sensed = rng.uniform(*measured[c.index])
            else:
                sensed = _sensed_start(rng, cells[c.index], c.lane, scenario.lane, scenario.grid)
            # the sensing error and the snapshot's age in its lane (``Sound.age_m``; a measured vehicle's own top)
            e = sound.start_error_m(c.lane, None if c.dynamics is None else c.dynamics.highest_mps)
            err = {"low": -e, "high": e}.get(pick, rng.uniform(-e, e))
            out.append(sensed + err)
        return tuple(out)

    def constant(which: int) -> tuple[tuple[tuple[float, float], ...], ...]:
        return tuple(((0.0, interval(c)[which]),) for c in cars)

    def switched(first: int, at_s: float) -> tuple[tuple[tuple[float, float], ...], ...]:
        return tuple(((0.0, interval(c)[first]), (at_s, interval(c)[1 - first])) for c in cars)

    ahead, behind = ((0.0, ev),), ((0.0, -ev),)
    mid = path.end_s / 2
    low, high = start_speeds(0), start_speeds(1)
    out = [Motion("corner: slowest, readings low, AV ahead", starts("low"), constant(0), ahead, low),
           Motion("corner: fastest, readings high, AV behind", starts("high"), constant(1), behind, high),
           Motion("corner: fastest, readings high, AV ahead", starts("high"), constant(1), ahead, high),
           Motion("corner: slowest, readings low, AV behind", starts("low"), constant(0), behind, low),
           Motion(f"corner: slowest then fastest at {mid:.1f} s", starts("low"), switched(0, mid), ahead, low),
           Motion(f"corner: fastest then slowest at {mid:.1f} s", starts("high"), switched(1, mid), ahead, high)]
    if any(c.dynamics is not None for c in cars):  # braking to a standstill at the worst instants
        out += [Motion(f"corner: fastest, then braking to a standstill at {k / 4 * path.end_s:.1f} s",
                       starts("high"), switched(1, k / 4 * path.end_s), ahead, high) for k in range(1, 4)]
    if any(c.index is None for c in cars):
        extremes = (("slowest", "low", 0), ("fastest", "high", 1))
        out += [Motion(f"corner: {name}, phantoms {k}/{HIDDEN_STEPS} into their stretch",
                       starts(pick, k / HIDDEN_STEPS), constant(which), ahead, start_speeds(which))
                for k in range(1, HIDDEN_STEPS + 1) for name, pick, which in extremes]
    for k in range(count):
        schedules = []
        for c in cars:
            lo, hi = interval(c)
            steps, t = [(0.0, rng.uniform(lo, hi))], 0.0
            while True:
                t += rng.expovariate(1 / 4.0)
                if t >= end_s:
                    break
                steps.append((t, rng.choice((lo, hi, rng.uniform(lo, hi)))))
            schedules.append(tuple(steps))
        offs, t = [(0.0, rng.uniform(-ev, ev))], 0.0
        while True:
            t += rng.expovariate(1 / 2.0)
            if t >= end_s:
                break
            offs.append((t, rng.uniform(-ev, ev)))
        out.append(Motion(f"sampled #{k}", starts("any", None), tuple(schedules), tuple(offs), start_speeds(None)))
    return out


def followers_now(followers: set[int], was_entering: bool, entering: bool, lanes: frozenset[Lane],
                  cars: Sequence[Vehicle], pos: Sequence[float], x_m: float) -> set[int]:
    """The same-direction vehicles that follow the AV at this instant: those behind it once it has finished moving
    into the left lane (a lane keeps its order), the same ones while it stays there, none while it is out of it."""
    if was_entering and not entering:
        followers = {i for i, c in enumerate(cars) if c.lane is Lane.LEFT and pos[i] < x_m}
    return followers if Lane.LEFT in lanes else set()


def run_motion(scenario: Scenario, actions: Sequence[Action], motion: Motion, goal: GoalRule | None = None,
               dt_s: float = MOTION_DT_S) -> Breach | None:
    """Drive one motion through the plan and the continuation; the first breach of the specification, or of
    ``goal`` when the plan ends.

    A same-direction vehicle behind the AV when it starts in, or finishes moving into, the left lane follows it
    (a lane keeps its order). Where followers react it is no conflict, and it is held at the specification's least
    gap behind; where they keep their speed it drives its schedule and is checked (``BEHIND``) while the reference
    is slower than it may be. The AV's
    deviation from its reference changes at its scheduled rate (at most the speed error) and stays within the
    position error."""
    sound = _sound(scenario)
    path = scenario_path(scenario, actions)
    cars = _drivers(scenario)
    length, ex, g_min = sound.safety.vehicle_length_m, sound.tracking.position_m, sound.safety.min_gap_m
    pos, idx = list(motion.starts_m), [0] * len(cars)
    own = [motion.start_mps[i] if motion.start_mps and c.dynamics is not None else None for i, c in enumerate(cars)]
    dev, dev_k = 0.0, 0
    times = path.times(dt_s)
    # at the start in the left lane (or moving sideways: partly in it): one short of ``follower_limit_m`` follows (one
    # not, and not clear ahead with its gap, is an unsafe start)
    in_left = scenario.lane is Lane.LEFT or sound.sideways_s > 0
    followers = {i for i, c in enumerate(cars) if c.lane is Lane.LEFT and in_left
                 and pos[i] <= follower_limit_m(0.0, sound)}
    goal_checked, was_entering = goal is None, False
    windows = held_windows_s(sound, scenario.lane, actions)
    held: list[float | None] = [None] * len(cars)  # a measured same-direction vehicle's speed as a window began
    for k, t in enumerate(times):
        while dev_k + 1 < len(motion.av_offset) and motion.av_offset[dev_k + 1][0] <= t:
            dev_k += 1
        rate = motion.av_offset[dev_k][1]
        if (dev >= ex and rate > 0) or (dev <= -ex and rate < 0):
            rate = 0.0
        x, v = path.position(t) + dev, path.speed(t) + rate
        lanes, entering = path.occupancy(t)
        followers = followers_now(followers, was_entering, entering, lanes, cars, pos, x)
        was_entering = entering
        speeds: list[float] = []
        for i in range(len(cars)):
            sched = motion.speeds[i]
            while idx[i] + 1 < len(sched) and sched[idx[i] + 1][0] <= t:
                idx[i] += 1
            now = own[i]
            speeds.append(sched[idx[i]][1] if now is None else now)
        if not goal_checked and t >= path.end_s:
            goal_checked = True
            found = _goal_breach(scenario, goal, cars, pos, x, motion.name, t)
            if found is not None:
                return found
        rear = [not sound.bounds.followers_react and path.speed(t) < top_mps(sound.bounds, c) - TOLERANCE_M
                for c in cars]  # per follower: closing in
        found = instant_breach(sound, motion.name, t, x, v, lanes, entering, rear, cars, pos, speeds, followers)
        if found is not None:
            return found
        step = (times[k + 1] - t) if k + 1 < len(times) else 0.0
        dev = max(-ex, min(ex, dev + rate * step))
        passing = any(t0 <= t < t1 for t0, t1 in windows)
        for i, c in enumerate(cars):
            d, now = c.dynamics, own[i]
            if d is not None and now is not None:
                target = motion.speeds[i][idx[i]][1]
                if passing and c.lane is Lane.LEFT:  # no speeding up while the AV passes (``Overtaken``)
                    cap = now if (kept := held[i]) is None else kept
                    held[i], target = cap, min(target, cap)
                else:
                    held[i] = None
                move, own[i] = _approach(now, target, step, d.change.accel_mps2, d.change.brake_mps2)
            else:
                move = speeds[i] * step
            pos[i] = pos[i] + move if c.lane is Lane.LEFT else pos[i] - move
            if i in followers and sound.bounds.followers_react:
                pos[i] = min(pos[i], path.position(t + step) + dev - length - g_min)
    return None


def _approach(speed_mps: float, target_mps: float, dt_s: float, accel_mps2: float,
              brake_mps2: float) -> tuple[float, float]:
    """The distance covered in ``dt_s`` and the speed then, heading from ``speed_mps`` for ``target_mps`` at the
    given rate (exactly: the speed reaches the target within the step and holds it)."""
    rate = accel_mps2 if target_mps >= speed_mps else -brake_mps2
    reach_s = min(dt_s, (target_mps - speed_mps) / rate) if rate else 0.0
    end_mps = speed_mps + rate * reach_s
    return speed_mps * reach_s + rate * reach_s * reach_s / 2 + end_mps * (dt_s - reach_s), end_mps


def instant_breach(sound: Sound, motion: str, t: float, x: float, v: float, lanes: frozenset[Lane], entering: bool,
                   rear: Sequence[bool], cars: Sequence[Vehicle], pos: Sequence[float], speeds: Sequence[float],
                   followers: set[int]) -> Breach | None:
    """The first vehicle whose gap to the AV (at ``x``, speed ``v``, occupying ``lanes``) breaks the specification at
    one instant, each vehicle at ``pos`` moving at ``speeds``: ahead in the left lane (behind it while entering that
    lane: a cut-in; a follower only where followers keep their speed and the AV is slower than it may be, ``rear``,
    per vehicle), oncoming while the AV is in the right lane and the vehicle not yet past."""
    length = sound.safety.vehicle_length_m
    for i, c in enumerate(cars):
        y, s = pos[i], speeds[i]
        if rear[i] and c.lane is Lane.LEFT and Lane.LEFT in lanes and i in followers:
            found = _gap_breach(sound, motion, Conflict.BEHIND, c.name, t, x - y - length, s - v)
            if found is not None:
                return found
        if c.lane is Lane.LEFT and Lane.LEFT in lanes and i not in followers:
            if entering and y < x:
                found = _gap_breach(sound, motion, Conflict.CUT_IN, c.name, t, x - y - length, s - v)
            else:
                found = _gap_breach(sound, motion, Conflict.AHEAD, c.name, t, y - x - length, v - s)
            if found is not None:
                return found
        if c.lane is Lane.RIGHT and Lane.RIGHT in lanes and y + length > x:
            found = _gap_breach(sound, motion, Conflict.ONCOMING, c.name, t, y - x - length, v + s)
            if found is not None:
                return found
    return None


def _goal_breach(scenario: Scenario, goal: GoalRule | None, cars: tuple[Vehicle, ...], pos: list[float], x: float,
                 name: str, t: float) -> Breach | None:
    """The goal's fields for this motion when the plan ends: targets behind the AV, oncoming vehicles past it."""
    if goal is None:
        return None
    length = _sound(scenario).safety.vehicle_length_m
    for i, c in enumerate(cars):
        if c.index is None:
            continue
        target = c.lane is Lane.LEFT and c.index in scenario.target_indices
        if goal.targets_behind and target and pos[i] + length > x:
            return Breach(None, c.name, t, x - pos[i] - length, 0.0, f"{name} (a target not behind at the end)")
        if goal.oncoming_passed and c.lane is Lane.RIGHT and pos[i] + length > x:
            return Breach(None, c.name, t, x - pos[i] - length, 0.0, f"{name} (an oncoming vehicle not past)")
    return None
