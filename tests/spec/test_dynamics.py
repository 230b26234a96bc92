"""A measured vehicle's dynamics (``spec.dynamics``): every motion within its speed interval and acceleration bounds
stays inside its travel and speed bounds, the bounds are reached (braking to a standstill, speeding up to its top),
and bad values are refused."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from spec.actions import Action
from spec.dynamics import Dynamics, passing_windows_s
from spec.errors import OptionError
from spec.lanes import Lane
from spec.tracking import SpeedChange

CHANGE = SpeedChange(3.0, 9.0, "test")


@st.composite
def driven(draw: st.DrawFn) -> tuple[Dynamics, float, list[tuple[float, float]]]:
    """A vehicle's dynamics, a start speed inside its interval and a schedule of (duration, acceleration) within the
    bounds: braking at b_max, speeding up at a_max, anything between, at any instant."""
    low = draw(st.floats(0.0, 12.0))
    high = low + draw(st.floats(0.0, 4.0))
    top = draw(st.floats(0.5, 15.0))
    start = draw(st.floats(low, high))
    accel = st.one_of(st.sampled_from((-CHANGE.brake_mps2, CHANGE.accel_mps2, 0.0)),
                      st.floats(-CHANGE.brake_mps2, CHANGE.accel_mps2))
    schedule = draw(st.lists(st.tuples(st.floats(0.01, 3.0), accel), min_size=1, max_size=6))
    return Dynamics((low, high), top, CHANGE), start, schedule


@given(driven())
def test_every_motion_within_the_bounds_stays_inside_its_travel_and_speed_bounds(
        drawn: tuple[Dynamics, float, list[tuple[float, float]]]) -> None:
    dynamics, speed, schedule = drawn
    _drive_inside(dynamics, dynamics, speed, schedule, math.inf)


def _drive_inside(dynamics: Dynamics, bounds: Dynamics, speed: float, schedule: list[tuple[float, float]],
                  hold_s: float) -> None:
    """Drive ``schedule`` from ``speed`` within ``dynamics``' bounds (never backwards, never above its top, never
    above its speed at ``hold_s`` from then on) and assert every instant inside ``bounds``' travel and speeds."""
    top = dynamics.highest_mps
    t, travel, dt, cap = 0.0, 0.0, 0.005, math.inf
    for duration, accel in schedule:
        end = t + duration
        while t < end - 1e-12:
            h = min(dt, end - t, hold_s - t if t < hold_s else math.inf)
            if t >= hold_s:
                cap = min(cap, speed)
            new = min(max(speed + accel * h, 0.0), max(top, speed), cap)
            travel += (speed + new) / 2 * h  # exact: the speed is linear within a step that does not clip
            speed, t = new, t + h
            least, most = bounds.travel_m(t)
            slow, fast = bounds.speeds_mps(t)
            assert least - 1e-6 <= travel <= most + 1e-6, (t, travel, least, most)
            assert slow - 1e-9 <= speed <= fast + 1e-9, (t, speed, slow, fast)


def test_the_bounds_are_braking_to_a_standstill_and_speeding_up_to_the_top() -> None:
    d = Dynamics((6.0, 8.0), 10.0, CHANGE)
    assert d.travel_m(0.0) == (0.0, 0.0)
    stop_s = 6.0 / 9.0
    assert d.speeds_mps(stop_s / 2) == pytest.approx((3.0, 8.0 + 3.0 * stop_s / 2))
    assert d.travel_m(5.0)[0] == pytest.approx(6.0 * 6.0 / 18.0)  # stood since 2/3 s
    assert d.speeds_mps(5.0) == (0.0, 10.0)
    top_s = 2.0 / 3.0
    assert d.travel_m(5.0)[1] == pytest.approx(9.0 * top_s + 10.0 * (5.0 - top_s))
    standing = Dynamics((0.0, 0.0), 10.0, CHANGE)
    assert standing.travel_m(100.0)[0] == 0.0 and standing.speeds_mps(1.0) == (0.0, 3.0)
    above = Dynamics((12.0, 12.5), 10.0, CHANGE)  # measured above its lane's top: it may keep that speed
    assert above.highest_mps == 12.5 and above.travel_m(2.0)[1] == pytest.approx(25.0)


@given(driven(), st.floats(0.0, 6.0))
def test_a_motion_that_stops_speeding_up_at_the_hold_stays_inside_the_held_bounds(
        drawn: tuple[Dynamics, float, list[tuple[float, float]]], hold_s: float) -> None:
    """``held_from``: every motion within the bounds that does not speed up after ``hold_s`` (its speed never above
    what it was then) stays inside the held travel and speeds."""
    dynamics, speed, schedule = drawn
    _drive_inside(dynamics, dynamics.held_from(hold_s), speed, schedule, hold_s)


def test_held_from_speeds_up_until_the_hold_and_keeps_that_speed() -> None:
    d = Dynamics((6.0, 8.0), 10.0, CHANGE)
    held = d.held_from(0.5)
    assert held.speeds_mps(0.25)[1] == pytest.approx(8.75) and held.speeds_mps(3.0)[1] == pytest.approx(9.5)
    assert held.travel_m(3.0)[1] == pytest.approx(8.0 * 0.5 + 3.0 * 0.5 * 0.5 / 2 + 9.5 * 2.5)
    assert held.travel_m(3.0)[0] == d.travel_m(3.0)[0]  # braking is unchanged
    assert d.held_from(0.0).travel_m(2.0)[1] == 16.0 and d.held_from(5.0).travel_m(2.0) == d.travel_m(2.0)
    assert d.held_from(1.0).held_from(2.0).hold_from_s == 1.0  # the earliest hold holds


@pytest.mark.parametrize(("lane", "plan", "windows"), [
    (Lane.LEFT, (Action.DRIVE,), ()),
    (Lane.LEFT, (Action.DRIVE, Action.RIGHT_LANE_CHANGE, Action.ACCELERATE, Action.LEFT_LANE_CHANGE), ((3.0, 12.0),)),
    (Lane.LEFT, (Action.RIGHT_LANE_CHANGE, Action.ACCELERATE), ((0.0, math.inf),)),
    (Lane.RIGHT, (Action.ACCELERATE, Action.LEFT_LANE_CHANGE, Action.RIGHT_LANE_CHANGE), ((0.0, 6.0), (6.0, math.inf))),
    (Lane.RIGHT, (), ((0.0, math.inf),)),
])
def test_the_passing_windows_run_from_the_move_out_to_the_end_of_the_move_back(
        lane: Lane, plan: tuple[Action, ...], windows: tuple[tuple[float, float], ...]) -> None:
    assert passing_windows_s(lane, plan) == windows


def test_a_snapshot_aged_widens_the_speed_interval_by_the_change_it_allows() -> None:
    aged = Dynamics((6.0, 8.0), 10.0, CHANGE).aged(0.1)
    assert aged.speed_mps == pytest.approx((6.0 - 0.9, 8.0 + 0.3))


@pytest.mark.parametrize(("speed", "top", "reason"), [
    ((-0.1, 2.0), 10.0, "0 <= low <= high"),
    ((3.0, 2.0), 10.0, "0 <= low <= high"),
    ((math.nan, 2.0), 10.0, "finite"),
    ((1.0, math.inf), 10.0, "finite"),
    ((1.0, 2.0), 0.0, "above 0"),
])
def test_a_bad_speed_interval_or_top_speed_is_refused(speed: tuple[float, float], top: float, reason: str) -> None:
    with pytest.raises(OptionError, match=reason):
        Dynamics(speed, top, CHANGE)
