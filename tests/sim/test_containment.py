"""Containment: a vehicle moving within its lane's bounds never breaches, one outside them does, with the bound it
broke; unknown vehicles only where no phantom could be and only once sensed; followers too close; the AV's envelope."""

from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace

import pytest
from hypothesis import given
from hypothesis import strategies as st

from sim.containment import Containment, ContainmentReport
from sim.driver.monitor import BreachKind, Sighting
from sim.driver.readings import Reading
from sim.vehicle import Pose
from spec.assumptions import world_bounds
from spec.envelope import TRACKING
from spec.grid import PAPER_GRID
from spec.lanes import Lane
from spec.physical import CAR, SENSORS
from spec.scenario import make_scenario
from spec.sound import Sound, reach_m

BOUNDS = world_bounds("spread", "exact")  # 4.9 .. 9.1 m/s both lanes, no sensing error
SOUND = Sound(BOUNDS)
AV = Pose(0.0, 1.8, 0.0, 7.0)


def car(body: int, x_m: float, velocity_mps: float = 7.0, respawns: int = 0) -> SimpleNamespace:
    return SimpleNamespace(body=body, x_m=x_m, velocity_mps=velocity_mps, respawns=respawns)


def watch(left: dict[int, float], oncoming: dict[int, float], sound: Sound = SOUND) -> Containment:
    """Containment of a decision made from readings of ``left`` and ``oncoming`` (body -> metres ahead) at t = 0."""
    readings = tuple(Reading(Lane.LEFT, b, dx) for b, dx in left.items()) + tuple(
        Reading(Lane.RIGHT, b, dx) for b, dx in oncoming.items())
    from sim.driver.discretiser import discretise

    scenario = discretise(readings, Lane.LEFT, PAPER_GRID, measured=True)  # as the simulator watches
    cars = [car(b, dx) for b, dx in (left | oncoming).items()]
    return Containment(1, sound, scenario, readings, PAPER_GRID, 0.0, 0.0, cars)  # type: ignore[arg-type]


def never(_car: object) -> bool:
    return False


@given(speed=st.floats(BOUNDS.same_mps.low_mps, BOUNDS.same_mps.high_mps),
       onc=st.floats(BOUNDS.oncoming_mps.low_mps, BOUNDS.oncoming_mps.high_mps), t_s=st.floats(0.0, 60.0),
       ahead=st.floats(30.0, 90.0), away=st.floats(150.0, 300.0))
def test_vehicles_moving_within_their_lanes_bounds_never_breach(speed: float, onc: float, t_s: float, ahead: float,
                                                                 away: float) -> None:
    c = watch({1: ahead}, {2: away})
    left = [car(1, ahead + speed * t_s, speed)]
    oncoming = [car(2, away - onc * t_s, -onc)]
    assert c.check(t_s, 0.0, AV, left, oncoming, "drive", never) == []  # type: ignore[arg-type]


@pytest.mark.parametrize(("lane", "speed", "kind"), [(Lane.LEFT, 3.0, BreachKind.TOO_SLOW),
                                                     (Lane.LEFT, 12.0, BreachKind.TOO_FAST),
                                                     (Lane.RIGHT, 3.0, BreachKind.TOO_SLOW),
                                                     (Lane.RIGHT, 12.0, BreachKind.TOO_FAST)])
def test_a_vehicle_outside_its_bounds_breaches_once_naming_the_bound(lane: Lane, speed: float,
                                                                     kind: BreachKind) -> None:
    start = 60.0 if lane is Lane.LEFT else 250.0
    c = watch({1: start} if lane is Lane.LEFT else {}, {} if lane is Lane.LEFT else {1: start})
    sign = 1.0 if lane is Lane.LEFT else -1.0
    found = []
    for t_s in (5.0, 10.0, 20.0, 30.0):
        moved = [car(1, start + sign * speed * t_s, sign * speed)]
        left, oncoming = (moved, []) if lane is Lane.LEFT else ([], moved)
        found += c.check(t_s, 0.0, AV, left, oncoming, "drive", never)  # type: ignore[arg-type]
    assert [b.kind for b in found] == [kind] and found[0].body == 1 and found[0].by_m > 0
    assert c.world_breached() and kind.ends_decision and not kind.inside


