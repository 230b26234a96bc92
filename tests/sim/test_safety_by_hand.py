"""The safety monitor on constructed two-vehicle situations whose gap, closing speed and time to collision are
worked out by hand: ahead in the AV's lane, oncoming in the right lane, and what must not count (a vehicle behind,
one pulling away, one in the other lane), with the near-miss thresholds tested exactly at and just past their value.

The AV is 4.5 m long (``CAR.length_m``), so a vehicle whose centre is x m ahead is x - 4.5 m away bumper to bumper;
the numbers are chosen so that each gap and time to collision is exact in binary floating point."""

from __future__ import annotations

import math
from types import SimpleNamespace

import pytest

from sim.safety import RULE, SafetyMonitor, ahead_in_lane
from sim.vehicle import Pose
from spec.lanes import Lane
from spec.physical import CAR
from spec.safety import SAFETY

LENGTH_M = 4.5
NEAR_GAP_M, NEAR_TTC_S = 2.0, 1.5  # the stated near-miss thresholds (SafetySpec)
LEFT_Y_M, RIGHT_Y_M = 1.8, -1.8


def car(body: int, x_m: float, velocity_mps: float) -> SimpleNamespace:
    return SimpleNamespace(body=body, x_m=x_m, velocity_mps=velocity_mps)


def watch(lane: Lane, av_mps: float, left: list[SimpleNamespace], oncoming: list[SimpleNamespace]) -> SafetyMonitor:
    """One observation of the AV at x = 0 in ``lane`` at ``av_mps``."""
    monitor = SafetyMonitor()
    pose = Pose(0.0, LEFT_Y_M if lane is Lane.LEFT else RIGHT_Y_M, 0.0, av_mps)
    monitor.observe(pose, lane, left, oncoming, 2.5, 30.0, "drive", {}.get)  # type: ignore[arg-type]
    return monitor


def test_the_stated_thresholds_and_car_length_are_the_ones_these_cases_assume() -> None:
    assert (SAFETY.min_gap_m, SAFETY.time_gap_s) == (NEAR_GAP_M, NEAR_TTC_S)
    assert CAR.length_m == LENGTH_M


def test_the_vehicle_ahead_is_the_nearest_one_ahead_with_its_bumper_gap_and_closing_speed() -> None:
    """AV at 10 m/s; ahead in the left lane at 20 m (6 m/s) and 50 m (0 m/s): the one at 20 m, 15.5 m away,
    closing at 4 m/s; the standing one further on does not count yet."""
    near, far = car(1, 20.0, 6.0), car(2, 50.0, 0.0)
    found, gap_m, closing_mps = ahead_in_lane(Pose(0.0, LEFT_Y_M, 0.0, 10.0), Lane.LEFT, [far, near], [])  # type: ignore[list-item]
    assert found is near and gap_m == 15.5 and closing_mps == 4.0
    report = watch(Lane.LEFT, 10.0, [far, near], []).report
    assert report.min_gap_left_m == 15.5 and report.min_ttc_left_s == 15.5 / 4.0 and report.near_misses == 0
    assert report.min_gap_oncoming_m == math.inf and report.min_ttc_oncoming_s == math.inf


def test_an_oncoming_vehicle_closes_at_the_sum_of_both_speeds() -> None:
    """AV at 7 m/s in the right lane, an oncoming vehicle 40 m ahead at 7 m/s towards it: 35.5 m, closing at
    14 m/s, 35.5 / 14 s to collision."""
    oncoming = car(3, 40.0, -7.0)
    found, gap_m, closing_mps = ahead_in_lane(Pose(0.0, RIGHT_Y_M, 0.0, 7.0), Lane.RIGHT, [], [oncoming])  # type: ignore[list-item]
    assert found is oncoming and gap_m == 35.5 and closing_mps == 14.0
    report = watch(Lane.RIGHT, 7.0, [], [oncoming]).report
    assert report.min_ttc_oncoming_s == 35.5 / 14.0 and report.min_gap_left_m == math.inf


@pytest.mark.parametrize(("x_m", "near"), [(6.5, False), (6.49, True)])
def test_a_gap_exactly_at_the_near_miss_gap_is_none_and_just_below_it_is_one(x_m: float, near: bool) -> None:
    """Same speed as the AV (never closing, infinite time to collision): only the gap can make it a near miss;
    a centre 6.5 m ahead is a 2.0 m gap."""
    report = watch(Lane.LEFT, 7.0, [car(4, x_m, 7.0)], []).report
    assert report.min_ttc_left_s == math.inf and report.min_gap_left_m == pytest.approx(x_m - LENGTH_M)
    assert report.near_misses == int(near)


