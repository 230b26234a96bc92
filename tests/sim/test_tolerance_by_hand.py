"""The tolerance check on hand traces with a signed deviation: ahead of the prediction is positive, behind negative,
the thresholds bite at the stated values in both directions, and the histogram bin is the one worked out by hand,
so a fault in a sign (measured and predicted swapped, the displacement taken the wrong way round, an ``abs``
dropped) fails here rather than only in a seeded drive.

Quarter-cell offsets (5.25 m of a 21 m cell) are exact in binary floating point, so the thresholds are tested at
exactly their value; other offsets are compared to within 1e-12 cells."""

from __future__ import annotations

import pytest

from sim.tolerance import HISTOGRAM_BIN, HISTOGRAM_BINS, ToleranceReport
from spec.kinds import ViolationKind
from spec.physical import LOOP

UNIT_M = 21.0  # the paper's cell: tolerances count it whatever the planner's grid (LOOP.tolerance_unit_m)
STEP_CELLS, PLAN_CELLS = 0.25, 0.5  # the stated tolerances (LoopSpec)
START_DX_M = 63.0  # the vehicle 3 cells ahead of the AV when the plan started
PREDICTED_M = 42.0  # the model moves it 2 cells further ahead over the action


def _report() -> ToleranceReport:
    return ToleranceReport(STEP_CELLS, PLAN_CELLS)


def _after(report: ToleranceReport, off_cells: float, previous: float = 0.0, step: int = 1,
           predicted_m: float = PREDICTED_M) -> float:
    """One check of a vehicle that is ``off_cells`` ahead of where the model put it (negative: behind)."""
    now_dx_m = START_DX_M + predicted_m + off_cells * UNIT_M
    return report.check(7, step, "accelerate", "left_lane[0]", predicted_m, START_DX_M, now_dx_m, previous)


def test_the_stated_tolerances_and_unit_are_the_ones_these_traces_assume() -> None:
    assert LOOP.tolerance_unit_m == UNIT_M
    assert (LOOP.step_tolerance_cells, LOOP.plan_tolerance_cells) == (STEP_CELLS, PLAN_CELLS)
    default = ToleranceReport()
    assert (default.step_tolerance, default.plan_tolerance) == (STEP_CELLS, PLAN_CELLS)


@pytest.mark.parametrize("off_cells", [0.2, -0.2, 0.05, -0.05])
def test_the_deviation_is_measured_minus_predicted_with_its_sign(off_cells: float) -> None:
    """A vehicle further ahead of the AV than predicted has a positive deviation, one behind a negative one."""
    report = _report()
    assert _after(report, off_cells) == pytest.approx(off_cells, abs=1e-12)
    assert report.violations == [] and report.checks["accelerate"] == 1
    assert report.largest["accelerate"] == pytest.approx(abs(off_cells), abs=1e-12)


def test_the_displacement_counts_from_the_plans_start_not_from_the_avs_position() -> None:
    """Start 3 cells ahead, predicted 2 cells on, found 4.5 cells ahead: moved 1.5 cells, half a cell short of the
    prediction; the starting distance itself is no part of the deviation."""
    report = _report()
    deviation = report.check(1, 1, "drive", "left_lane[0]", PREDICTED_M, START_DX_M, 4.5 * UNIT_M, 0.0)
    assert deviation == pytest.approx(-0.5, abs=1e-12)
    (violation,) = report.violations  # half a cell in one step: beyond the step tolerance
    assert violation.kind is ViolationKind.STEP
    assert violation.predicted_cells == pytest.approx(2.0, abs=1e-12)
    assert violation.measured_cells == pytest.approx(1.5, abs=1e-12)
    assert violation.deviation == pytest.approx(-0.5, abs=1e-12)
    assert violation.to_json()["deviation_cells"] == -0.5


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_one_step_at_exactly_the_step_tolerance_is_none_and_just_past_it_is_a_step_violation(sign: float) -> None:
    at, past = _report(), _report()
    assert _after(at, sign * 0.25) == sign * 0.25  # exact: 5.25 m over 21 m
    _after(past, sign * 0.26)
    assert at.violations == []
    (violation,) = past.violations
    assert violation.kind is ViolationKind.STEP and violation.vehicle == "left_lane[0]"
    assert violation.plan == 7 and violation.step == 1 and violation.action == "accelerate"
    assert violation.deviation == pytest.approx(sign * 0.26, abs=1e-12)  # behind is negative, ahead positive
    assert past.violations_by_action == {"accelerate": 1} and past.violation_count == 1


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_a_plan_at_exactly_the_plan_tolerance_is_none_and_just_past_it_is_a_plan_violation(sign: float) -> None:
    """Two steps of a quarter cell each (each at the step tolerance) reach half a cell: not beyond it; a third step
    of a hundredth of a cell goes beyond it, in either direction."""
    report = _report()
    deviation = _after(report, sign * 0.25, 0.0, step=1)
    deviation = _after(report, sign * 0.5, deviation, step=2)
    assert deviation == sign * 0.5 and report.violations == []
    deviation = _after(report, sign * 0.51, deviation, step=3)
    (violation,) = report.violations
    assert violation.kind is ViolationKind.PLAN and violation.step == 3
    assert deviation == pytest.approx(sign * 0.51, abs=1e-12) and violation.deviation == pytest.approx(deviation)


