"""The executor's speed reference, as spec/ states it: positions are its exact integral, and the ramps keep to the
car's limits; ``covered_s`` is when that integral first reaches a distance."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from spec.actions import ACTION_RULES, Action
from spec.grid import PAPER_GRID, Grid
from spec.motion import RAMP_SHARE, covered_s, plan_profiles
from spec.physical import CAR

PLANS = [(Action.ACCELERATE,), (Action.BRAKE, Action.ACCELERATE, Action.DRIVE),
         (Action.ACCELERATE, Action.RIGHT_LANE_CHANGE, Action.ACCELERATE, Action.LEFT_LANE_CHANGE, Action.BRAKE)]


@pytest.mark.parametrize(("plan", "start_mps", "grid"),
                         list(itertools.product(PLANS, [0.0, 7.0, 12.5], [PAPER_GRID, Grid(7)])))
def test_the_distance_is_the_exact_integral_of_the_reference_speed(plan: tuple[Action, ...], start_mps: float,
                                                                   grid: Grid) -> None:
    profiles = plan_profiles(plan, start_mps, grid)
    covered_m = 0.0
    for action, profile in zip(plan, profiles):
        duration_s = float(ACTION_RULES[action].duration_s)
        assert profile.distance_m(0.0) == pytest.approx(covered_m, abs=1e-6)
        t = np.linspace(0.0, duration_s, 60_001)
        speeds = np.array([profile.at(x) for x in t])
        covered_m += float(np.sum((speeds[1:] + speeds[:-1]) / 2 * np.diff(t)))  # trapezoids: exact up to 1e-6
        assert profile.distance_m(duration_s) == pytest.approx(covered_m, abs=1e-5)


def test_every_ramp_keeps_to_its_share_of_the_cars_limits() -> None:
    for profile in plan_profiles(PLANS[-1], 0.0, PAPER_GRID):
        for ramp in profile.ramps:
            limit = CAR.max_accel_mps2 if ramp.dv_mps > 0 else CAR.max_brake_mps2
            assert abs(ramp.dv_mps) / ramp.duration_s == pytest.approx(RAMP_SHARE * limit)


@given(st.floats(0.01, 30.0), st.floats(-10.0, 10.0), st.floats(-10.0, 10.0), st.floats(0.5, 8.0))
def test_covered_s_is_when_the_integral_of_the_relative_speed_first_reaches_the_distance(
        distance_m: float, from_mps: float, to_mps: float, rate_mps2: float) -> None:
    """The motion integrated by trapezoids on a 1 ms grid over 60 s (its speed exact at each step) first covers the
    distance within a step of ``covered_s``, or never when it says infinite."""
    dt_s = 1e-3
    t = np.arange(0.0, 60.0, dt_s)
    speed = np.minimum(from_mps + rate_mps2 * t, to_mps) if to_mps >= from_mps else np.maximum(
        from_mps - rate_mps2 * t, to_mps)
    travelled = np.concatenate(([0.0], np.cumsum((speed[1:] + speed[:-1]) / 2 * dt_s)))
    reached = np.flatnonzero(travelled >= distance_m)
    got_s = covered_s(distance_m, from_mps, to_mps, rate_mps2)
    if not reached.size:
        assert got_s == math.inf or got_s > 59.0
    else:
        assert got_s == pytest.approx(t[reached[0]], abs=2 * dt_s)