def test_a_vehicle_stopping_inside_its_cell_breaches_the_interval_it_was_measured_in() -> None:
    """The audit's collision inside the assumptions (spread traffic, seed 2): the vehicle ahead, sensed 21.6 m away,
    stopped within 2 s; its cell (21 .. 42 m and more) still held it, the interval the plan was proved against did
    not. Containment now holds each vehicle to where it was measured."""
    c = watch({1: 21.6}, {})
    (breach,) = c.check(2.0, 0.0, AV, [car(1, 25.0, 0.0)], [], "drive", never)  # type: ignore[list-item]
    assert breach.kind is BreachKind.TOO_SLOW and breach.by_m == pytest.approx(21.6 + 2 * 4.9 - 25.0)


def test_two_readings_in_one_cell_are_one_vehicle_over_their_hull() -> None:
    c = watch({1: 25.0, 2: 30.0, 3: 70.0}, {})  # 25 and 30 m: both in cell 11
    assert c.tracked[1] is c.tracked[2] and c.tracked[3].index == 1
    assert (c.tracked[1].lo_m, c.tracked[1].hi_m) == (25.0, 30.0)
    moved = [car(1, 25.0 + 5.0, 5.0), car(2, 30.0 + 9.0, 9.0), car(3, 70.0 + 7.0, 7.0)]
    assert c.check(1.0, 0.0, AV, moved, [], "drive", never) == []  # type: ignore[arg-type]


def test_a_miss_below_the_rounding_of_positions_is_no_breach() -> None:
    """The paper's world: exact sensing and every vehicle at 7 m/s make intervals of no width."""
    readings = (Reading(Lane.LEFT, 1, 42.0),)
    from sim.driver.discretiser import discretise

    scenario = discretise(readings, Lane.LEFT, PAPER_GRID, measured=True)
    c = Containment(1, Sound(world_bounds("paper", "exact")), scenario, readings, PAPER_GRID, 0.0, 0.0,
                    [car(1, 42.0)])  # type: ignore[list-item]
    assert c.check(1.0, 0.0, AV, [car(1, 49.0 + 1e-9)], [], "drive", never) == []  # type: ignore[list-item]
    (breach,) = c.check(1.0, 0.0, AV, [car(1, 49.0 + 1e-3)], [], "drive", never)  # type: ignore[list-item]
    assert breach.kind is BreachKind.TOO_FAST


def test_a_vehicle_sensed_farther_off_than_the_error_bound_breaches_at_the_snapshot() -> None:
    c = watch({1: 60.0}, {})
    (breach,) = c.check(0.0, 0.0, AV, [car(1, 90.0)], [], "drive", never)  # type: ignore[list-item]
    assert breach.kind is BreachKind.SENSING


def test_an_unknown_vehicle_breaches_only_where_no_phantom_could_be_and_only_once_sensed() -> None:
    c = watch({}, {})
    beyond = car(5, SENSORS.left_range_m + 10.0)  # where the left-lane phantom stands: inside the assumptions
    within = car(6, 40.0)
    passed = car(7, -30.0, -7.0)  # an oncoming vehicle behind the AV: no condition speaks of it
    assert c.check(1.0, 0.0, AV, [beyond, within], [passed], "drive", never) == []  # type: ignore[list-item]
    (breach,) = c.check(1.0, 0.0, AV, [beyond, within], [passed], "drive", lambda _c: True)  # type: ignore[list-item]
    assert breach.kind is BreachKind.APPEARED and breach.body == 6


def test_an_unseen_vehicle_touching_the_av_is_after_an_assumption_broke_not_inside() -> None:
    """The 2,000 km audit's collision counted inside (following traffic, noisy sensing, seed 55): the vehicle ahead
    stopped under one decision; the next snapshot, taken as the AV reached it, could not read it (no ray reaches a
    body touching the AV), so its containment never counted it. It is where no phantom could be: an encounter with it
    is after the sensing assumption broke (``hidden``), though ``check`` does not count it (it is not sensed)."""
    c = watch({}, {})
    touching = car(6, CAR.length_m, 0.0)
    assert c.check(0.1, 0.0, AV, [touching], [], "brake", never) == []  # type: ignore[list-item]
    breach = c.hidden(0.1, 0.0, AV, Lane.LEFT, touching, "brake")  # type: ignore[arg-type]
    assert breach is not None and breach.kind is BreachKind.APPEARED and breach.body == 6 and breach.by_m > 0
    assert not c.breached  # the attribution's only: nothing recorded, nothing counted
    beyond = car(5, SENSORS.left_range_m + 10.0)  # where the phantom stands: inside the assumptions
    assert c.hidden(0.1, 0.0, AV, Lane.LEFT, beyond, "brake") is None  # type: ignore[arg-type]
    known = watch({6: 30.0}, {})
    assert known.hidden(0.1, 0.0, AV, Lane.LEFT, car(6, 30.0), "brake") is None  # type: ignore[arg-type]


