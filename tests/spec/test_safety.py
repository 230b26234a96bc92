"""The one safety specification: the required gap is max(g_min, tau x closing speed), and breaking it is exactly the
audit's near miss (a gap under 2 m or a time to collision under 1.5 s)."""

from __future__ import annotations

import math

import pytest

from spec.physical import CAR
from spec.safety import SAFETY, SafetySpec


def test_the_defaults_are_the_audits_near_miss_thresholds_and_the_cars_length() -> None:
    assert (SAFETY.min_gap_m, SAFETY.time_gap_s, SAFETY.vehicle_length_m) == (2.0, 1.5, CAR.length_m)


@pytest.mark.parametrize(("closing_mps", "required_m"), [(-3.0, 2.0), (0.0, 2.0), (1.0, 2.0), (4.0, 6.0),
                                                         (14.0, 21.0)])
def test_the_required_gap_is_the_larger_of_the_minimum_and_the_time_gap(closing_mps: float,
                                                                        required_m: float) -> None:
    assert SAFETY.required_gap_m(closing_mps) == pytest.approx(required_m)
    assert not SAFETY.violated(required_m, closing_mps) and SAFETY.violated(required_m - 1e-9, closing_mps)


@pytest.mark.parametrize("gap_m", [-1.0, 0.0, 0.5, 1.99, 2.0, 3.0, 5.9, 6.0, 20.0])
@pytest.mark.parametrize("closing_mps", [-2.0, 0.0, 0.5, 4.0, 14.0])
def test_a_violation_is_exactly_a_gap_under_two_metres_or_a_time_to_collision_under_one_and_a_half_seconds(
        gap_m: float, closing_mps: float) -> None:
    ttc = gap_m / closing_mps if closing_mps > 0 and gap_m > 0 else (0.0 if gap_m <= 0 else math.inf)
    assert SafetySpec().violated(gap_m, closing_mps) == (gap_m < 2.0 or ttc < 1.5)


def test_the_bumper_gap_takes_one_car_length_off_the_centres() -> None:
    assert SAFETY.bumper_gap_m(30.0, 10.0) == pytest.approx(20.0 - CAR.length_m)
