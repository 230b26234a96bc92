"""Fault injectors: each kind does what it says, at its stated rate per sweep that offers it a target, for its
persistence, and only that; the truth is never changed; each kind draws from its own stream. The steering fault's
default size spins the car, and a drive records the loss of control."""

from __future__ import annotations

import itertools
import math
from collections import Counter
from collections.abc import Callable

import pytest

from sim.driver.readings import Reading
from sim.faults import GHOST_BODY, FaultySensor, SteeringFault
from sim.sensors import Truth
from spec.cells import left_cell
from spec.faults import (
    DEFAULT_STEERING_OFFSET_DEG,
    DEFAULT_STEERING_SWEEPS,
    GHOST_BEHIND_M,
    Fault,
    FaultKind,
    FaultSpec,
    lost_control,
)
from spec.grid import PAPER_GRID
from spec.lanes import Lane
from spec.physical import CAR, ROAD, SENSORS

GRID = PAPER_GRID
CELL = GRID.cell
# The AV in the right lane (overtaking) with left-lane vehicles a cell behind and ahead of it (the paper's 9 and 11
# around its 10), one more in the next cell ahead (adjacent: a fake gap's target), one far ahead; two oncoming.
WORLD = (Reading(Lane.LEFT, 1, -CELL), Reading(Lane.LEFT, 2, CELL), Reading(Lane.LEFT, 3, 2 * CELL),
         Reading(Lane.LEFT, 4, 5 * CELL), Reading(Lane.RIGHT, 5, 7 * CELL), Reading(Lane.RIGHT, 6, 12 * CELL))
TRUTH = Truth(WORLD, tuple((r.dx_m, 0.0) for r in WORLD), 0.0, -ROAD.lane_width_m / 2)
SENSING = [k for k in FaultKind if k.sensing]


class Exact:
    """A sensor that reports the truth as it is."""

    def read(self, truth: Truth) -> tuple[Reading, ...]:
        return truth.readings


def cell_of(r: Reading) -> int:
    return left_cell(r.dx_m, Lane.RIGHT, GRID)


def changed(seen: tuple[Reading, ...]) -> tuple[list[Reading], list[Reading]]:
    """What a sweep lost and gained against the truth."""
    before, after = Counter(WORLD), Counter(seen)
    return list((before - after).elements()), list((after - before).elements())


def fake_gap(lost: list[Reading], gained: list[Reading]) -> bool:
    """The rear of two left-lane vehicles in adjacent cells, reported one cell further back."""
    if len(lost) != 1 or len(gained) != 1:
        return False
    (rear,), (moved,) = lost, gained
    front = [r for r in WORLD if r.lane is Lane.LEFT and cell_of(r) == cell_of(rear) + 1]
    return moved.body == rear.body and moved.dx_m == rear.dx_m - CELL and rear.lane is Lane.LEFT and bool(front)


def ghost(lane: Lane, low: float, high: float) -> Callable[[list[Reading], list[Reading]], bool]:
    def check(lost: list[Reading], gained: list[Reading]) -> bool:
        if lost or len(gained) != 1:
            return False
        (g,) = gained
        free = all(abs(r.dx_m - g.dx_m) >= CAR.length_m for r in WORLD if r.lane is lane)
        return g.body == GHOST_BODY and g.lane is lane and low <= g.dx_m <= high and free
    return check


def same_cell(lost: list[Reading], gained: list[Reading]) -> bool:
    """A left-lane vehicle next to the AV reported at its neighbour's place, both within a cell of the AV's."""
    if len(lost) != 1 or len(gained) != 1:
        return False
    (was,), (now,) = lost, gained
    other = [r for r in WORLD if r.body != was.body and r.lane is Lane.LEFT and r.dx_m == now.dx_m]
    near = all(abs(cell_of(r) - GRID.av_cell) <= 1 for r in (was, *other))
    return now.body == was.body and len(other) == 1 and near


