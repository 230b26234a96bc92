"""The AV's own containment monitor at its boundaries (``sim.driver.monitor.Monitor.sense``): a reading is explained
while its interval, widened by the sensing error (its own), meets where a vehicle the decision knew can be (the
snapshot's reading widened by the sensing error, grown by its lane's speed bounds since, or, for a vehicle whose
speed was measured, by its own dynamics: braking at b_max to a standstill, speeding up at a_max); a reading just
beyond that is a breach the AV senses, of the kind its side names, one just inside is not.

Every boundary is computed here from the declarations (the world's bounds), not read back from the monitor.
"""

from __future__ import annotations

from dataclasses import replace

import pytest
from hypothesis import given
from hypothesis import strategies as st

from sim.driver.discretiser import discretise
from sim.driver.monitor import ROUNDING_M, BreachKind, Monitor, known_m
from sim.driver.readings import Reading
from spec.assumptions import world_bounds
from spec.dynamics import Dynamics
from spec.grid import PAPER_GRID
from spec.lanes import Lane
from spec.sound import Sound
from spec.tracking import VEHICLE_SPEED_CHANGE

BOUNDS = world_bounds("spread", "noisy")  # 4.9..9.1 m/s both lanes, sensing error 1.5 m
E_M = BOUNDS.sensing_error_m
READ_M = {Lane.LEFT: 40.0, Lane.RIGHT: 150.0}  # where the snapshot read each lane's vehicle, ahead of the AV
ELAPSED_S = 1.0
AV_MOVED_M = 7.0  # the AV's own travel since the snapshot: a later reading is ahead of it, not of the snapshot
NUDGE_M = 1e-3  # just inside or just beyond (the monitor's own slack is 1e-6 m)
#: Each vehicle's measured speed at the snapshot, along its direction of travel (m/s): each stops within the elapsed
#: time when it brakes at b_max (5 / 9 s, 5.5 / 9 s), neither reaches its lane's top speeding up (6 + 3 x 1 < 9.1).
MEASURED_MPS = {Lane.LEFT: (5.0, 6.0), Lane.RIGHT: (5.5, 6.0)}


def _monitor(measured: bool) -> Monitor:
    seen = tuple(Reading(lane, body, READ_M[lane], speed_mps=MEASURED_MPS[lane] if measured else None)
                 for lane, body in ((Lane.LEFT, 1), (Lane.RIGHT, 2)))
    scenario = replace(discretise(seen, Lane.LEFT, PAPER_GRID, measured=True), sound=Sound(BOUNDS))
    assert scenario.sound is not None
    assert (scenario.left_mps is not None) == measured
    return Monitor(0, scenario.sound, scenario, seen, PAPER_GRID, 0.0, 0.0)


def _edges_m(lane: Lane, measured: bool) -> tuple[float, float]:
    """The farthest a reading (road coordinates, the snapshot's frame) may lie behind and ahead and be explained: the
    vehicle's interval (its reading +- the error) grown by its lane's speeds, or by its own least and most travel
    (braking at b_max to a standstill, speeding up at a_max), then the reading's own error."""
    read, t = READ_M[lane], ELAPSED_S
    if measured:
        (v_low, v_high), a, b = MEASURED_MPS[lane], VEHICLE_SPEED_CHANGE.accel_mps2, VEHICLE_SPEED_CHANGE.brake_mps2
        least = v_low * v_low / (2 * b) if v_low / b <= t else v_low * t - b * t * t / 2
        most = v_high * t + a * t * t / 2
        assert v_high + a * t <= BOUNDS.speeds(lane).high_mps  # below its top all the while
    else:
        speeds = BOUNDS.speeds(lane)
        least, most = speeds.low_mps * t, speeds.high_mps * t
    if lane is Lane.LEFT:
        low, high = read - E_M + least, read + E_M + most
    else:
        low, high = read - E_M - most, read + E_M - least
    return low - E_M, high + E_M