def test_an_oncoming_vehicle_hidden_behind_a_left_lane_vehicle_is_held_to_the_phantom_where_the_view_ended() -> None:
    """A snapshot that saw the oncoming lane to 50 m only (``Sound.oncoming_view_m``): a vehicle sensed at 80 m a
    second later came out of the hidden stretch, inside the assumptions; had the lane been seen to the sensor's range,
    it appeared where none could be."""
    hidden = car(5, 80.0, -7.0)
    shadowed = watch({}, {}, replace(SOUND, oncoming_view_m=50.0))
    assert shadowed.check(1.0, 0.0, AV, [], [hidden], "drive", lambda _c: True) == []  # type: ignore[list-item]
    (breach,) = watch({}, {}).check(1.0, 0.0, AV, [], [hidden], "drive", lambda _c: True)  # type: ignore[list-item]
    assert breach.kind is BreachKind.APPEARED and breach.body == 5


def test_a_respawned_vehicle_is_a_new_one() -> None:
    c = watch({1: 60.0}, {})
    (breach,) = c.check(1.0, 0.0, AV, [car(1, 30.0, respawns=1)], [], "drive", lambda _c: True)  # type: ignore[list-item]
    assert breach.kind is BreachKind.APPEARED


def test_a_follower_too_close_breaks_its_assumption_without_ending_the_decision() -> None:
    c = watch({}, {})
    tailgater = car(3, -(CAR.length_m + 1.0), 7.0)  # 1 m behind the AV's bumper at the AV's speed
    (breach,) = c.check(1.0, 0.0, AV, [tailgater], [], "brake", never)  # type: ignore[list-item]
    assert breach.kind is BreachKind.FOLLOWER and breach.by_m == pytest.approx(1.0)
    assert not breach.kind.ends_decision and not c.world_breached()


@pytest.mark.parametrize(("pose", "what"), [(Pose(TRACKING.position_m + 0.1, 1.8, 0.0, 7.0), "position"),
                                            (Pose(0.0, 1.8, 0.0, 7.0 + TRACKING.speed_mps + 0.1), "speed"),
                                            (Pose(0.0, 0.0, 0.0, 7.0), "sideways")])
def test_the_av_outside_its_envelope_is_an_executor_fault_inside_the_assumptions(pose: Pose, what: str) -> None:
    c = watch({}, {})
    assert c.check_av(1.0, 0.0, AV, 0.0, 7.0, Lane.LEFT, "drive") is None
    breach = c.check_av(1.0, 0.0, pose, 0.0, 7.0, Lane.LEFT, "drive")
    assert breach is not None and breach.kind is BreachKind.AV_ENVELOPE and what in breach.vehicle
    assert breach.kind.inside and not c.world_breached()
    assert c.check_av(2.0, 0.0, pose, 0.0, 7.0, Lane.LEFT, "drive") is None  # once per decision


def test_the_report_counts_every_breach_and_reads_back_from_json() -> None:
    c = watch({1: 60.0}, {})
    report = ContainmentReport()
    for breach in c.check(10.0, 0.1, AV, [car(1, 60.0, 0.0)], [], "drive", never):  # type: ignore[list-item]
        report.add(breach)
    again = ContainmentReport.from_json(report.to_json())
    assert again.count == report.count == 1 and again.breaches == report.breaches


def test_a_decision_under_the_paper_bounds_knows_its_vehicles_by_cell() -> None:
    scenario = make_scenario(Lane.LEFT, [12], [20], 1)
    readings = (Reading(Lane.LEFT, 1, 42.0), Reading(Lane.RIGHT, 2, 210.0))
    c = Containment(1, Sound(world_bounds("paper", "exact")), scenario, readings, PAPER_GRID, 0.0, 0.0,
                    [car(1, 42.0), car(2, 210.0, -7.0)])  # type: ignore[list-item]
    assert set(c.tracked) == {1, 2} and c.tracked[1].index == 0 and c.tracked[2].lane is Lane.RIGHT


