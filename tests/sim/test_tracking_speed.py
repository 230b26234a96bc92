"""The tracker's speed intervals (``sim.tracking``, rules ``spec.tracking``): set-membership from range-rate readings.

Property: whenever every range-rate reading is within its error bound and the vehicle's speed changes within
``SpeedChange`` (any acceleration in [-b_max, a_max], switched at any instant, never below a standstill), the
vehicle's true speed is inside its track's interval on every sweep. Boundaries: a reading just inside its error bound
of the grown interval narrows it; one just beyond starts the interval again from the reading, flagged.
"""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from sim.tracking import Detection, Track, Tracker
from spec.assumptions import Bounds, SpeedBounds, speed_error_mps, world_bounds
from spec.errors import OptionError
from spec.lanes import Lane
from spec.tracking import UNKNOWN_SPEED, VEHICLE_SPEED_CHANGE, SpeedChange, grown_speed_mps, read_speed_mps

A, B = VEHICLE_SPEED_CHANGE.accel_mps2, VEHICLE_SPEED_CHANGE.brake_mps2
DT_S = 0.1  # one sweep (spec.physical.SENSORS.sweep_hz)
E_MPS = speed_error_mps("noisy")
#: wide enough lane bounds that the position gates never lose the vehicle (this file is about its speed)
WIDE = Bounds("wide", SpeedBounds(0.0, 40.0), SpeedBounds(0.0, 40.0), 0.5, True, "the speed tests' lanes")
NUDGE_MPS = 1e-3  # just inside or just beyond a bound (the tracker's own slack is 1e-6 m/s)


def _only(tracker: Tracker) -> Track:
    (track,) = tracker.tracks
    return track


def _rate(lane: Lane, speed_mps: float, av_speed_mps: float) -> float:
    """How fast a vehicle of ``lane`` at ``speed_mps`` gets farther from the AV (a left-lane vehicle drives the AV's
    way, an oncoming one the other)."""
    return (speed_mps if lane is Lane.LEFT else -speed_mps) - av_speed_mps


@st.composite
def motions(draw: st.DrawFn) -> tuple[Lane, float, list[list[float]], list[float], list[float]]:
    """A vehicle's lane and start speed, each sweep's accelerations (a few pieces of equal length, each within the
    bounds, so that switches fall anywhere), the AV's speed per sweep and each reading's error (within its bound,
    its ends included)."""
    sweeps = draw(st.integers(2, 25))  # within 2.5 s the vehicle stays within its sensor's range
    accel = st.one_of(st.sampled_from([-B, A, 0.0]), st.floats(-B, A))
    pieces = draw(st.lists(st.lists(accel, min_size=1, max_size=4), min_size=sweeps, max_size=sweeps))
    errors = draw(st.lists(st.one_of(st.sampled_from([-E_MPS, E_MPS]), st.floats(-E_MPS, E_MPS)),
                           min_size=sweeps, max_size=sweeps))
    avs = draw(st.lists(st.floats(0.0, 12.0), min_size=sweeps, max_size=sweeps))
    return draw(st.sampled_from(list(Lane))), draw(st.floats(0.0, 15.0)), pieces, avs, errors


@given(motions())
def test_the_true_speed_never_leaves_its_interval_inside_the_bounds(
        motion: tuple[Lane, float, list[list[float]], list[float], list[float]]) -> None:
    lane, speed, pieces, avs, errors = motion
    tracker = Tracker(WIDE, speed_error_mps=E_MPS)
    x_m = 40.0 if lane is Lane.LEFT else 200.0
    av_x_m = 0.0
    for sweep, (accels, av_mps, error) in enumerate(zip(pieces, avs, errors, strict=True)):
        if sweep:
            for accel in accels:  # the sweep's time in equal pieces, each at its own acceleration
                h = DT_S / len(accels)
                after = max(0.0, speed + accel * h)
                stop_s = h if after > 0 or accel >= 0 else speed / -accel
                travel = speed * stop_s + accel * stop_s * stop_s / 2
                x_m += travel if lane is Lane.LEFT else -travel
                speed = after
            av_x_m += av_mps * DT_S
        tracker.update(sweep * DT_S, av_x_m, av_mps,
                       [Detection(lane, x_m - av_x_m, _rate(lane, speed, av_mps) + error)])
        track = _only(tracker)
        lo, hi = track.speed_mps
        assert lo - 1e-6 <= speed <= hi + 1e-6, (sweep, speed, track.speed_mps)
        assert not track.speed_broke