def test_the_measured_bounds_are_the_declared_dynamics() -> None:
    d = Dynamics(MEASURED_MPS[Lane.LEFT], BOUNDS.same_mps.high_mps)
    assert d.travel_m(ELAPSED_S) == pytest.approx((25 / 18, 7.5))


@pytest.mark.parametrize("measured", [False, True], ids=["lane speeds", "measured speeds"])
@pytest.mark.parametrize("lane", list(Lane))
@pytest.mark.parametrize("side", ["behind", "ahead"])
@pytest.mark.parametrize("inside", [True, False])
def test_a_reading_just_beyond_its_allowance_is_a_sensed_breach_one_just_inside_is_not(
        lane: Lane, side: str, inside: bool, measured: bool) -> None:
    low, high = _edges_m(lane, measured)
    nudge = -NUDGE_M if inside else NUDGE_M
    x_m = low - nudge if side == "behind" else high + nudge
    breach = _monitor(measured).sense(ELAPSED_S, 0.0, AV_MOVED_M, (Reading(lane, 1, x_m - AV_MOVED_M),), "a test")
    if inside:
        assert breach is None
        return
    assert breach is not None and breach.sensed
    # behind its interval in the left lane is slower than its bounds; an oncoming vehicle nearer than its interval
    # (behind it in road coordinates) is faster
    slower = (side == "behind") == (lane is Lane.LEFT)
    assert breach.kind is (BreachKind.TOO_SLOW if slower else BreachKind.TOO_FAST)
    assert breach.by_m == pytest.approx(NUDGE_M, abs=1e-6)


@pytest.mark.parametrize("measured", [False, True], ids=["lane speeds", "measured speeds"])
@pytest.mark.parametrize("lane", list(Lane))
def test_a_reading_the_sets_explain_is_narrowed_to_what_it_and_the_sets_share(lane: Lane, measured: bool) -> None:
    """SPOT's refinement (``Monitor.refine``): a reading half its error inside the sets' near edge becomes the set from
    that edge to the reading's own far error, the sensing error held (``Sound.sensed_sets``); every other reading
    is its interval widened by the error. Computed from the same edges as the breach test above."""
    low, high = _edges_m(lane, measured)
    near, far = low + E_M, high - E_M  # the sets' own edges, without the reading's error
    x_m = near - E_M / 2  # its error reaches 1.5 E behind the near edge, 0.5 E beyond it
    other = Reading(Lane.RIGHT if lane is Lane.LEFT else Lane.LEFT, 3, 500.0 - AV_MOVED_M)
    refined = _monitor(measured).refine((Reading(lane, 1, x_m - AV_MOVED_M), other), ELAPSED_S, AV_MOVED_M)
    assert refined is not None
    (narrowed, widened) = refined
    assert narrowed.interval_m == pytest.approx((near - AV_MOVED_M, x_m + E_M - AV_MOVED_M))
    assert widened.interval_m == pytest.approx((500.0 - E_M - AV_MOVED_M, 500.0 + E_M - AV_MOVED_M))
    assert far > x_m + E_M  # the far edge is the reading's own


def test_readings_inside_the_sets_whole_or_that_meet_none_are_not_narrowed() -> None:
    """A reading whose error lies inside the sets gains nothing, and one that meets no set (a breach ``sense``
    reports) is left as read: the monitor narrows no snapshot then."""
    low, high = _edges_m(Lane.LEFT, False)
    monitor = _monitor(False)
    inside = Reading(Lane.LEFT, 1, (low + high) / 2 - AV_MOVED_M)
    beyond = Reading(Lane.LEFT, 1, high + 1.0 - AV_MOVED_M)
    assert monitor.refine((inside,), ELAPSED_S, AV_MOVED_M) is None
    assert monitor.refine((beyond,), ELAPSED_S, AV_MOVED_M) is None


@given(read=st.tuples(st.floats(-50, 50), st.floats(0, 3)), error_m=st.floats(0, 3),
       sets=st.lists(st.tuples(st.floats(-60, 60), st.floats(0, 20)), max_size=4), at=st.floats(0, 1))