@pytest.mark.parametrize(("lane", "speed_mps", "kind"), [(Lane.LEFT, 0.4, BreachKind.TOO_SLOW),
                                                         (Lane.LEFT, 12.0, BreachKind.TOO_FAST),
                                                         (Lane.RIGHT, 3.0, BreachKind.TOO_SLOW),
                                                         (Lane.RIGHT, 12.0, BreachKind.TOO_FAST)])
def test_a_known_vehicle_driving_outside_its_speed_bounds_breaches_while_still_inside_its_interval(
        lane: Lane, speed_mps: float, kind: BreachKind) -> None:
    """The audit's near miss counted inside the assumptions (following traffic, seed 6): the vehicle ahead braked from
    6.9 to 0.4 m/s in 2.5 s and stayed inside its interval for 2 s more; the safety specification's gap to it
    depends on its speed, which had left the bounds the plan was proved against."""
    start = 60.0 if lane is Lane.LEFT else 250.0
    c = watch({1: start} if lane is Lane.LEFT else {}, {} if lane is Lane.LEFT else {1: start})
    sign = 1.0 if lane is Lane.LEFT else -1.0
    t_s = 0.1  # the position barely moved: inside the interval
    moved = [car(1, start + sign * 7.0 * t_s, sign * speed_mps)]
    left, oncoming = (moved, []) if lane is Lane.LEFT else ([], moved)
    (breach,) = c.check(t_s, 0.0, AV, left, oncoming, "drive", never)  # type: ignore[arg-type]
    bounds = BOUNDS.speeds(lane)
    expected = bounds.low_mps - speed_mps if kind is BreachKind.TOO_SLOW else speed_mps - bounds.high_mps
    assert breach.kind is kind and breach.speed and breach.by_m == pytest.approx(expected)
    assert breach.size.endswith("m/s") and c.world_breached()


def test_an_unknown_vehicle_is_held_to_a_phantom_by_position_only() -> None:
    """A vehicle beyond the sensor's range is no vehicle the plan knew: only the phantom's set speaks of it."""
    c = watch({}, {})
    beyond = car(5, SENSORS.left_range_m + 10.0, 0.0)
    assert c.check(0.1, 0.0, AV, [beyond], [], "drive", lambda _c: True) == []  # type: ignore[list-item]


# -- the AV's own monitor: the sweep's readings, no identities, no truth -----------------------------------------------
NOISY = Sound(world_bounds("spread", "noisy"))  # the same speeds, a sensing error bound


def watch_noisy(left: dict[int, float], oncoming: dict[int, float]) -> Containment:
    readings = tuple(Reading(Lane.LEFT, b, dx) for b, dx in left.items()) + tuple(
        Reading(Lane.RIGHT, b, dx) for b, dx in oncoming.items())
    from sim.driver.discretiser import discretise

    scenario = discretise(readings, Lane.LEFT, PAPER_GRID, measured=True)
    cars = [car(b, dx) for b, dx in (left | oncoming).items()]
    return Containment(1, NOISY, scenario, readings, PAPER_GRID, 0.0, 0.0, cars)  # type: ignore[arg-type]


@given(speed=st.floats(BOUNDS.same_mps.low_mps, BOUNDS.same_mps.high_mps),
       onc=st.floats(BOUNDS.oncoming_mps.low_mps, BOUNDS.oncoming_mps.high_mps), t_s=st.floats(0.0, 30.0),
       error=st.floats(-1.0, 1.0), av_mps=st.floats(3.5, 14.0))
def test_the_avs_monitor_explains_every_reading_within_the_bounds_and_the_error(speed: float, onc: float, t_s: float,
                                                                                 error: float, av_mps: float) -> None:
    """Readings of vehicles that kept their lane's speeds, each off by at most the sensing error bound, and read from
    wherever the AV has got to, are explained: no sensed breach, whatever the readings carry as body ids (none used)."""
    c = watch_noisy({1: 40.0}, {2: 250.0})
    err_m = NOISY.bounds.sensing_error_m * error
    av_x = av_mps * t_s
    sweep = (Reading(Lane.LEFT, 99, 40.0 + speed * t_s + err_m - av_x),
             Reading(Lane.RIGHT, 98, 250.0 - onc * t_s + err_m - av_x))
    assert c.sense(t_s, 0.0, av_x, sweep, "drive") is None and c.sensed is None


