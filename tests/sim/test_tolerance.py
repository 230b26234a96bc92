"""The tolerance check: a step that adds more than the step tolerance to a vehicle's deviation is a step violation,
one within it is none, and a deviation that builds up beyond the plan tolerance is a plan violation."""

from __future__ import annotations

import pytest

from sim import tolerance
from sim.driver.readings import Reading
from sim.tolerance import ToleranceReport
from spec.grid import PAPER_GRID
from spec.kinds import ViolationKind
from spec.lanes import Lane
from spec.physical import CAR, LOOP
from spec.state import State

UNIT_M = LOOP.tolerance_unit_m


def _check(report: ToleranceReport, measured_units: float, previous: float = 0.0) -> float:
    return report.check(1, 1, "drive", "left_lane[0]", 0.0, 0.0, measured_units * UNIT_M, previous)


def test_a_step_just_over_the_step_tolerance_is_a_violation_and_just_under_is_none() -> None:
    over, under = ToleranceReport(0.25, 0.5), ToleranceReport(0.25, 0.5)
    _check(over, 0.26)
    _check(under, 0.24)
    assert [v.kind for v in over.violations] == [ViolationKind.STEP] and under.violations == []


def test_small_steps_that_build_up_beyond_the_plan_tolerance_are_a_plan_violation() -> None:
    report = ToleranceReport(0.25, 0.5)
    deviation = 0.0
    for k in range(1, 4):
        deviation = _check(report, 0.2 * k, deviation)
    assert [v.kind for v in report.violations] == [ViolationKind.PLAN]


def test_the_check_follows_each_vehicle_in_the_window_by_its_lane_and_index_from_its_start() -> None:
    g = PAPER_GRID
    seen = (Reading(Lane.LEFT, 7, 45.0), Reading(Lane.LEFT, 8, -5000.0), Reading(Lane.LEFT, 9, 2.0),
            Reading(Lane.RIGHT, 4, 300.0))
    start = State(Lane.LEFT, (10, 12), (25,))
    followed = tolerance.followed(seen, start, g)
    # the one far behind is outside the window; indices count each lane's vehicles in it from behind
    assert followed == {(Lane.LEFT, 0, 9): (2.0, 10), (Lane.LEFT, 1, 7): (45.0, 12), (Lane.RIGHT, 0, 4): (300.0, 25)}
    gaps = tolerance.implied_gaps(followed, State(Lane.LEFT, (11, 13), (20,)), g)
    assert gaps == pytest.approx({9: g.cell - CAR.length_m, 7: 3 * g.cell - CAR.length_m,
                                  4: 10 * g.cell - CAR.length_m})


def test_a_plans_check_follows_its_vehicles_until_they_respawn_implies_gaps_only_while_an_action_runs() -> None:
    """``PlanCheck``: after each action every vehicle of the plan's window against its predicted cell, told to the
    observers with the new violations; a vehicle respawned since the plan started is another vehicle, no longer
    followed nor given an implied gap; a ghost a fault injected (no body in the world) is never followed."""
    from dataclasses import dataclass

    from spec.actions import Action

    @dataclass
    class Car:
        body: int
        x_m: float
        respawns: int = 0

    g = PAPER_GRID
    ahead, oncoming = Car(7, 45.0), Car(4, 300.0)
    seen = (Reading(Lane.LEFT, 7, 45.0), Reading(Lane.LEFT, 99, 80.0), Reading(Lane.RIGHT, 4, 300.0))
    states = (State(Lane.LEFT, (12, 14), (25,)), State(Lane.LEFT, (12, 14), (25,)), State(Lane.LEFT, (12, 14), (25,)))
    told: list[tuple[int, Action, int]] = []
    check = tolerance.PlanCheck(ToleranceReport(), 3, seen, states, g, lambda: [ahead, oncoming], lambda: 0.0,
                                lambda step, action, state, new: told.append((step, action, len(new))))
    assert set(check.tracked) == {(Lane.LEFT, 0, 7), (Lane.RIGHT, 0, 4)}  # body 99 is no vehicle of the world
    assert check.implied == {}
    check.expecting(0)
    assert set(check.implied) == {7, 4}
    check.expecting(None)
    assert check.implied == {}
    oncoming.x_m = 300.0 - 3 * LOOP.tolerance_unit_m  # it moved three tolerance units more than predicted: violations
    assert check.deviated(0, Action.DRIVE) and told == [(1, Action.DRIVE, 1)]
    oncoming.respawns = 1  # respawned: another vehicle, no longer followed
    check.expecting(1)
    assert set(check.implied) == {7}
    assert not check.deviated(1, Action.DRIVE) and told[-1] == (2, Action.DRIVE, 0)
