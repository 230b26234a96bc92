"""The tracking layer: without faults it plans around every vehicle where it is and flags nothing; each of the paper's
faults it was built for is held, kept or rejected as its rules say, and what it cannot resolve flags its lane. The
tracker reads detections without bodies (``Detection`` has none)."""

from __future__ import annotations

import dataclasses

import pytest

from sim.driver.readings import Reading
from sim.faults import FaultySensor
from sim.sensors import Truth
from sim.tracking import Detection, TrackedSweep, Tracker, hides
from spec.assumptions import world_bounds
from spec.faults import Fault, FaultKind, FaultSpec
from spec.grid import PAPER_GRID
from spec.lanes import Lane
from spec.physical import SENSORS
from spec.tracking import CONFIRM_SWEEPS, TrackState

BOUNDS = world_bounds("paper", "exact")  # every vehicle at 7 m/s, no sensing error
DT_S, AV_MPS, V_MPS = 0.1, 14.0, 7.0
# left-lane vehicles in adjacent 21 m cells ahead of the AV (a fake gap's target), one beyond the range; oncoming
LEFT = {1: 30.0, 2: 51.0, 3: 93.0, 4: 160.0}
ONCOMING = {5: 200.0, 6: 330.0}


AV_Y_M = -1.8  # the AV overtaking in the right lane, where the paper's sensing faults struck: it sees along the platoon


def truth_at(k: int) -> Truth:
    """The world at sweep ``k``: the AV at 14 m/s, left-lane vehicles at 7, oncoming at -7; what is in range and in
    sight (no other body on the line to it, as the sensors' rays)."""
    av = AV_MPS * k * DT_S
    readings = [Reading(Lane.LEFT, b, x + V_MPS * k * DT_S - av) for b, x in LEFT.items()]
    readings += [Reading(Lane.RIGHT, b, x - V_MPS * k * DT_S - av) for b, x in ONCOMING.items()]
    near = [r for r in readings if (abs(r.dx_m) <= SENSORS.left_range_m if r.lane is Lane.LEFT
                                    else -SENSORS.side_range_m <= r.dx_m <= SENSORS.right_range_m)]
    seen = tuple(r for r in near if not any(hides(AV_Y_M, r.lane, r.dx_m, o.lane, o.dx_m) for o in readings))
    # ``targets`` here: every vehicle in range, sighted or not, its lane as the sign of the second number
    return Truth(seen, tuple((r.dx_m, 1.0 if r.lane is Lane.LEFT else -1.0) for r in near), av, AV_Y_M)


def where(view: TrackedSweep, truth: Truth) -> bool:
    """The planner is told of every vehicle in sight, where it is, and of nothing that is not a vehicle in range (a
    vehicle hidden behind another may be kept, where it is)."""
    told = planned(view, truth.av_x_m)
    in_range = {("left" if y > 0 else "right", x) for x, y in truth.targets}
    return set(true(truth)) <= set(told) and len(told) == len(set(told)) and all(
        any(lane == p_lane and abs(x - p_x) < 1e-6 for lane, x in in_range) for p_lane, p_x in told)


class Exact:
    def read(self, truth: Truth) -> tuple[Reading, ...]:
        return truth.readings


CLEAN = 40  # sweeps read without faults first (4 s): the first sweep is the picture the tracker starts from


def run(sweeps: int, faults: tuple[Fault, ...] = (), seed: int = 1,
        until: int | None = None) -> list[tuple[Truth, TrackedSweep, tuple[Reading, ...] | None]]:
    """Sweeps of the world through the fault injectors (from sweep ``CLEAN`` on, and before ``until``)."""
    sensor = FaultySensor(Exact(), FaultSpec(faults), PAPER_GRID, seed)
    tracker = Tracker(BOUNDS)
    out = []
    for k in range(sweeps):
        truth = truth_at(k)
        raw = truth.readings if k < CLEAN or (until is not None and k >= until) else sensor.read(truth)
        view = tracker.update(k * DT_S, truth.av_x_m, AV_MPS,
                              None if raw is None else [Detection(r.lane, r.dx_m) for r in raw], truth.av_y_m)
        out.append((truth, view, raw))
    return out


def planned(view: TrackedSweep, av_x_m: float) -> list[tuple[str, float]]:
    return sorted((t.lane.value, round(t.place_m - av_x_m, 6)) for t in view.planned)


def true(truth: Truth) -> list[tuple[str, float]]:
    return sorted((r.lane.value, round(r.dx_m, 6)) for r in truth.readings)