def merged(lost: list[Reading], gained: list[Reading]) -> bool:
    """Two vehicles of one lane within two cells, reported as one at their middle."""
    if len(lost) != 2 or len(gained) != 1:
        return False
    a, b = lost
    (one,) = gained
    return (a.lane is b.lane is one.lane and abs(a.dx_m - b.dx_m) <= 2 * CELL and one.body in (a.body, b.body)
            and math.isclose(one.dx_m, (a.dx_m + b.dx_m) / 2))


def split(lost: list[Reading], gained: list[Reading]) -> bool:
    """One vehicle reported twice, the copy a cell ahead or behind."""
    if lost or len(gained) != 1:
        return False
    (copy,) = gained
    original = [r for r in WORLD if r.body == copy.body]
    return len(original) == 1 and original[0].lane is copy.lane and abs(abs(copy.dx_m - original[0].dx_m) - CELL) < 1e-9


EXPECTED: dict[FaultKind, Callable[[list[Reading], list[Reading]], bool]] = {
    FaultKind.FAKE_GAP: fake_gap,
    FaultKind.GHOST_LEFT: ghost(Lane.LEFT, -GHOST_BEHIND_M, 0.0),
    FaultKind.GHOST_ONCOMING: ghost(Lane.RIGHT, -SENSORS.side_range_m, SENSORS.right_range_m),
    FaultKind.SAME_CELL: same_cell,
    FaultKind.MERGED: merged,
    FaultKind.SPLIT: split,
}


def sweeps(kind: FaultKind, rate: float, persistence: int, n: int, seed: int = 7,
           others: tuple[Fault, ...] = ()) -> tuple[FaultySensor, list[tuple[Reading, ...] | None]]:
    sensor = FaultySensor(Exact(), FaultSpec((Fault(kind, rate, persistence), *others)), GRID, seed)
    return sensor, [sensor.read(TRUTH) for _ in range(n)]


def test_every_sensing_kind_has_a_stated_effect_checked_here() -> None:
    assert set(SENSING) == {*EXPECTED, FaultKind.DROPPED}


@pytest.mark.parametrize("kind", SENSING, ids=lambda k: k.value)
def test_each_fault_starts_at_its_stated_rate_per_sweep_that_offers_a_target(kind: FaultKind) -> None:
    sensor, _ = sweeps(kind, 0.2, 1, 3000)
    injector = sensor.injectors[kind]
    assert injector.offered >= 2000  # this world offers every kind a target on most sweeps (a ghost: where none is)
    expected, sd = 0.2 * injector.offered, math.sqrt(injector.offered * 0.2 * 0.8)
    assert abs(injector.started - expected) < 4 * sd, (injector.started, expected)


@pytest.mark.parametrize("kind", SENSING, ids=lambda k: k.value)
def test_each_fault_changes_what_it_says_and_only_that_and_never_the_truth(kind: FaultKind) -> None:
    truth_before = repr(TRUTH)
    sensor, seen = sweeps(kind, 0.3, 3, 400)
    faulty = [s for s in seen if s is None or Counter(s) != Counter(WORLD)]
    assert faulty, "no sweep changed"
    for sweep in seen:
        if kind is FaultKind.DROPPED:
            assert sweep is None or Counter(sweep) == Counter(WORLD)
        else:
            assert sweep is not None
            if Counter(sweep) != Counter(WORLD):
                lost, gained = changed(sweep)
                assert EXPECTED[kind](lost, gained), (kind, lost, gained)
    assert repr(TRUTH) == truth_before
    changed_sweeps = sum(e.sweeps for e in sensor.events)
    assert changed_sweeps == len(faulty)  # every changed sweep is a logged fault's, and every logged one changed


@pytest.mark.parametrize("kind", SENSING, ids=lambda k: k.value)
def test_a_fault_lasts_its_persistence_while_its_vehicles_stay_in_the_sweep(kind: FaultKind) -> None:
    sensor, seen = sweeps(kind, 1.0, 5, 12)
    events = sensor.events
    if kind is FaultKind.GHOST_LEFT:  # a ghost starts only on a sweep whose drawn place is free: later, maybe
        assert all(b.start_sweep >= a.start_sweep + 5 for a, b in itertools.pairwise(events))
    else:
        assert [e.start_sweep for e in events] == [1, 6, 11]
    assert events and all(e.sweeps == 5 for e in events if e.end_sweep <= 12)
    if kind is FaultKind.GHOST_LEFT or kind is FaultKind.GHOST_ONCOMING:
        first = events[0].start_sweep - 1
        assert len({g.dx_m for s in seen[first:first + 5] if s is not None for g in s if g.body == GHOST_BODY}) == 1