@pytest.mark.parametrize(("reading", "kind"), [(Reading(Lane.LEFT, 1, 40.0 + 1.0 * 10), BreachKind.TOO_SLOW),
                                               (Reading(Lane.LEFT, 1, 40.0 + 12.0 * 10), BreachKind.APPEARED),
                                               (Reading(Lane.RIGHT, 2, 250.0 - 14.0 * 10), BreachKind.TOO_FAST),
                                               (Reading(Lane.LEFT, 7, 12.0), BreachKind.APPEARED)])
def test_a_reading_no_set_explains_is_a_sensed_breach_once_and_names_its_lane(reading: Reading,
                                                                              kind: BreachKind) -> None:
    """A vehicle ahead that slowed to 1 m/s, one far beyond every interval (into the phantom's stretch it is no
    breach; short of it, where nothing was known: appeared), an oncoming one at 14 m/s, a reading between the AV and
    the vehicle it knew: each is found in the sweep alone, once per decision, by the lane it was read in."""
    c = watch_noisy({1: 40.0}, {2: 250.0})
    found = c.sense(10.0, 0.0, 0.0, (reading,), "drive")
    if kind is BreachKind.APPEARED and reading.dx_m > 100:  # beyond the known vehicle, in the phantom's reach or not
        explained = any(lo <= reading.dx_m <= hi for lo, hi in
                        (reach_m(v, NOISY.bounds, 10.0) for v in c.phantoms[Lane.LEFT]))
        assert (found is None) == explained
        return
    assert found is not None and found.kind is kind and found.sensed and reading.lane.value in found.vehicle
    assert c.sense(11.0, 0.0, 0.0, (reading,), "drive") is None  # once


def test_the_truth_alone_never_ends_a_decision_a_sensed_reading_does() -> None:
    """A vehicle outside its interval is the simulator's breach (``check``) but not the AV's until a reading shows
    it: ``unseen`` until then."""
    c = watch_noisy({1: 40.0}, {})
    assert c.check(10.0, 0.0, AV, [car(1, 40.0 + 1.0 * 10, 1.0)], [], "drive", never)  # type: ignore[arg-type]
    assert c.world_breached() and c.unseen()
    assert c.sense(10.0, 0.0, 0.0, (Reading(Lane.LEFT, -5, 50.0),), "drive") is not None
    assert not c.unseen()


def test_a_reading_of_no_vehicle_in_the_snapshot_is_a_sensing_breach_of_the_truth_not_the_avs() -> None:
    """A ghost (a fault's reading where no vehicle is) in a decision's snapshot broke the sensing assumption: the
    truth's bookkeeping records it at once (so a take-over it leads to counts as after an assumption broke); the AV,
    whose sets were made from that snapshot, has nothing to sense."""
    from sim.driver.discretiser import discretise
    from sim.faults import GHOST_BODY

    readings = (Reading(Lane.LEFT, 1, 40.0), Reading(Lane.LEFT, GHOST_BODY, -2.0))
    scenario = discretise(readings, Lane.LEFT, PAPER_GRID, measured=True)
    c = Containment(1, NOISY, scenario, readings, PAPER_GRID, 0.0, 0.0, [car(1, 40.0)])  # type: ignore[list-item]
    found = c.check(0.0, 0.0, AV, [car(1, 40.0)], [], "drive", never)  # type: ignore[list-item]
    assert [(b.kind, b.body) for b in found] == [(BreachKind.SENSING, GHOST_BODY)] and "no vehicle" in found[0].vehicle
    assert c.world_breached() and c.check(1.0, 0.0, AV, [car(1, 47.0)], [], "drive", never) == []  # type: ignore[list-item]
    assert c.sense(0.0, 0.0, 0.0, readings, "drive") is None