def test_property_a_known_set_holds_every_place_the_reading_and_the_sets_both_allow(
        read: tuple[float, float], error_m: float, sets: list[tuple[float, float]], at: float) -> None:
    """``known_m``: every place within the reading's error that a set holds is in the known set, and the known set
    lies within the reading's error (so a plan from it is proved for every vehicle the assumptions allow, and never
    asks for more room than the reading alone)."""
    read_m = (read[0] - error_m, read[0] + read[1] + error_m)
    sets_m = [(lo, lo + width) for lo, width in sets]
    known = known_m(read_m, sets_m)
    shared = [(max(read_m[0], lo), min(read_m[1], hi)) for lo, hi in sets_m]
    shared = [(a, b) for a, b in shared if a <= b]
    if not shared:
        assert known is None or known[1] - known[0] <= ROUNDING_M
        return
    assert known is not None
    assert read_m[0] <= known[0] <= known[1] <= read_m[1]
    for a, b in shared:
        x = a + at * (b - a)
        assert known[0] <= x <= known[1]


def test_two_readings_that_meet_one_known_vehicles_set_are_neither_narrowed() -> None:
    """A vehicle the decision knew is one vehicle: a second reading meeting its set may be one hidden at that snapshot
    (an ``appeared`` breach the AV cannot tell), here 1 m beyond the set and read 1.4 m short. Narrowed into the set
    it would lose its truth; neither reading is narrowed, where the same reading alone would be."""
    low, high = _edges_m(Lane.LEFT, False)
    far = high - E_M  # the set's far edge, the reading's own error taken off
    hidden = Reading(Lane.LEFT, 2, far + 1.0 - 1.4 - AV_MOVED_M)
    known = Reading(Lane.LEFT, 1, low + E_M + 2.0 - AV_MOVED_M)
    monitor = _monitor(False)
    alone = monitor.refine((hidden,), ELAPSED_S, AV_MOVED_M)
    assert alone is not None and alone[0].interval_m[1] == pytest.approx(far - AV_MOVED_M)
    both = monitor.refine((known, hidden), ELAPSED_S, AV_MOVED_M)
    assert both is None or both[1].interval_m == pytest.approx((hidden.dx_m - E_M, hidden.dx_m + E_M))


def test_a_narrowed_decision_narrows_the_next_snapshot_against_what_it_read_not_against_its_own_sets() -> None:
    """A decision whose snapshot was narrowed (its sets hold the sensing error, ``Sound.sensed_sets``) watches those
    sets, but narrows the next snapshot against the vehicles as its snapshot read them (each within the error of its
    reading, grown since): a reading beyond the error bound narrows one decision's sets, never every later one's."""
    read = (Reading(Lane.LEFT, 1, READ_M[Lane.LEFT]),)
    narrowed = (Reading(Lane.LEFT, 1, READ_M[Lane.LEFT], (0.0, 0.5)),)
    sets = Sound(BOUNDS, sensed_sets=True)
    scenario = replace(discretise(narrowed, Lane.LEFT, PAPER_GRID, measured=True), sound=sets)
    monitor = Monitor(0, sets, scenario, narrowed, PAPER_GRID, 0.0, 0.0, read)
    low, _ = _edges_m(Lane.LEFT, False)
    near_m = READ_M[Lane.LEFT] + BOUNDS.same_mps.low_mps * ELAPSED_S  # the narrowed set's near edge now
    x_m = low + 1.5 * E_M  # its error reaches half an error behind the read set's near edge, into the narrowed set
    assert x_m - E_M < near_m < x_m + E_M
    assert monitor.sense(ELAPSED_S, 0.0, AV_MOVED_M, (Reading(Lane.LEFT, 1, x_m - AV_MOVED_M),), "a test") is None
    refined = monitor.refine((Reading(Lane.LEFT, 1, x_m - AV_MOVED_M),), ELAPSED_S, AV_MOVED_M)
    assert refined is not None and refined[0].interval_m[0] == pytest.approx(low + E_M - AV_MOVED_M)
    assert low + E_M < near_m
