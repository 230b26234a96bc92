"""The fallback's closing speed on the vehicle ahead: fitted over the stated number of sweeps, whose rule gives the
speed error it claims under the noisy sensor's range noise."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from spec.envelope import TRACKING, closing_fit_sweeps, fitted_closing_mps, own_motion_closing_mps
from spec.physical import NOISE, SENSORS


def test_the_window_is_the_fewest_sweeps_whose_fitted_speed_error_is_within_the_executors() -> None:
    n = closing_fit_sweeps()
    sd = NOISE.range_sd_m * SENSORS.sweep_hz / math.sqrt(n * (n * n - 1) / 12)
    fewer = NOISE.range_sd_m * SENSORS.sweep_hz / math.sqrt((n - 1) * ((n - 1) ** 2 - 1) / 12)
    assert sd <= TRACKING.speed_mps < fewer
    assert closing_fit_sweeps(range_sd_m=0.0) == 2


def test_the_fitted_speed_errs_by_the_stated_sd_under_the_noisy_sensors_range_noise() -> None:
    """Measured, not assumed: 4,000 seeded windows of a vehicle closing at 4 m/s (seed 2026)."""
    rng = np.random.default_rng(2026)
    n = closing_fit_sweeps()
    truth = 40.0 - 4.0 * np.arange(n) / SENSORS.sweep_hz
    fits = [fitted_closing_mps(tuple(truth + rng.normal(0.0, NOISE.range_sd_m, n))) for _ in range(4000)]
    errors = np.array(fits, dtype=float) - 4.0
    assert abs(errors.mean()) < 0.1 and np.std(errors) <= TRACKING.speed_mps * 1.05


@given(st.floats(-20.0, 20.0), st.floats(1.0, 200.0), st.integers(3, 12))
def test_a_vehicle_at_a_constant_closing_speed_is_fitted_exactly(closing_mps: float, start_m: float,
                                                                 sweeps: int) -> None:
    distances = tuple(start_m - closing_mps * i / SENSORS.sweep_hz for i in range(sweeps))
    assert fitted_closing_mps(distances) == pytest.approx(closing_mps, abs=1e-9)


def test_fewer_than_three_distances_measure_nothing() -> None:
    assert fitted_closing_mps(()) is None and fitted_closing_mps((5.0, 4.0)) is None


def _speeding_up(accel_mps2: float, start_mps: float, other_mps: float, gap_m: float, behind: bool,
                 sweeps: int) -> tuple[tuple[float, ...], tuple[float, ...], float]:
    """Distances to a vehicle at ``other_mps`` (ahead, or behind) and the AV's odometer at ``sweeps`` sweeps while
    the AV speeds up from ``start_mps`` at ``accel_mps2``; and the AV's speed at the last sweep."""
    times = [i / SENSORS.sweep_hz for i in range(sweeps)]
    av = [start_mps * t + accel_mps2 * t * t / 2 for t in times]
    other = [(-gap_m if behind else gap_m) + other_mps * t for t in times]
    distances = tuple((a - o) if behind else (o - a) for a, o in zip(av, other, strict=True))
    return distances, tuple(av), start_mps + accel_mps2 * times[-1]


@given(st.floats(-3.0, 3.0), st.floats(0.0, 20.0), st.floats(0.0, 20.0), st.floats(5.0, 100.0), st.booleans(),
       st.integers(3, 12))
def test_the_closing_speed_with_the_avs_own_motion_taken_out_is_exact_at_the_last_sweep_while_the_av_changes_speed(
        accel_mps2: float, start_mps: float, other_mps: float, gap_m: float, behind: bool, sweeps: int) -> None:
    distances, travelled, av_mps = _speeding_up(accel_mps2, start_mps, other_mps, gap_m, behind, sweeps)
    closing = (other_mps - av_mps) if behind else (av_mps - other_mps)
    assert own_motion_closing_mps(distances, travelled, av_mps, behind) == pytest.approx(closing, abs=1e-6)


def test_the_distances_own_fit_lags_an_av_that_speeds_up_by_half_its_window_times_the_acceleration() -> None:
    """Seed 48 of the reliability campaign at c2c5ab8: returning from the oncoming lane at 9.8 m/s behind a vehicle
    at 7.0 m/s after speeding up at about 2.7 m/s2, the distances' fit said 2.2 m/s closing, not 2.8."""
    n = closing_fit_sweeps()
    distances, travelled, av_mps = _speeding_up(2.7, 8.5, 7.0, 15.0, False, n)
    lag_mps = 2.7 * (n - 1) / SENSORS.sweep_hz / 2
    plain = fitted_closing_mps(distances)
    assert plain == pytest.approx(av_mps - 7.0 - lag_mps, abs=1e-6)
    assert own_motion_closing_mps(distances, travelled, av_mps) == pytest.approx(av_mps - 7.0, abs=1e-6)