def test_deviations_of_opposite_sign_cancel_since_the_deviation_is_measured_from_the_plans_start() -> None:
    """Ahead by 0.2 then 0.4 cells, then back to 0.2 and 0.0: each step adds 0.2 (within 0.25) and the total never
    passes 0.5, so nothing is a violation and the vehicle ends where the model put it."""
    report = _report()
    deviation, seen = 0.0, []
    for k, off_cells in enumerate((0.2, 0.4, 0.2, 0.0), start=1):
        deviation = _after(report, off_cells, deviation, step=k)
        seen.append(deviation)
    assert seen == pytest.approx([0.2, 0.4, 0.2, 0.0], abs=1e-12)
    assert report.violations == [] and report.checks["accelerate"] == 4
    assert report.largest["accelerate"] == pytest.approx(0.2, abs=1e-12)


def test_a_swing_from_ahead_to_behind_adds_both_parts_in_one_step() -> None:
    """From 0.2 cells ahead to 0.2 cells behind in one action is a step of 0.4 cells (a step violation), though
    neither position alone is beyond either tolerance."""
    report = _report()
    deviation = _after(report, 0.2, 0.0, step=1)
    deviation = _after(report, -0.2, deviation, step=2)
    assert deviation == pytest.approx(-0.2, abs=1e-12)
    (violation,) = report.violations
    assert violation.kind is ViolationKind.STEP and violation.step == 2
    assert report.largest["accelerate"] == pytest.approx(0.4, abs=1e-12)


def test_deviations_of_one_sign_build_up_behind_the_prediction_as_well_as_ahead() -> None:
    report = _report()
    deviation = 0.0
    for k in range(1, 4):
        deviation = _after(report, -0.2 * k, deviation, step=k)
    assert deviation == pytest.approx(-0.6, abs=1e-12)
    assert [(v.kind, v.step) for v in report.violations] == [(ViolationKind.PLAN, 3)]


@pytest.mark.parametrize(("off_cells", "previous", "bin_index"), [
    (0.11, 0.0, 5),  # 0.11 / 0.02 = 5.5
    (-0.11, 0.0, 5),  # the same size behind the prediction: the same bin
    (0.05, 0.16, 5),  # from 0.16 back to 0.05: 0.11 added
    (-0.27, 0.0, 13),  # 13.5
    (0.0, 0.0, 0),
    (-1.5, 0.0, HISTOGRAM_BINS),  # 75 bins: the overflow bin
])
def test_the_added_deviation_lands_in_the_bin_worked_out_by_hand(off_cells: float, previous: float,
                                                                  bin_index: int) -> None:
    assert (HISTOGRAM_BIN, HISTOGRAM_BINS) == (0.02, 50)
    report = _report()
    _after(report, off_cells, previous)
    expected = [0] * (HISTOGRAM_BINS + 1)
    expected[bin_index] = 1
    assert report.histogram["accelerate"] == expected


def test_a_report_read_back_from_json_keeps_its_counts_and_its_largest_step_deviation() -> None:
    report = _report()
    _after(report, -0.3)
    again = ToleranceReport.from_json(report.to_json())
    assert again.violation_count == 1 and dict(again.checks) == {"accelerate": 1}
    assert again.largest["accelerate"] == pytest.approx(0.3) and again.histogram == report.histogram
