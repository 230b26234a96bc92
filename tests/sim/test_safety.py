"""The safety monitor: gaps, times to collision and near misses, with the gap the model's cells implied."""

from __future__ import annotations

import math
from types import SimpleNamespace

import pytest

from sim.safety import SafetyMonitor, SafetyReport
from sim.vehicle import Pose
from spec.lanes import Lane
from spec.physical import CAR
from spec.safety import SafetySpec


def car(body: int, x_m: float, velocity_mps: float) -> SimpleNamespace:
    return SimpleNamespace(body=body, x_m=x_m, velocity_mps=velocity_mps)


def test_a_closing_vehicle_ahead_is_one_near_miss_with_its_worst_values_and_implied_gap() -> None:
    monitor = SafetyMonitor(SafetySpec(min_gap_m=2.0, time_gap_s=1.5))
    implied = {7: 16.5}.get
    for x_m in (30.0, 12.0, 10.0, 8.0, 30.0, 9.0):  # closes in, drops back, closes in again
        pose = Pose(0.0, 1.8, 0.0, 10.0)
        monitor.observe(pose, Lane.LEFT, [car(7, x_m, 6.0)], [], 1.0, 10.0, "drive", implied)  # type: ignore[list-item]
    report = monitor.report
    assert report.near_misses == 2 and report.contacts == 0
    first = report.encounters[0]
    assert first.gap_m == pytest.approx(8.0 - CAR.length_m) and first.ttc_s == pytest.approx((8.0 - 4.5) / 4.0)
    assert first.implied_gap_m == 16.5 and first.lane == "left" and first.doing == "drive"
    assert report.min_gap_left_m == pytest.approx(3.5) and report.min_gap_oncoming_m == math.inf


def test_oncoming_traffic_counts_the_sum_of_both_speeds_and_only_in_the_right_lane() -> None:
    monitor = SafetyMonitor()
    oncoming = [car(3, 40.0, -7.0)]
    monitor.observe(Pose(0.0, -1.8, 0.0, 7.0), Lane.RIGHT, [], oncoming, 0.0, 0.0, "x", {}.get)  # type: ignore[arg-type]
    assert monitor.report.min_ttc_oncoming_s == pytest.approx((40.0 - 4.5) / 14.0)
    assert monitor.report.min_gap_left_m == math.inf and monitor.report.near_misses == 0
    monitor.observe(Pose(0.0, 1.8, 0.0, 7.0), Lane.LEFT, [], oncoming, 0.0, 0.0, "x", {}.get)  # type: ignore[arg-type]
    assert monitor.report.min_gap_oncoming_m == pytest.approx(35.5)  # unchanged: the AV was back in its lane


def test_a_report_round_trips_through_json() -> None:
    monitor = SafetyMonitor()
    monitor.observe(Pose(0.0, 1.8, 0.0, 9.0), Lane.LEFT, [car(1, 6.0, 7.0)], [], 0.5, 3.0, "accelerate",  # type: ignore[list-item]
                    {}.get)
    monitor.contact(car(1, 5.0, 7.0), Lane.LEFT, Pose(0.0, 1.8, 0.0, 9.0), 0.5, 3.1, "accelerate", None)  # type: ignore[arg-type]
    again = SafetyReport.from_json(monitor.report.to_json())
    assert again.to_json() == monitor.report.to_json() and again.contacts == 1 and again.near_misses == 1


def test_deviation_quantiles_name_an_empty_histogram_and_the_overflow_bin_apart() -> None:
    from sim.tolerance import HISTOGRAM_BINS, histogram_quantile

    assert histogram_quantile([0] * (HISTOGRAM_BINS + 1), 0.5) is None
    bins = [0] * (HISTOGRAM_BINS + 1)
    bins[2], bins[-1] = 9, 1
    assert histogram_quantile(bins, 0.5) == 0.06 and histogram_quantile(bins, 0.95) == math.inf