def test_a_fault_ends_when_the_vehicles_it_touched_leave_the_sweep() -> None:
    sensor = FaultySensor(Exact(), FaultSpec((Fault(FaultKind.SPLIT, 1.0, 30),)), GRID, 3)
    first = sensor.read(TRUTH)
    assert first is not None and len(first) == len(WORLD) + 1
    (event,) = sensor.events
    gone = tuple(r for r in WORLD if r.body not in event.bodies)
    sensor.read(Truth(gone, tuple((r.dx_m, 0.0) for r in gone), 0.0, TRUTH.av_y_m))
    assert event.end_sweep == 2 and event.sweeps == 1


def test_each_kind_draws_from_its_own_stream() -> None:
    alone, _ = sweeps(FaultKind.FAKE_GAP, 0.1, 2, 500)
    with_others, _ = sweeps(FaultKind.FAKE_GAP, 0.1, 2, 500, others=(Fault(FaultKind.SPLIT, 0.3, 4),
                                                                     Fault(FaultKind.DROPPED, 0.2, 1)))
    assert [e.start_sweep for e in alone.injectors[FaultKind.FAKE_GAP].events] == \
        [e.start_sweep for e in with_others.injectors[FaultKind.FAKE_GAP].events]


def test_no_target_no_fault_a_fake_gap_needs_two_vehicles_in_adjacent_cells() -> None:
    lone = (Reading(Lane.LEFT, 1, 5 * CELL),)
    sensor = FaultySensor(Exact(), FaultSpec((Fault(FaultKind.FAKE_GAP, 1.0, 1),)), GRID, 1)
    for _ in range(50):
        assert sensor.read(Truth(lone, ((5 * CELL, 0.0),), 0.0, TRUTH.av_y_m)) == lone
    assert sensor.injectors[FaultKind.FAKE_GAP].offered == 0


def test_the_steering_fault_offsets_the_steering_at_its_rate_and_for_its_duration() -> None:
    steering = SteeringFault(FaultSpec((Fault(FaultKind.STEERING, 0.05, DEFAULT_STEERING_SWEEPS),)), 11)
    offsets = [steering.on_sweep() for _ in range(20_000)]
    injector = steering.injector
    assert injector is not None
    faulty = [o for o in offsets if o]
    assert {abs(o) for o in faulty} == {math.radians(DEFAULT_STEERING_OFFSET_DEG)}
    assert len(faulty) == DEFAULT_STEERING_SWEEPS * sum(1 for e in injector.events if e.end_sweep <= 20_000) + (
        0 if injector.active is None else injector.active.sweeps)
    expected, sd = 0.05 * injector.offered, math.sqrt(injector.offered * 0.05 * 0.95)
    assert abs(injector.started - expected) < 4 * sd
    assert SteeringFault(FaultSpec(), 11).on_sweep() == 0.0


def test_loss_of_control_is_a_spin_or_leaving_the_road() -> None:
    assert lost_control(ROAD.lane_width_m / 2, 0.3) is None
    assert "spun" in (lost_control(0.0, -1.7) or "")
    assert "left the road" in (lost_control(-ROAD.lane_width_m - 0.1, 0.0) or "")


