"""What a decision makes of a snapshot (``sim.driver.plan``): the paper model's plan in its first action's frame, with
a scripted planner, and the tracking layer's refusal at each boundary; no physics engine."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, cast

import pytest

from sim.driver.plan import Framed, in_frame, plan_in_frame, refuses
from sim.driver.readings import Reading
from spec.actions import Action
from spec.answers import Answer, Status, Strategy
from spec.envelope import TRACKING
from spec.errors import ScenarioError
from spec.grid import PAPER_GRID
from spec.lanes import Lane
from spec.motion import action_speed_mps, ramp_gain_m
from spec.scenario import Scenario

COMMON = PAPER_GRID.speed
FAST = action_speed_mps(Action.ACCELERATE, PAPER_GRID)
READINGS = (Reading(Lane.LEFT, 0, 30.0), Reading(Lane.RIGHT, 1, 200.0))


def answer(status: Status, *actions: Action, ms: float = 1.0) -> Answer:
    return Answer(status, None, "scripted", Strategy.SENSIBLE, actions, (), 0, ms)


@dataclass
class Scripted:
    """A planner whose answers are given in order; a scenario is the readings it was cut from (or an error)."""

    answers: list[Answer]
    unreadable: set[int] = field(default_factory=set)  # the calls (from 0) whose snapshot makes no scenario
    asked: list[tuple[Reading, ...]] = field(default_factory=list)

    def scenario(self, readings: tuple[Reading, ...], lane: Lane, speed_mps: float | None = None,
                 oncoming_view_m: float | None = None, sensors_ahead_m: float = 0.0) -> Scenario:
        self.asked.append(readings)
        if len(self.asked) - 1 in self.unreadable:
            raise ScenarioError("left_lane", [11, 11], "two vehicles in one cell")
        return cast(Scenario, readings)

    def plan(self, scenario: Scenario) -> Answer:
        return self.answers.pop(0)


def framed(planner: Scripted, speed_mps: float = COMMON) -> Framed:
    return plan_in_frame(cast(Any, planner), PAPER_GRID, READINGS, speed_mps, Lane.LEFT)


def test_the_frame_is_the_snapshot_moved_by_what_the_first_ramp_gains() -> None:
    moved = in_frame(READINGS, 14.0, COMMON)  # braking to 7 m/s gains on traffic
    assert [r.dx_m for r in moved] == pytest.approx([30.0 - ramp_gain_m(14.0, 7.0), 200.0 - ramp_gain_m(14.0, 7.0)])
    assert in_frame(READINGS, 7.0, 7.0) == READINGS


def test_a_plan_that_starts_at_the_common_speed_is_made_once_in_the_common_frame() -> None:
    planner = Scripted([answer(Status.PLAN, Action.RIGHT_LANE_CHANGE)])
    got = framed(planner, speed_mps=9.0)
    assert got.frame_mps == COMMON and not got.fell_back and len(planner.asked) == 1
    assert got.seen == in_frame(READINGS, 9.0, COMMON) == got.scenario


def test_no_plan_is_answered_from_the_common_frame_without_a_second_plan() -> None:
    planner = Scripted([answer(Status.NO_PLAN)])
    got = framed(planner)
    assert got.answer.status is Status.NO_PLAN and got.frame_mps == COMMON and len(planner.asked) == 1


def test_a_plan_at_another_speed_is_made_again_in_that_speeds_frame_and_kept_when_it_agrees() -> None:
    planner = Scripted([answer(Status.PLAN, Action.ACCELERATE, ms=2.0), answer(Status.PLAN, Action.ACCELERATE, ms=3.0)])
    got = framed(planner)
    assert got.frame_mps == FAST and not got.fell_back
    assert got.seen == in_frame(READINGS, COMMON, FAST) == planner.asked[1]
    assert got.answer.elapsed_ms == 5.0  # both plans' time is the decision's


@pytest.mark.parametrize("second", [answer(Status.PLAN, Action.RIGHT_LANE_CHANGE), answer(Status.NO_PLAN)])
def test_a_second_plan_that_does_not_start_at_its_frames_speed_leaves_the_first_standing(second: Answer) -> None:
    planner = Scripted([answer(Status.PLAN, Action.ACCELERATE, ms=2.0), second])
    got = framed(planner)
    assert got.fell_back and got.frame_mps == COMMON and got.answer.actions == (Action.ACCELERATE,)
    assert got.seen == in_frame(READINGS, COMMON, COMMON) and got.answer.elapsed_ms == 3.0


def test_a_second_frame_that_makes_no_scenario_leaves_the_first_plan_standing() -> None:
    planner = Scripted([answer(Status.PLAN, Action.ACCELERATE, ms=2.0)], unreadable={1})
    got = framed(planner)
    assert got.fell_back and got.frame_mps == COMMON and got.answer.elapsed_ms == 2.0


def test_a_first_frame_that_makes_no_scenario_is_the_callers_to_answer() -> None:
    with pytest.raises(ScenarioError):
        framed(Scripted([], unreadable={0}))


START = (Action.ACCELERATE, Action.RIGHT_LANE_CHANGE)


@pytest.mark.parametrize(("unresolved", "actions", "under_way", "lane", "speed_mps", "refused"), [
    (True, START, (), Lane.LEFT, COMMON, True),
    (False, START, (), Lane.LEFT, COMMON, False),  # nothing unresolved
    (True, (Action.DRIVE, Action.ACCELERATE), (), Lane.LEFT, COMMON, False),  # no overtake started
    (True, START, (Action.RIGHT_LANE_CHANGE,), Lane.LEFT, COMMON, False),  # a lane change under way: mid-manoeuvre
    (True, START, (Action.DRIVE,), Lane.LEFT, COMMON, True),  # what is under way changes no lane
    (True, START, (), Lane.RIGHT, COMMON, False),  # not in its own lane
    (True, START, (), Lane.LEFT, COMMON + TRACKING.speed_mps, True),  # at the envelope's edge: still at the speed
    (True, START, (), Lane.LEFT, COMMON - TRACKING.speed_mps - 0.01, False),  # off the common speed: mid-manoeuvre
    (True, START, (), Lane.LEFT, COMMON + TRACKING.speed_mps + 0.01, False),
])
def test_an_unresolved_contradiction_refuses_only_the_decision_that_starts_an_overtake(
        unresolved: bool, actions: tuple[Action, ...], under_way: tuple[Action, ...], lane: Lane, speed_mps: float,
        refused: bool) -> None:
    assert refuses(unresolved, actions, under_way, lane, speed_mps, COMMON) is refused
