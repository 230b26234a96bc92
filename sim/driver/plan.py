"""What a decision makes of a snapshot before it acts: the paper model's plan in the frame of its first action, and
the tracking layer's refusal to start an overtake. Pure, given a planner (``sim.parts.Planner``)."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Protocol

from sim.driver.readings import Reading
from spec.actions import ACTION_RULES, Action
from spec.answers import Answer, Status
from spec.envelope import TRACKING
from spec.errors import ScenarioError
from spec.grid import Grid
from spec.lanes import Lane
from spec.motion import action_speed_mps, ramp_gain_m
from spec.scenario import Scenario


class Planner(Protocol):
    """What the decision layer asks of a planner: a snapshot cut into a scenario, and that scenario's answer."""

    def scenario(self, readings: tuple[Reading, ...], lane: Lane, speed_mps: float | None = ...,
                 oncoming_view_m: float | None = ..., sensors_ahead_m: float = ...,
                 sensed_sets: bool = ..., from_reference: bool = ...) -> Scenario: ...

    def plan(self, scenario: Scenario) -> Answer: ...


def in_frame(readings: tuple[Reading, ...], speed_mps: float, first_mps: float) -> tuple[Reading, ...]:
    """The readings as the model's AV sees them: a car at the plan's first speed ``first_mps`` from the start.

    The model starts each action at its own speed; the real car, at ``speed_mps``, gets there on a ramp, gaining (or
    losing) ``ramp_gain_m`` on traffic meanwhile, so the plan is made, executed and checked in the frame where that
    gain is already done. Planning from the raw snapshot would ignore the AV's momentum (a re-plan right after an
    accelerate found it at 14 m/s beside a car)."""
    gain_m = ramp_gain_m(speed_mps, first_mps)
    return tuple(replace(r, dx_m=r.dx_m - gain_m) for r in readings)


@dataclass(frozen=True, slots=True)
class Framed:
    """A paper-model plan, the readings in the frame it was made in, its scenario, that frame's speed, and whether the
    common-speed frame's plan stands because none was consistent with its own frame (``fell_back``)."""

    answer: Answer
    seen: tuple[Reading, ...]
    scenario: Scenario
    frame_mps: float
    fell_back: bool = False


def plan_in_frame(planner: Planner, grid: Grid, readings: tuple[Reading, ...], speed_mps: float,
                  lane: Lane) -> Framed:
    """Plan in the frame of a first action at the common speed; if the plan starts at another speed, plan again in
    that speed's frame and keep the second plan when it starts at that speed too. Otherwise the first plan stands,
    made in the common-speed frame (the executor's reference then starts where that frame puts the AV:
    ``spec.motion.reference_offset_m``). ScenarioError when the common-speed frame's snapshot makes no scenario."""
    common = grid.speed
    seen = in_frame(readings, speed_mps, common)
    scenario = planner.scenario(seen, lane)
    answer = planner.plan(scenario)
    first_mps = action_speed_mps(answer.actions[0], grid) if answer.actions else common
    if answer.status is not Status.PLAN or first_mps == common:
        return Framed(answer, seen, scenario, common)
    seen_again = in_frame(readings, speed_mps, first_mps)
    try:
        scenario_again = planner.scenario(seen_again, lane)
    except ScenarioError:
        return Framed(answer, seen, scenario, common, fell_back=True)
    again = planner.plan(scenario_again)
    both_ms = again.elapsed_ms + answer.elapsed_ms
    if again.status is Status.PLAN and again.actions and action_speed_mps(again.actions[0], grid) == first_mps:
        return Framed(replace(again, elapsed_ms=both_ms), seen_again, scenario_again, first_mps)
    return Framed(replace(answer, elapsed_ms=both_ms), seen, scenario, common, fell_back=True)


def refuses(unresolved: bool, actions: tuple[Action, ...], under_way: tuple[Action, ...], lane: Lane,
            speed_mps: float, common_mps: float) -> bool:
    """With tracking, whether a plan (``actions``) that would start an overtake (a lane change out of the left lane)
    does not start because a lane holds an ``unresolved`` contradiction (the return's gap is part of the overtake).
    Only the decision that starts it is refused: one with no lane change ``under_way`` (the rest of the last plan)
    and the AV in the left ``lane`` within ``TRACKING.speed_mps`` of the common speed, so that driving on in lane is
    what it was doing anyway. Mid-manoeuvre (an acceleration towards the lane change already run) the plan goes on:
    stopping it there leaves the AV too fast and too near the vehicle it meant to pass (measured: 8 of 10 failures
    of a refusal that acted there)."""
    if not unresolved or Action.RIGHT_LANE_CHANGE not in actions:
        return False
    if any(ACTION_RULES[a].to_lane is not None for a in under_way) or lane is not Lane.LEFT:
        return False
    return abs(speed_mps - common_mps) <= TRACKING.speed_mps
