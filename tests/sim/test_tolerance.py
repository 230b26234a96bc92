"""The tolerance check: a step that adds more than the step tolerance to a vehicle's deviation is a step violation,
one within it is none, and a deviation that builds up beyond the plan tolerance is a plan violation."""

from __future__ import annotations

from sim.tolerance import ToleranceReport
from spec.kinds import ViolationKind
from spec.physical import LOOP

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
