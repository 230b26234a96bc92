"""Each gate of the tracker at its boundary (``sim.tracking``, rules ``spec.tracking``): a reading just inside a gate
is what the gate says, one just beyond it is not. The gates, for one vehicle sensed once and read again a sweep
later, its interval grown by its lane's speed bounds (``spec.sound.reach_m``):

- **inside**: within the grown interval widened by the sensing error: that vehicle, seen (its interval narrowed);
- **beyond**: past that by at most what one sweep adds to a vehicle breaking its bounds (behind: a vehicle that
  stopped loses its lane's slowest speed times the sweep; ahead: one sweep at the car's acceleration limit past the
  top speed, ``a x dt^2``): that vehicle, followed and flagged;
- farther: not that vehicle: a new reading, explained as **entering** within one sweep's travel (the AV's and the
  lane's fastest, plus the sensing error) of a sensor's range edge, else an appearance, held.

Every boundary is computed here from the declarations (the bounds, ``spec.physical.CAR``, ``SENSORS``), not read
back from the tracker."""

from __future__ import annotations

import pytest

from sim.tracking import Detection, Tracker
from spec.assumptions import world_bounds
from spec.lanes import Lane
from spec.physical import CAR, SENSORS
from spec.tracking import Explained, TrackState

BOUNDS = world_bounds("spread", "noisy")  # speeds 4.9..9.1 m/s in both lanes, sensing error 1.5 m
E_M = BOUNDS.sensing_error_m
DT_S = 0.1  # one sweep
NUDGE_M = 1e-3  # just inside or just beyond a boundary (the gates' own slack is 1e-6 m)
READ_M = {Lane.LEFT: 60.0, Lane.RIGHT: 150.0}  # where the vehicle is read first, ahead of the AV standing at 0


def _after_a_sweep(lane: Lane, x_m: float) -> Tracker:
    """A tracker that read one vehicle of ``lane`` at ``READ_M`` on its first sweep and reads it at ``x_m`` (road
    coordinates, the AV standing at 0) on the next."""
    tracker = Tracker(BOUNDS)
    tracker.update(0.0, 0.0, 0.0, [Detection(lane, READ_M[lane])])
    tracker.update(DT_S, 0.0, 0.0, [Detection(lane, x_m)])
    return tracker


def _grown(lane: Lane) -> tuple[float, float]:
    """The vehicle's interval a sweep after it was read: the reading +- the sensing error, grown by the lane's speed
    bounds (a same-direction vehicle forwards, an oncoming one backwards)."""
    speeds = BOUNDS.speeds(lane)
    lo, hi = READ_M[lane] - E_M, READ_M[lane] + E_M
    if lane is Lane.LEFT:
        return lo + speeds.low_mps * DT_S, hi + speeds.high_mps * DT_S
    return lo - speeds.high_mps * DT_S, hi - speeds.low_mps * DT_S


def _beyond_m(lane: Lane) -> tuple[float, float]:
    """How far past the inside gate (behind, ahead in road coordinates) the beyond gate reaches: a vehicle that
    stopped falls behind its interval's slowest end by the lane's slowest speed times the sweep; one at the car's
    acceleration limit gets ahead of its fastest end by ``a x dt^2``. An oncoming vehicle moves backwards."""
    stopped_m, accelerating_m = BOUNDS.speeds(lane).low_mps * DT_S, CAR.max_accel_mps2 * DT_S * DT_S
    return (stopped_m, accelerating_m) if lane is Lane.LEFT else (accelerating_m, stopped_m)


def _gate_of(tracker: Tracker) -> str:
    """What the second sweep made of the reading: the first vehicle seen, or followed beyond its bounds, or a new
    track (the first one then missing where a sensor sees)."""
    first, *others = tracker.tracks
    if first.state is TrackState.SEEN:
        return "inside"
    if first.state is TrackState.BROKE_BOUNDS:
        return "beyond"
    assert first.state is TrackState.MISSING and len(others) == 1, tracker.tracks
    return f"new: {others[0].born.value}"


@pytest.mark.parametrize("lane", list(Lane))
def test_a_reading_just_inside_its_vehicles_interval_is_that_vehicle_seen_and_just_beyond_it_is_flagged(
        lane: Lane) -> None:
    lo, hi = _grown(lane)
    for x_m, gate in ((lo - E_M + NUDGE_M, "inside"), (hi + E_M - NUDGE_M, "inside"),
                      (lo - E_M - NUDGE_M, "beyond"), (hi + E_M + NUDGE_M, "beyond")):
        assert _gate_of(_after_a_sweep(lane, x_m)) == gate, (lane, x_m, gate)
    seen = _after_a_sweep(lane, hi + E_M - NUDGE_M).tracks[0]
    assert seen.lo_m == pytest.approx(hi - NUDGE_M) and seen.hi_m == pytest.approx(hi)  # narrowed to the reading


@pytest.mark.parametrize("lane", list(Lane))
def test_a_reading_just_within_a_sweeps_bound_breaking_is_that_vehicle_and_just_past_it_is_another(
        lane: Lane) -> None:
    """The beyond gate at both ends: a vehicle that stopped (behind), one at the car's acceleration limit (ahead).
    Past it the reading is another vehicle (so close behind the first one's last place that it counts as having come
    out from behind it: ``Explained.UNHIDDEN``), and the first one is missing."""
    lo, hi = _grown(lane)
    behind_m, ahead_m = _beyond_m(lane)
    for x_m, gate in ((lo - E_M - behind_m + NUDGE_M, "beyond"), (hi + E_M + ahead_m - NUDGE_M, "beyond"),
                      (lo - E_M - behind_m - NUDGE_M, "new"), (hi + E_M + ahead_m + NUDGE_M, "new")):
        assert _gate_of(_after_a_sweep(lane, x_m)).split(":")[0] == gate, (lane, x_m, gate)


def _new_reading(lane: Lane, x_m: float, av_mps: float) -> Explained:
    """How the tracker explains a vehicle read at ``x_m`` on its second sweep, none before (the AV at ``av_mps``)."""
    tracker = Tracker(BOUNDS)
    tracker.update(0.0, 0.0, av_mps, [])
    tracker.update(DT_S, 0.0, av_mps, [Detection(lane, x_m)])
    (track,) = tracker.tracks
    return track.born


@pytest.mark.parametrize("lane", list(Lane))
def test_a_new_reading_within_one_sweeps_travel_of_the_range_edge_entered_and_just_farther_inside_appeared(
        lane: Lane) -> None:
    av_mps = 8.0
    travel_m = (av_mps + BOUNDS.speeds(lane).high_mps) * DT_S + E_M
    edge_m = SENSORS.left_range_m if lane is Lane.LEFT else SENSORS.right_range_m
    assert _new_reading(lane, edge_m - travel_m + NUDGE_M, av_mps) is Explained.ENTERED
    assert _new_reading(lane, edge_m - travel_m - NUDGE_M, av_mps) is Explained.APPEARED
    if lane is Lane.RIGHT:  # the oncoming lane's other edge: the side sensor's, behind the AV
        behind_m = -SENSORS.side_range_m
        assert _new_reading(lane, behind_m + travel_m - NUDGE_M, av_mps) is Explained.ENTERED
        assert _new_reading(lane, behind_m + travel_m + NUDGE_M, av_mps) is Explained.APPEARED