def test_the_tracker_reads_no_vehicle_identity() -> None:
    assert [f.name for f in dataclasses.fields(Detection)] == ["lane", "dx_m", "rate_mps"]


def test_without_faults_every_vehicle_is_planned_where_it_is_and_nothing_is_flagged() -> None:
    for truth, view, _ in run(120):
        assert where(view, truth)
        assert not view.unresolved and not view.held


def test_a_dropped_sweep_is_bridged_by_each_track_within_its_bounds() -> None:
    for truth, view, raw in run(60, (Fault(FaultKind.DROPPED, 0.3, 2),)):
        assert where(view, truth), raw is None  # 7 m/s exactly: the prediction is exact


def test_a_fake_gap_is_filled_by_the_kept_track_and_flags_the_lane_until_it_ends() -> None:
    results = run(100, (Fault(FaultKind.FAKE_GAP, 1.0, 30),), until=CLEAN + 30)  # one fault of 30 sweeps
    faulty = [(truth, view) for truth, view, raw in results if raw is not None and set(raw) != set(truth.readings)]
    assert len(faulty) == 30
    for truth, view, _ in results:
        assert where(view, truth)  # the displaced reading is held, not planned; the vehicle is kept where it is
    for _, view in faulty:
        assert Lane.LEFT in view.unresolved
    assert not results[-1][1].unresolved and not results[-1][1].held  # resolved once the fault is over


def test_a_ghost_that_moves_with_the_av_is_held_while_it_appears_and_planned_at_most_where_sight_just_opened() -> None:
    """A ghost that appears where nothing hid a vehicle is held (its lane flagged) and rejected when its next reading
    breaks the lane's bounds; one that appears where a vehicle just came into sight is a vehicle to the tracker for a
    sweep, until its next reading breaks the bounds."""
    for kind, lane in ((FaultKind.GHOST_LEFT, Lane.LEFT), (FaultKind.GHOST_ONCOMING, Lane.RIGHT)):
        run_of_planned = 0
        for truth, view, raw in run(160, (Fault(kind, 1.0, 30),))[CLEAN:]:
            assert raw is not None
            ghosts = [r for r in raw if r.body < 0]
            told = planned(view, truth.av_x_m)
            planned_ghost = any((g.lane.value, round(g.dx_m, 6)) in told and (g.lane.value, round(g.dx_m, 6))
                                not in true(truth) for g in ghosts)
            run_of_planned = run_of_planned + 1 if planned_ghost else 0
            assert run_of_planned <= 1, kind
            if view.held:
                assert lane in view.unresolved


@pytest.mark.parametrize("kind", [FaultKind.SAME_CELL, FaultKind.MERGED])
def test_readings_moved_onto_others_keep_every_vehicle_where_it_is(kind: FaultKind) -> None:
    def world(k: int) -> Truth:  # the AV beside two vehicles, a cell behind and ahead of it (the paper's 9 and 11)
        readings = (Reading(Lane.LEFT, 1, -21.0), Reading(Lane.LEFT, 2, 21.0))
        return Truth(readings, ((-21.0, 0.0), (21.0, 0.0)), AV_MPS * k * DT_S, -1.8)

    sensor = FaultySensor(Exact(), FaultSpec((Fault(kind, 1.0, 30),)), PAPER_GRID, 3)
    bounds = dataclasses.replace(BOUNDS, same_mps=dataclasses.replace(BOUNDS.same_mps, low_mps=14.0, high_mps=14.0))
    tracker = Tracker(bounds)  # the vehicles keep the AV's speed here
    for k in range(70):  # 30 sweeps of one fault: shorter than the 40 the vehicles were seen before it
        truth = world(k)
        raw = truth.readings if k < 40 else sensor.read(truth)  # tracked for 4 s before the faults start
        assert raw is not None
        view = tracker.update(k * DT_S, truth.av_x_m, AV_MPS, [Detection(r.lane, r.dx_m) for r in raw], -1.8)
        assert planned(view, truth.av_x_m) == true(truth), (k, raw)
        assert (Lane.LEFT in view.unresolved) == (set(raw) != set(truth.readings))