def test_the_default_steering_fault_spins_the_car_at_the_overtaking_speed() -> None:
    from sim.executor import Executor
    from sim.scene import Scene
    from sim.vehicle import WheeledCar

    def worst_yaw(offset_deg: float) -> float:
        scene = Scene()
        try:
            car = WheeledCar(scene, 0.0, scene.lane_y(Lane.LEFT))
            executor = Executor(scene, car, Lane.LEFT, GRID)
            executor.hold(4.0, 2 * float(GRID.speed), lambda dt: True)
            executor.steer_offset_rad = math.radians(offset_deg)
            yaws: list[float] = []
            executor.hold(DEFAULT_STEERING_SWEEPS / SENSORS.sweep_hz, 2 * float(GRID.speed),
                          lambda dt: yaws.append(abs(car.pose().yaw_rad)) is None)
            executor.steer_offset_rad = 0.0  # the fault is over; does the car come back?
            executor.hold(3.0, 2 * float(GRID.speed), lambda dt: yaws.append(abs(car.pose().yaw_rad)) is None)
            return max(yaws)
        finally:
            scene.close()

    assert worst_yaw(DEFAULT_STEERING_OFFSET_DEG) > math.pi / 2  # a spin, as in the paper
    assert worst_yaw(DEFAULT_STEERING_OFFSET_DEG - 15) < math.pi / 2  # the next smaller step does not


def test_sensors_sweep_at_their_stated_rate_whenever_the_planner_decides() -> None:
    from sim.parts import DriveConfig
    from sim.simulator import run_drive

    summary = run_drive(1, DriveConfig(0.3))
    assert abs(summary.sweeps - summary.sim_time_s * SENSORS.sweep_hz) <= 1
    assert summary.faults == {}


def test_a_drive_with_every_sweep_dropped_never_plans_and_counts_each_unread_snapshot() -> None:
    from sim.parts import DriveConfig
    from sim.simulator import run_drive
    from spec.kinds import FailureKind

    summary = run_drive(1, DriveConfig(0.3, faults="dropped-sweep=1/1"))
    assert summary.plans == 0 and summary.failures
    assert {(f.kind, f.cause) for f in summary.failures} == {(FailureKind.SENSING, "the sensors' last sweep never "
                                                                                   "arrived")}
    assert summary.faults["dropped-sweep"]["sweeps"] == summary.sweeps
    assert {f.fault for f in summary.failures} == {"dropped-sweep"} and summary.crash is None


def test_a_steering_fault_that_spins_the_car_is_a_loss_of_control() -> None:
    from sim.parts import DriveConfig
    from sim.simulator import run_drive
    from spec.kinds import FailureKind

    summary = run_drive(1, DriveConfig(0.5, faults="steering=1"))
    assert summary.failure is not None and summary.failure.kind is FailureKind.LOSS_OF_CONTROL
    assert "steering offset" in summary.failure.detail and summary.failure.fault == "steering"


def test_an_encounter_under_an_injected_steering_fault_is_after_an_assumption_broke() -> None:
    """The envelope is what the proofs assume of the AV's own motion: an injected steering fault under way breaks it
    (the world's fault, as a sensing fault is), whatever the vehicle or the fallback did; once it has ended, the
    rules before judge again (the executor's own envelope error counts as inside)."""
    from types import SimpleNamespace

    from sim.faults import FaultEvent
    from sim.simulator import Simulator

    fault = FaultEvent(FaultKind.STEERING, 40, (), 70, offset_rad=-math.radians(60))
    steering = SimpleNamespace(active=fault)
    sim = SimpleNamespace(steering=steering, takeover=None, containment=SimpleNamespace(breached={}), previous=None,
                          watch=object(), doing="drive (plan 8, step 1 of 2)", summary=SimpleNamespace(sim_time_s=9.0),
                          _hidden=lambda c, body: None)

    def judged() -> str | None:
        return Simulator._attribution(sim, 12)  # type: ignore[arg-type]

    assert judged() == "after an assumption broke: steering fault (-60 degrees) under way"
    sim.takeover = SimpleNamespace(after_breach=False, t_s=8.0, cause="no plan")
    assert judged() == "after an assumption broke: steering fault (-60 degrees) under way"
    steering.active = None
    assert judged() == "inside the assumptions: fallback since 8.0 s (no plan)"
    sim.takeover = None
    assert judged() == "inside the assumptions"
    sim.watch, sim.containment, steering.active = None, None, fault  # without bounds nothing is attributed
    assert judged() is None


