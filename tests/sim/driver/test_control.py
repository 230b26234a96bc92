"""The controller's law (``sim.driver.control``) at each of its terms and limits, from constructed car states: no
physics engine."""

from __future__ import annotations

import math

import pytest

from sim.driver.control import (
    K_VY,
    K_X,
    K_Y,
    MAX_SPEED_FACTOR,
    MIN_HEADING_COS,
    CarState,
    Command,
    Steps,
    control_law,
    cosine_move,
    held_reference,
    perform,
    resumed,
)
from spec.actions import ACTION_RULES, Action
from spec.envelope import TRACKING
from spec.motion import Ramp, SpeedProfile
from spec.physical import CAR

COMMON, DT = 7.0, 1 / 15


def steady(x_m: float = 0.0, y_m: float = 0.0, yaw_rad: float = 0.0, speed_mps: float = COMMON,
           before_mps: float | None = None) -> CarState:
    return CarState(x_m, y_m, yaw_rad, speed_mps, speed_mps if before_mps is None else before_mps)


def law(car: CarState, x_ref_m: float = 0.0, speed_mps: float = COMMON, y_ref_m: float = 0.0,
        vy_ref_mps: float = 0.0, offset_rad: float = 0.0) -> tuple[float, float]:
    return control_law(car, x_ref_m, speed_mps, y_ref_m, vy_ref_mps, DT, COMMON, CAR.wheelbase_m, offset_rad)


def test_a_car_on_its_references_is_commanded_its_reference_speed_straight_ahead() -> None:
    assert law(steady()) == (COMMON, 0.0)


def test_each_metre_behind_the_position_reference_adds_the_gain_to_the_speed_command() -> None:
    assert law(steady(x_m=-2.0))[0] == pytest.approx(COMMON + 2 * K_X)
    assert law(steady(x_m=1.0))[0] == pytest.approx(COMMON - K_X)


@pytest.mark.parametrize("yaw_deg", [20.0, -35.0, 59.0])
def test_a_car_turned_sideways_is_commanded_faster_along_its_heading_to_keep_its_speed_along_the_road(
        yaw_deg: float) -> None:
    yaw = math.radians(yaw_deg)
    assert law(steady(yaw_rad=yaw))[0] == pytest.approx(COMMON / math.cos(yaw))


def test_the_headings_correction_is_at_most_the_stated_factor() -> None:
    assert law(steady(yaw_rad=math.radians(80.0)))[0] == pytest.approx(COMMON / MIN_HEADING_COS)


def test_the_speed_command_stays_between_a_standstill_and_the_stated_top() -> None:
    assert law(steady(x_m=-100.0))[0] == MAX_SPEED_FACTOR * COMMON
    assert law(steady(x_m=100.0))[0] == 0.0


def test_a_car_off_its_lateral_reference_steers_towards_it_by_the_pd_law() -> None:
    v = COMMON
    _, steer = law(steady(y_m=-0.5))  # right of the reference, heading straight: turn left
    assert steer == pytest.approx(math.atan(CAR.wheelbase_m * K_Y * 0.5 / (v * v)))
    _, steer = law(steady(), vy_ref_mps=1.0)  # the reference moves left at 1 m/s
    assert steer == pytest.approx(math.atan(CAR.wheelbase_m * K_VY * 1.0 / (v * v)))


def test_a_turned_car_speeding_up_asks_for_less_turn_by_the_sideways_part_of_its_speeding_up() -> None:
    yaw = math.radians(30.0)
    _, even = law(steady(yaw_rad=yaw, speed_mps=8.0, before_mps=8.0), y_ref_m=2.0)
    _, faster = law(steady(yaw_rad=yaw, speed_mps=8.0, before_mps=7.0), y_ref_m=2.0)
    speeding_up = 1.0 / DT
    assert math.tan(even) - math.tan(faster) == pytest.approx(CAR.wheelbase_m * speeding_up * math.sin(yaw) / 64)


def test_a_slow_car_steers_as_one_at_a_metre_per_second() -> None:
    assert law(steady(y_m=-0.5, speed_mps=0.2))[1] == law(steady(y_m=-0.5, speed_mps=1.0))[1]


def test_a_steering_fault_adds_its_offset_to_every_command() -> None:
    assert law(steady(y_m=-0.5), offset_rad=0.3)[1] == pytest.approx(law(steady(y_m=-0.5))[1] + 0.3)


def test_the_sideways_move_is_a_cosine_from_lane_to_lane_at_rest_at_both_ends() -> None:
    assert cosine_move(0.0, -3.5, 0.0, 2.0) == (0.0, 0.0)
    y, vy = cosine_move(0.0, -3.5, 1.0, 2.0)
    assert y == pytest.approx(-3.5) and vy == pytest.approx(0.0, abs=1e-12)
    y, vy = cosine_move(0.0, -3.5, 0.5, 2.0)
    assert y == pytest.approx(-1.75) and vy == pytest.approx(-3.5 * math.pi / 4)  # fastest half-way


def test_a_proved_action_resumed_on_time_starts_at_its_own_start() -> None:
    profile = SpeedProfile(COMMON, ())
    assert resumed(Action.DRIVE, profile, 10.0, 5.0, 10.0, DT) == (0.0, 5.0)


def test_a_proved_action_resumed_late_goes_on_from_where_its_reference_is_now_on_its_own_clock() -> None:
    profile = SpeedProfile(COMMON, (Ramp(0.0, 2.0, 3.0),))
    skip_s, x_ref_m = resumed(Action.DRIVE, profile, 10.0, 5.0, 10.0 + 3 * DT + 0.01, DT)
    assert skip_s == pytest.approx(3 * DT)  # whole control steps
    assert x_ref_m == pytest.approx(5.0 + profile.distance_m(3 * DT))


def test_a_proved_action_resumed_after_its_end_still_runs_its_last_control_step() -> None:
    duration_s = float(ACTION_RULES[Action.DRIVE].duration_s)
    skip_s, _ = resumed(Action.DRIVE, SpeedProfile(COMMON, ()), 10.0, 5.0, 10.0 + 2 * duration_s, DT)
    assert skip_s == pytest.approx(duration_s - DT)


def test_driving_on_in_lane_keeps_the_position_reference_while_the_car_is_within_its_envelope_of_it() -> None:
    assert held_reference(10.0 + TRACKING.position_m, 10.0) == 10.0 + TRACKING.position_m
    assert held_reference(10.0 - TRACKING.position_m, 10.0) == 10.0 - TRACKING.position_m
    assert held_reference(10.0 + TRACKING.position_m + 0.01, 10.0) == 10.0  # beyond it: restarted at the car


def three_steps(log: list[str]) -> Steps:
    try:
        for k in range(3):
            if not (yield float(k), 0.0, 0.0):
                return False
        return True
    finally:
        log.append("closed")


def test_performing_steps_applies_each_once_and_tells_it_whether_the_world_went_on() -> None:
    applied: list[Command] = []
    log: list[str] = []
    assert perform(three_steps(log), lambda c: applied.append(c) is None) is True
    assert applied == [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (2.0, 0.0, 0.0)] and log == ["closed"]
    applied.clear()
    assert perform(three_steps(log), lambda c: applied.append(c) is None and c[0] < 1.0) is False
    assert len(applied) == 2  # the step the world did not go on after is the last


def test_steps_the_world_fails_under_are_closed_before_the_error_goes_on() -> None:
    log: list[str] = []

    def broken(_command: Command) -> bool:
        raise RuntimeError("the world")

    with pytest.raises(RuntimeError):
        perform(three_steps(log), broken)
    assert log == ["closed"]  # its ``finally`` ran while the world was still there