def test_a_vehicles_second_reading_away_from_it_is_a_sensing_breach_of_the_truth_not_the_avs() -> None:
    """A fake gap's displaced copy held beside the vehicle's own kept track (faults run, seeds 4 and 11): the same
    vehicle read twice, one reading a cell behind it. The bookkeeping checks every reading of the snapshot, not one
    per vehicle: the copy broke the sensing assumption (keyed by that vehicle, so an encounter with it counts after
    an assumption broke); the vehicle's own reading is held to its interval as before; the AV's monitor, whose sets
    both readings made, has nothing to sense."""
    from sim.driver.discretiser import discretise

    readings = (Reading(Lane.LEFT, 1, 19.0), Reading(Lane.LEFT, 1, 40.0))  # the copy 21 m behind the vehicle
    scenario = discretise(readings, Lane.LEFT, PAPER_GRID, measured=True)
    c = Containment(1, NOISY, scenario, readings, PAPER_GRID, 0.0, 0.0, [car(1, 40.0)])  # type: ignore[list-item]
    found = c.check(0.0, 0.0, AV, [car(1, 40.0)], [], "drive", never)  # type: ignore[list-item]
    assert [(b.kind, b.body) for b in found] == [(BreachKind.SENSING, 1)] and "second reading" in found[0].vehicle
    assert found[0].by_m == pytest.approx(21.0 - NOISY.bounds.sensing_error_m)
    assert c.world_breached() and c.sense(0.0, 0.0, 0.0, readings, "drive") is None
    near = (Reading(Lane.LEFT, 1, 40.0), Reading(Lane.LEFT, 1, 40.5))  # read twice within the error: no breach
    c = Containment(1, NOISY, discretise(near, Lane.LEFT, PAPER_GRID, measured=True), near, PAPER_GRID, 0.0, 0.0,
                    [car(1, 40.0)])  # type: ignore[list-item]
    assert c.check(0.0, 0.0, AV, [car(1, 40.0)], [], "drive", never) == []  # type: ignore[list-item]


@given(bodies=st.lists(st.integers(-2, 50), min_size=3, max_size=3), t_s=st.floats(0.0, 20.0))
def test_the_avs_monitor_reads_no_identities(bodies: list[int], t_s: float) -> None:
    """Whatever body ids the readings carry (the bookkeeping's, one vehicle's twice, a ghost's), the AV's own monitor
    knows the same sets and senses the same breaches: they are made from the readings' lanes and distances only."""
    from sim.driver.discretiser import discretise

    places = ((Lane.LEFT, 19.0), (Lane.LEFT, 61.0), (Lane.RIGHT, 250.0))
    sweep = (Reading(Lane.LEFT, 77, 19.0 + 1.0 * t_s), Reading(Lane.LEFT, 78, 120.0), Reading(Lane.RIGHT, 79, 150.0))
    answers = []
    for ids in (bodies, [1, 2, 3]):
        readings = tuple(Reading(lane, b, dx) for (lane, dx), b in zip(places, ids, strict=True))
        scenario = discretise(readings, Lane.LEFT, PAPER_GRID, measured=True)
        cars = [car(b, dx) for (_, dx), b in zip(places, ids, strict=True) if b >= 0]
        c = Containment(1, NOISY, scenario, readings, PAPER_GRID, 0.0, 0.0, cars)  # type: ignore[arg-type]
        answers.append((c.explaining, c.sense(t_s, 0.0, 0.0, sweep, "drive")))
    assert answers[0] == answers[1]


def sighting(bounds: object = BOUNDS) -> Sighting:
    return Sighting((Reading(Lane.LEFT, 1, 40.0), Reading(Lane.RIGHT, 2, 250.0)), bounds, 0.0, 0.0)  # type: ignore[arg-type]


@given(speed=st.floats(BOUNDS.same_mps.low_mps, BOUNDS.same_mps.high_mps),
       onc=st.floats(BOUNDS.oncoming_mps.low_mps, BOUNDS.oncoming_mps.high_mps), t_s=st.floats(0.0, 30.0),
       av_mps=st.floats(3.5, 14.0), body=st.integers(-2, 99))
def test_a_vehicle_the_snapshot_showed_is_never_sensed_anew(speed: float, onc: float, t_s: float, av_mps: float,
                                                            body: int) -> None:
    """The paper's re-planning rule without identities: readings of the snapshot's vehicles, moved within their
    lanes' bounds and read from wherever the AV has got to, are no new vehicle, whatever body ids they carry."""
    av_x = av_mps * t_s
    sweep = (Reading(Lane.LEFT, body, 40.0 + speed * t_s - av_x), Reading(Lane.RIGHT, body, 250.0 - onc * t_s - av_x))
    assert not sighting().new(sweep, av_x, t_s)
    assert not sighting().new(sweep[:1], av_x, t_s)  # one of them missed: nothing new


@pytest.mark.parametrize("reading", [Reading(Lane.LEFT, 1, 40.0 + 12.0 * 10), Reading(Lane.LEFT, 1, 12.0),
                                     Reading(Lane.RIGHT, 2, 150.0), Reading(Lane.RIGHT, 2, 40.0 + 7.0 * 10)])