def _read_then(lane: Lane, first_mps: float, then_mps: float) -> Track:
    """A track read at ``first_mps`` (an exact reading, the AV standing) and a sweep later at ``then_mps``, readings
    within ``E_MPS``."""
    tracker = Tracker(WIDE, speed_error_mps=E_MPS)
    x_m = 80.0 if lane is Lane.LEFT else 200.0
    tracker.update(0.0, 0.0, 0.0, [Detection(lane, x_m, _rate(lane, first_mps, 0.0))])
    travel = first_mps * DT_S
    tracker.update(DT_S, 0.0, 0.0, [Detection(lane, x_m + (travel if lane is Lane.LEFT else -travel),
                                              _rate(lane, then_mps, 0.0))])
    return _only(tracker)


@pytest.mark.parametrize("lane", list(Lane))
@pytest.mark.parametrize(("side", "inside"), [("slower", True), ("slower", False), ("faster", True),
                                              ("faster", False)])
def test_a_reading_within_its_bound_of_the_grown_interval_narrows_it_one_beyond_starts_again(
        lane: Lane, side: str, inside: bool) -> None:
    """The first reading allows 8 +- E; a sweep later that has grown to 8 - E - b dt .. 8 + E + a dt; a reading is
    allowed E either side of it, so one just inside that reach narrows the interval to its edge, one just beyond
    shares no speed with it."""
    edge = 8.0 - E_MPS - B * DT_S - E_MPS if side == "slower" else 8.0 + E_MPS + A * DT_S + E_MPS
    nudge = NUDGE_MPS if inside else -NUDGE_MPS
    read = edge + nudge if side == "slower" else edge - nudge
    track = _read_then(lane, 8.0, read)
    assert track.speed_broke is not inside
    lo, hi = track.speed_mps
    if inside:
        assert hi - lo == pytest.approx(NUDGE_MPS, abs=1e-5)
    else:
        assert (lo, hi) == pytest.approx((read - E_MPS, read + E_MPS), abs=1e-5)


def test_a_speed_interval_never_goes_below_a_standstill() -> None:
    assert grown_speed_mps((0.5, 1.0), 1.0) == (0.0, 1.0 + A)
    assert read_speed_mps(Lane.LEFT, -5.0, 5.0, 1.0) == (0.0, 1.0)  # standing, read exactly
    lo, hi = read_speed_mps(Lane.RIGHT, 3.0, 0.0, 1.0)  # an oncoming vehicle read driving backwards at 3 m/s
    assert hi < lo


def test_a_vehicle_read_driving_backwards_breaks_its_bounds_and_is_taken_as_standing() -> None:
    track = _read_then(Lane.LEFT, 1.0, -1.0 - E_MPS - 1.0)
    assert track.speed_broke and track.speed_mps == (0.0, 0.0)


def test_without_a_range_rate_a_track_knows_nothing_of_its_speed() -> None:
    tracker = Tracker(world_bounds("spread", "noisy"), speed_error_mps=E_MPS)
    tracker.update(0.0, 0.0, 0.0, [Detection(Lane.LEFT, 50.0)])
    tracker.update(DT_S, 0.0, 0.0, [Detection(Lane.LEFT, 50.7)])
    assert _only(tracker).speed_mps == UNKNOWN_SPEED


@pytest.mark.parametrize(("accel", "brake"), [(0.0, 9.0), (3.0, -1.0), (float("nan"), 9.0)])
def test_an_acceleration_bound_of_zero_or_below_is_bad_input(accel: float, brake: float) -> None:
    with pytest.raises(OptionError, match="mps2"):
        SpeedChange(accel, brake, "a test")