@pytest.mark.parametrize(("av_mps", "near"), [(10.0, False), (10.25, True)])
def test_a_time_to_collision_exactly_at_the_near_miss_time_is_none_and_just_below_it_is_one(av_mps: float,
                                                                                            near: bool) -> None:
    """A 6 m gap (centre 10.5 m ahead) to a vehicle at 6 m/s: closing at 4 m/s it is 1.5 s away (none), at
    4.25 m/s 6 / 4.25 s (a near miss); the gap alone is no near miss."""
    report = watch(Lane.LEFT, av_mps, [car(5, 10.5, 6.0)], []).report
    assert report.min_gap_left_m == 6.0 and report.min_ttc_left_s == 6.0 / (av_mps - 6.0)
    assert report.near_misses == int(near)
    if near:
        (event,) = report.encounters
        assert event.kind == "near_miss" and event.lane == "left" and event.rule == RULE[Lane.LEFT]
        assert event.gap_m == 6.0 and event.ttc_s == 6.0 / 4.25 and event.km == 2.5 and event.t_s == 30.0


@pytest.mark.parametrize(("x_m", "near"), [(25.5, False), (25.4, True)])
def test_an_oncoming_time_to_collision_at_the_threshold_is_none_and_just_below_it_is_one(x_m: float,
                                                                                        near: bool) -> None:
    """Closing at 7 + 7 m/s, a 21 m gap (centre 25.5 m ahead) is exactly 1.5 s away; 20.9 m is a near miss."""
    report = watch(Lane.RIGHT, 7.0, [], [car(6, x_m, -7.0)]).report
    assert report.min_ttc_oncoming_s == pytest.approx((x_m - LENGTH_M) / 14.0)
    assert report.near_misses == int(near)
    if near:
        assert report.encounters[0].lane == "oncoming" and report.encounters[0].rule == RULE[Lane.RIGHT]


def test_a_vehicle_behind_the_av_does_not_count_however_fast_it_comes() -> None:
    """A vehicle 3 m behind the AV's centre (overlapping it from behind) at 20 m/s is not ahead: no gap, no near
    miss."""
    report = watch(Lane.LEFT, 7.0, [car(7, -3.0, 20.0)], []).report
    assert report.min_gap_left_m == math.inf and report.min_ttc_left_s == math.inf and report.near_misses == 0


def test_a_vehicle_pulling_away_has_no_time_to_collision_and_is_no_near_miss() -> None:
    """A 3 m gap to a vehicle at 12 m/s ahead of an AV at 10 m/s: the gap opens (closing at -2 m/s), so the time
    to collision is infinite, and 3 m is beyond the near-miss gap."""
    _, gap_m, closing_mps = ahead_in_lane(Pose(0.0, LEFT_Y_M, 0.0, 10.0), Lane.LEFT, [car(8, 7.5, 12.0)], [])  # type: ignore[list-item]
    assert gap_m == 3.0 and closing_mps == -2.0
    report = watch(Lane.LEFT, 10.0, [car(8, 7.5, 12.0)], []).report
    assert report.min_ttc_left_s == math.inf and report.near_misses == 0


def test_only_the_vehicles_of_the_avs_own_lane_count() -> None:
    """In the left lane, an oncoming vehicle 6 m ahead (a 1.5 m gap, closing fast) is in the other lane; in the
    right lane, a left-lane vehicle as close is too."""
    in_left = watch(Lane.LEFT, 7.0, [], [car(9, 6.0, -7.0)]).report
    in_right = watch(Lane.RIGHT, 7.0, [car(9, 6.0, 0.0)], []).report
    for report in (in_left, in_right):
        assert report.near_misses == 0 and report.min_gap_left_m == math.inf
        assert report.min_gap_oncoming_m == math.inf


def test_an_overlap_ahead_has_a_time_to_collision_of_zero() -> None:
    """A vehicle 4 m ahead (centre to centre) of a 4.5 m AV overlaps it: gap -0.5 m, time to collision 0, whatever
    the speeds."""
    report = watch(Lane.LEFT, 5.0, [car(10, 4.0, 9.0)], []).report
    assert report.min_gap_left_m == -0.5 and report.min_ttc_left_s == 0.0 and report.near_misses == 1


def test_a_contact_records_the_bumper_gap_and_a_time_to_collision_of_zero() -> None:
    monitor = SafetyMonitor()
    event = monitor.contact(car(11, 4.0, -7.0), Lane.RIGHT, Pose(0.0, RIGHT_Y_M, 0.0, 7.0), 1.0, 9.0,  # type: ignore[arg-type]
                            "drive", 12.0)
    assert event.kind == "contact" and event.gap_m == -0.5 and event.ttc_s == 0.0 and event.implied_gap_m == 12.0
    assert event.lane == "oncoming" and monitor.report.contacts == 1 and monitor.report.near_misses == 0