def test_a_split_copy_that_persists_is_confirmed_and_retired_once_missing_longer_than_seen() -> None:
    tracker = Tracker(BOUNDS)
    extra = []
    for k in range(120):
        truth = truth_at(k)
        raw = list(truth.readings)
        if 10 <= k < 40:  # one vehicle read twice, the copy a cell behind it, for 30 sweeps
            (copied,) = [r for r in raw if r.body == 3]
            raw.append(dataclasses.replace(copied, dx_m=copied.dx_m - PAPER_GRID.cell))
        view = tracker.update(k * DT_S, truth.av_x_m, AV_MPS, [Detection(r.lane, r.dx_m) for r in raw], AV_Y_M)
        in_range = {("left" if y > 0 else "right", round(x, 6)) for x, y in truth.targets}
        extra.append(sum(1 for p in planned(view, truth.av_x_m) if p not in in_range))  # planned, but no vehicle
    assert extra[:10 + CONFIRM_SWEEPS - 1] == [0] * (10 + CONFIRM_SWEEPS - 1)  # held until confirmed
    assert set(extra[10 + CONFIRM_SWEEPS - 1:40]) == {1}  # a copy read three sweeps running is a vehicle to it
    seen = 40 - 10
    assert extra[40:40 + seen] == [1] * seen  # then missing where the sensor sees: kept as long as it was seen
    assert set(extra[40 + seen + 1:]) == {0}  # and retired


def test_a_vehicle_entering_at_the_range_edge_is_planned_at_once_and_one_leaving_is_retired() -> None:
    results = run(400)
    counts = [len(view.planned) for _, view, _ in results]
    assert counts[0] == len(results[0][0].readings)
    for truth, view, _ in results:
        assert where(view, truth)
        assert all(t.state is not TrackState.HELD for t in view.planned)
    assert len(set(counts)) > 1  # vehicles came and went


def test_without_faults_tracking_changes_nothing_in_the_papers_world() -> None:
    from sim.parts import DriveConfig
    from sim.simulator import run_drive

    wall = ("wall_s", "plan_ms", "plan_latency_ms")
    plain = {k: v for k, v in run_drive(3, DriveConfig(1.0)).to_json().items() if k not in wall}
    tracked = {k: v for k, v in run_drive(3, DriveConfig(1.0, tracking=True)).to_json().items() if k not in wall}
    assert tracked == plain


def test_tracking_bridges_dropped_sweeps_that_leave_the_planner_without_a_snapshot_otherwise() -> None:
    from sim.parts import DriveConfig
    from sim.simulator import run_drive

    config = DriveConfig(0.5, faults="dropped-sweep=0.5/1")
    assert run_drive(4, config).stops  # without tracking: snapshots that could not be read
    tracked = run_drive(4, dataclasses.replace(config, tracking=True))
    assert not tracked.stops and tracked.faults["dropped-sweep"]["started"] > 0


def test_an_overtake_is_refused_only_at_the_decision_that_would_start_it() -> None:
    """With a lane holding an unresolved contradiction, a plan with a lane change out of the left lane is refused
    only where driving on in lane is what the AV does anyway: in the left lane, at the common speed, with no lane
    change under way. Mid-manoeuvre (a lane change still to come from the last plan, or the AV already faster) the
    plan goes on; without a contradiction, without tracking or without a lane change nothing is refused."""
    from sim.parts import DriveConfig
    from sim.simulator import Simulator
    from spec.actions import Action

    overtake = (Action.ACCELERATE, Action.RIGHT_LANE_CHANGE, Action.ACCELERATE, Action.LEFT_LANE_CHANGE)
    sim = Simulator(1, DriveConfig(1.0, tracking=True).parts())
    try:
        common, pose = float(sim.grid.speed), sim.car.pose()
        assert pose.y_m > 0  # the AV starts in the left lane
        sim.car.pose = lambda: dataclasses.replace(pose, speed_mps=common)  # type: ignore[method-assign]
        sim.unresolved = frozenset()
        assert not sim.refused(overtake, ())
        sim.unresolved = frozenset({Lane.LEFT})
        assert not sim.refused((Action.DRIVE, Action.DRIVE), ())  # no overtake in it
        assert not sim.refused(overtake, (Action.RIGHT_LANE_CHANGE, Action.ACCELERATE))  # one under way
        assert sim.refused(overtake, ()) and sim.summary.refusals == 1
        sim.car.pose = lambda: dataclasses.replace(pose, speed_mps=2 * common)  # type: ignore[method-assign]
        assert not sim.refused(overtake, ())  # already faster than the traffic: too near to brake
        assert sim.summary.refusals == 1
    finally:
        sim.close()
    untracked = Simulator(1, DriveConfig(1.0).parts())
    try:
        untracked.unresolved = frozenset({Lane.LEFT})
        assert not untracked.refused(overtake, ())
    finally:
        untracked.close()
