"""The AV's planned motion: the speed reference the executor follows through a plan, written once so that the
simulator's executor and the sound model's envelope of the AV read the same rule.

Each action has its speed (speed factor x the common speed, ``spec.actions``); between two actions
the reference ramps at ``RAMP_SHARE`` of the car's acceleration or braking limit, centred on their
boundary, so the distance lost on one side is made up on the other; the first ramp starts at the
car's measured speed, and the last runs towards the common speed, centred on the plan's end.
Positions are the reference's exact integral (``SpeedProfile.distance_m``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from spec.actions import ACTION_RULES, Action
from spec.grid import Grid
from spec.physical import CAR, CarSpec

RAMP_SHARE = 0.9  # reference ramps use this share of the car's limits, leaving some for the feedback


def action_speed_mps(action: Action | None, grid: Grid) -> float:
    """The AV's speed during an action by the physical mapping; None (no action): the common speed."""
    return grid.speed if action is None else float(ACTION_RULES[action].speed_factor) * grid.speed


def ramp_s(v_from_mps: float, v_to_mps: float, spec: CarSpec = CAR) -> float:
    """How long a speed change takes at RAMP_SHARE of the car's acceleration or braking limit."""
    rate = spec.max_accel_mps2 if v_to_mps > v_from_mps else spec.max_brake_mps2
    return abs(v_to_mps - v_from_mps) / (RAMP_SHARE * rate)


def ramp_gain_m(v_from_mps: float, v_to_mps: float) -> float:
    """How far a car ramping from one speed to another gets ahead (negative: behind) of one at the second all along."""
    return (v_from_mps - v_to_mps) * ramp_s(v_from_mps, v_to_mps) / 2


def covered_s(distance_m: float, from_mps: float, to_mps: float, rate_mps2: float) -> float:
    """How long a relative motion takes to cover ``distance_m``: its speed moving linearly from ``from_mps`` to
    ``to_mps`` at ``rate_mps2``, then kept (0 for no distance; infinite when it never covers it)."""
    if distance_m <= 0.0:
        return 0.0
    if to_mps == from_mps:
        return distance_m / to_mps if to_mps > 0.0 else math.inf
    rate = rate_mps2 if to_mps > from_mps else -rate_mps2
    change_s = (to_mps - from_mps) / rate
    change_m = (to_mps * to_mps - from_mps * from_mps) / (2.0 * rate)
    # the farthest the change reaches: where it ends, or where its speed passes 0 when it turns round on the way
    reach_m = from_mps * from_mps / (-2.0 * rate) if rate < 0.0 < from_mps and to_mps < 0.0 else change_m
    if distance_m <= reach_m:  # on the way: the first time the displacement reaches it
        return (-from_mps + math.sqrt(from_mps * from_mps + 2.0 * rate * distance_m)) / rate
    if to_mps <= 0.0:
        return math.inf
    return change_s + (distance_m - change_m) / to_mps


@dataclass(frozen=True, slots=True)
class Ramp:
    """A linear speed change of ``dv_mps`` from ``start_s`` on, over ``duration_s`` (times on a plan's clock)."""

    start_s: float
    duration_s: float
    dv_mps: float

    def at(self, t_s: float) -> float:
        if t_s <= self.start_s:
            return 0.0
        if t_s >= self.start_s + self.duration_s:
            return self.dv_mps
        return self.dv_mps * (t_s - self.start_s) / self.duration_s

    def integral_m(self, t_s: float) -> float:
        """The distance this ramp has added by ``t_s`` (the integral of ``at`` from minus infinity)."""
        if t_s <= self.start_s:
            return 0.0
        if t_s >= self.start_s + self.duration_s:
            return self.dv_mps * (t_s - self.start_s - self.duration_s / 2)
        return self.dv_mps * (t_s - self.start_s) ** 2 / (2 * self.duration_s)


@dataclass(frozen=True, slots=True)
class SpeedProfile:
    """The speed reference through one action: a window onto its plan's reference, which is a starting
    speed plus one ramp per boundary between speeds, superposed (so a long ramp may run on into the next
    action, the speed stays continuous, and every ramp keeps its area)."""

    start_mps: float
    ramps: tuple[Ramp, ...]
    offset_s: float = 0.0  # where this action starts on the plan's clock

    def at(self, t_s: float) -> float:
        """The reference speed ``t_s`` into the action."""
        t = self.offset_s + t_s
        return self.start_mps + sum(r.at(t) for r in self.ramps)

    def distance_m(self, t_s: float) -> float:
        """How far the reference has gone from the plan's start to ``t_s`` into this action (exact)."""
        t = self.offset_s + t_s
        return self.start_mps * t + sum(r.integral_m(t) - r.integral_m(0.0) for r in self.ramps)


def plan_profiles(actions: tuple[Action, ...], start_mps: float, grid: Grid, to_common: bool = True) -> list[
        SpeedProfile]:
    """One profile per action of a plan: a ramp from the car's speed into the first action, starting now;
    between two actions a ramp centred on their boundary, so the distance lost on one side is made up on
    the other and the car is where the model puts it at every boundary (to within half the ramp's area);
    and (``to_common``, the paper model's) a ramp towards the common speed centred on the plan's end (the next
    plan's frame starts there). The sound model's reference has none: its last action keeps its speed to the end
    (``spec.envelope``), and the next plan starts from the speed the car has.
    """
    speeds = [action_speed_mps(a, grid) for a in actions]
    starts, t = [], 0.0
    for action in actions:
        starts.append(t)
        t += float(ACTION_RULES[action].duration_s)
    edges = [(0.0, start_mps, speeds[0], False)]
    edges += [(starts[k], speeds[k - 1], speeds[k], True) for k in range(1, len(speeds))]
    edges += [(t, speeds[-1], grid.speed, True)] if to_common else []
    ramps = tuple(Ramp(at - (ramp_s(v0, v1) / 2 if centred else 0.0), ramp_s(v0, v1), v1 - v0)
                  for at, v0, v1, centred in edges if v1 != v0)
    return [SpeedProfile(start_mps, ramps, start) for start in starts]


def reference_offset_m(speed_mps: float, frame_mps: float, first_mps: float) -> float:
    """Where a plan's position reference starts, ahead of the car: at the AV of the frame the plan was
    made in (``ramp_gain_m`` to the frame's speed), less what the first ramp itself gains on the way to
    the first action's speed (zero in the plan's own frame, where the two are the same)."""
    return ramp_gain_m(speed_mps, frame_mps) - ramp_gain_m(speed_mps, first_mps)