def test_a_reading_no_vehicle_of_the_snapshot_explains_is_a_new_vehicle(reading: Reading) -> None:
    """Beyond the fastest the vehicle ahead may have gone, short of the slowest, an oncoming one where none was, or
    one in the other lane at the vehicle ahead's place: new, even under the vehicle's own id."""
    assert sighting().new((reading,), 0.0, 10.0)


def test_the_paper_worlds_vehicles_are_known_only_exactly_where_they_went() -> None:
    """Under the paper's bounds (every vehicle at 7 m/s, exact sensing) a vehicle is the one the snapshot showed only
    where 7 m/s took it: a metre off is a new one."""
    from spec.assumptions import PROFILES

    s = sighting(PROFILES["paper"])
    assert not s.new((Reading(Lane.LEFT, 5, 40.0 + 70.0 - 70.0),), 70.0, 10.0)
    assert s.new((Reading(Lane.LEFT, 5, 41.0),), 70.0, 10.0)


def test_a_measured_vehicle_braking_to_a_standstill_is_inside_one_braking_harder_than_b_max_is_not() -> None:
    """A vehicle whose speed was measured (``Reading.speed_mps``) may brake at b_max to a standstill: the position
    and the speed that motion reaches are inside its own bounds, where its lane's 4.9 m/s floor called both a breach;
    a speed just below what braking at b_max allows is a breach, ``too slow``, by that much; a speed outside the
    measured interval at the snapshot itself is a ``sensing error`` (the range-rate reading's error bound broke)."""
    from sim.driver.discretiser import discretise
    from spec.tracking import VEHICLE_SPEED_CHANGE

    b = VEHICLE_SPEED_CHANGE.brake_mps2
    readings = (Reading(Lane.LEFT, 1, 40.0, speed_mps=(7.0, 7.0)),)
    scenario = discretise(readings, Lane.LEFT, PAPER_GRID, measured=True)
    assert scenario.left_mps == ((7.0, 7.0),)

    def watched() -> Containment:
        return Containment(1, SOUND, scenario, readings, PAPER_GRID, 0.0, 0.0, [car(1, 40.0)])  # type: ignore[list-item]

    stopped_s = 7.0 / b
    for t_s in (0.5 * stopped_s, stopped_s, 3.0):  # braking at b_max, then standing
        speed = max(0.0, 7.0 - b * t_s)
        x = 40.0 + (7.0 * t_s - b * t_s * t_s / 2 if t_s < stopped_s else 49.0 / (2 * b))
        assert watched().check(t_s, 0.0, AV, [car(1, x, speed)], [], "drive", never) == []  # type: ignore[list-item]
    t_s = 0.5 * stopped_s
    x = 40.0 + 7.0 * t_s - b * t_s * t_s / 2
    (breach,) = watched().check(t_s, 0.0, AV, [car(1, x, 7.0 - b * t_s - 0.01)], [], "drive",  # type: ignore[list-item]
                                never)
    assert breach.kind is BreachKind.TOO_SLOW and breach.speed and breach.by_m == pytest.approx(0.01)
    # outside the measured interval at the snapshot itself: the speed reading's error bound broke, not the vehicle
    (breach,) = watched().check(0.0, 0.0, AV, [car(1, 40.0, 7.02)], [], "drive", never)  # type: ignore[list-item]
    assert breach.kind is BreachKind.SENSING and breach.speed and breach.by_m == pytest.approx(0.02)