def test_a_failure_is_attributed_by_the_stated_rule() -> None:
    from sim.faults import FaultEvent, attribute

    gap = FaultEvent(FaultKind.FAKE_GAP, 1, (4, 5), 31)
    ghost = FaultEvent(FaultKind.GHOST_LEFT, 3, (), 33)
    split = FaultEvent(FaultKind.SPLIT, 5, (9,), 35)
    steer = FaultEvent(FaultKind.STEERING, 6, (), 26)
    assert attribute(5, [gap, ghost, split], [steer]) is steer  # steering moves the AV whatever the plan
    assert attribute(5, [gap, ghost, split], []) is gap  # the last that touched the vehicle in the collision
    assert attribute(7, [gap, ghost, split], []) is ghost  # else the last that touched no vehicle
    assert attribute(7, [gap, split], []) is split  # else the last sensing fault: what it added may hold the AV
    assert attribute(7, [], []) is None
    assert attribute(None, [gap, split, ghost], []) is ghost  # no vehicle (a stop): the last sensing fault
    assert attribute(None, [], []) is None


def test_only_collisions_and_losses_of_control_end_a_run_until_failure() -> None:
    from spec.kinds import FailureKind

    assert {k for k in FailureKind if k.ends_run} == {FailureKind.COLLISION, FailureKind.LOSS_OF_CONTROL}


def test_until_a_sensing_failure_only_a_sensing_fault_ends_the_run() -> None:
    """The reliability target counts km between failures a sensing fault caused: a steering fault's loss of control
    and a collision no fault touched are counted, and the drive goes on; the first sensing-caused one ends it."""
    from sim.summary import Failure, RunSummary
    from spec.kinds import FailureKind

    spun = Failure(FailureKind.LOSS_OF_CONTROL, "spun", "", 1.0, 10.0, fault="steering")
    own = Failure(FailureKind.COLLISION, "collision", "", 2.0, 20.0)
    stop = Failure(FailureKind.SENSING, "unreadable", "", 2.5, 25.0, fault="same-cell")
    gap = Failure(FailureKind.COLLISION, "collision", "", 3.0, 30.0, fault="fake-gap")
    summary = RunSummary(1, failures=[spun, own, stop, gap])
    assert summary.ended(False) is spun and summary.ended(True) is gap and summary.sensing_crash is gap
    assert RunSummary(1, failures=[spun, own, stop]).ended(True) is None


def test_until_a_sensing_failure_a_steering_loss_of_control_restarts_the_drive() -> None:
    from sim.parts import DriveConfig
    from sim.simulator import run_drive
    from spec.kinds import FailureKind

    summary = run_drive(1, DriveConfig(0.3, faults="steering=0.02", until_sensing_failure=True))
    losses = summary.of_kind(FailureKind.LOSS_OF_CONTROL)
    assert len(losses) >= 2 and summary.restarts >= 2 and summary.sensing_crash is None and summary.km >= 0.3
    assert run_drive(1, DriveConfig(0.3, faults="steering=0.02", until_failure=True)).restarts == 0


def test_the_faults_table_counts_every_failure_of_a_run_that_started_again() -> None:
    """A run that starts again after a failure (the audit, --until-sensing-failure) may have several: each counts
    under its fault, not only the run's first."""
    from sim.summary import Failure, RunSummary
    from sim.tables import faults_table
    from spec.kinds import FailureKind

    spun = Failure(FailureKind.LOSS_OF_CONTROL, "spun", "", 1.0, 10.0, fault="steering", flagged=False)
    gaps = [Failure(FailureKind.COLLISION, "collision", "", km, km * 10, fault="fake-gap", flagged=True)
            for km in (2.0, 3.0)]
    stats = {"offered": 10, "started": 2, "sweeps": 60}
    summary = RunSummary(1, km=100.0, failures=[spun, *gaps], faults={"fake-gap": stats, "steering": stats})
    table = faults_table([summary])
    failures = dict(zip(table.columns[0]._cells, table.columns[4]._cells, strict=True))
    flagged = dict(zip(table.columns[0]._cells, table.columns[6]._cells, strict=True))
    assert failures == {"fake-gap": "2", "steering": "1", "(no fault)": "0"}
    assert flagged["fake-gap"] == "2" and flagged["steering"] == "0"