def test_a_measured_vehicle_speeding_up_while_overtaken_breaks_the_no_acceleration_profile_only() -> None:
    """Under ``Overtaken.NO_ACCELERATION`` the decision's proof took a measured same-direction vehicle not to speed up
    while the AV is in the passing lane (``passing_windows_s`` of the actions it executes): a speed just above the
    one it had when the window began is ``accelerated while overtaken``, one at it is inside; beyond what a_max allows
    is ``too fast``; under ``physics`` speeding up at a_max is inside; outside the window the profile says nothing."""
    from sim.driver.discretiser import discretise
    from spec.actions import Action
    from spec.dynamics import Overtaken
    from spec.tracking import VEHICLE_SPEED_CHANGE

    a = 0.5  # below its lane's top (9.1 m/s) all the while: 7 + 0.5 x 4 s
    change = replace(VEHICLE_SPEED_CHANGE, accel_mps2=a)
    readings = (Reading(Lane.LEFT, 1, 40.0, speed_mps=(7.0, 7.0)),)
    scenario = discretise(readings, Lane.LEFT, PAPER_GRID, measured=True)
    plan = (Action.DRIVE, Action.RIGHT_LANE_CHANGE, Action.ACCELERATE, Action.LEFT_LANE_CHANGE)
    out_s = 3.0  # the drive's end: the move out starts

    def watched(overtaken: Overtaken) -> Containment:
        sound = replace(SOUND, overtaken=overtaken, speed_change=change)
        c = Containment(1, sound, scenario, readings, PAPER_GRID, 0.0, 0.0, [car(1, 40.0)])  # type: ignore[list-item]
        c.passing(plan)
        return c

    assert watched(Overtaken.NO_ACCELERATION).windows_s == ((out_s, 12.0),)
    t_s = out_s + 1.0
    held_x = 40.0 + 7.0 * out_s + a * out_s * out_s / 2 + (7.0 + a * out_s) * 1.0  # sped up until the move out only
    held_v = 7.0 + a * out_s
    for overtaken, speed, kind in ((Overtaken.NO_ACCELERATION, held_v, None),
                                   (Overtaken.NO_ACCELERATION, held_v + 0.01, BreachKind.ACCELERATED),
                                   (Overtaken.NO_ACCELERATION, 7.0 + a * t_s + 0.01, BreachKind.TOO_FAST),
                                   (Overtaken.PHYSICS, 7.0 + a * t_s, None),
                                   (Overtaken.PHYSICS, 7.0 + a * t_s + 0.01, BreachKind.TOO_FAST)):
        found = watched(overtaken).check(t_s, 0.0, AV, [car(1, held_x, speed)], [], "drive",  # type: ignore[list-item]
                                         never)
        assert [b.kind for b in found] == ([] if kind is None else [kind]), (overtaken, speed)
    # before the move out, speeding up at a_max is inside either way
    before_s = out_s - 0.5
    x = 40.0 + 7.0 * before_s + a * before_s * before_s / 2
    assert watched(Overtaken.NO_ACCELERATION).check(before_s, 0.0, AV, [car(1, x, 7.0 + a * before_s)], [],  # type: ignore[list-item]
                                                    "drive", never) == []
    # a position the held speed cannot reach, and speeding up at a_max can (0.25 m farther): accelerated while
    # overtaken, by how far beyond the held reach
    (breach,) = watched(Overtaken.NO_ACCELERATION).check(t_s, 0.0, AV, [car(1, held_x + 0.1, held_v)], [],  # type: ignore[list-item]
                                                         "drive", never)
    assert breach.kind is BreachKind.ACCELERATED and not breach.speed and breach.by_m == pytest.approx(0.1)
    # the AV's own monitor reads the same: a reading only the held speed cannot explain, then one it can
    sensed = watched(Overtaken.NO_ACCELERATION).sense(t_s, 0.0, 0.0, (Reading(Lane.LEFT, 1, held_x + 0.1),), "drive")
    assert sensed is not None and sensed.kind is BreachKind.ACCELERATED and sensed.by_m == pytest.approx(0.1)
    assert watched(Overtaken.NO_ACCELERATION).sense(t_s, 0.0, 0.0, (Reading(Lane.LEFT, 1, held_x),), "drive") is None
    assert watched(Overtaken.PHYSICS).sense(t_s, 0.0, 0.0, (Reading(Lane.LEFT, 1, held_x + 0.1),), "drive") is None


@pytest.mark.parametrize(("followed", "at_m", "acts"), [(True, -8.0, False), (False, -8.0, True), (True, 80.0, True)])
def test_a_follower_found_behind_its_interval_is_not_acted_on_while_the_av_is_in_its_lane(
        followed: bool, at_m: float, acts: bool) -> None:
    """A vehicle behind the AV in the left lane, read 5 s on (the AV 30 m on) where only 3 m/s, below its lane's
    least speed, puts it: too slow. With the AV in the left lane (``followed``) it follows the AV and cannot pass it,
    so every condition of the decision bounds it from ahead: farther behind breaks none, and the AV does not re-plan
    on it (at every sweep behind a slow platoon, that made 78% of a drive's decisions re-plans). Out of the lane it
    is acted on, and so is a vehicle ahead found too slow, whatever the lane."""
    c = watch_noisy({1: at_m}, {})
    found = c.sense(5.0, 0.0, 30.0, (Reading(Lane.LEFT, 1, at_m + 3.0 * 5 - 30.0),), "drive", followed)
    assert (found is not None) is acts
    if acts:
        assert found is not None and found.kind is BreachKind.TOO_SLOW
