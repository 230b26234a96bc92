"""The paper's rules in the loop (``sim.driver.paper.PaperDriver``) with a scripted host, planner and prediction
check: each re-planning rule at its boundary, no physics engine."""

from __future__ import annotations

from dataclasses import dataclass, field

import pytest

from sim.driver.control import lane_y, perform
from sim.driver.paper import PaperDriver
from sim.driver.readings import Reading
from spec.actions import Action
from spec.answers import Answer, Status
from spec.envelope import TRACKING
from spec.grid import PAPER_GRID
from spec.kinds import FailureKind
from spec.lanes import Lane
from spec.physical import LOOP
from spec.state import State
from tests.sim.driver.test_plan import Scripted, answer
from tests.sim.driver.test_sound import DT, Host

TWELVE = (Action.DRIVE,) * 12
TEN = LOOP.replan_after_actions


@dataclass
class Prediction:
    """A scripted prediction check: the actions (from 0) after which a vehicle deviated beyond the tolerance."""

    deviates_after: set[int] = field(default_factory=set)
    expected: list[int | None] = field(default_factory=list)
    checked: list[int] = field(default_factory=list)

    def expecting(self, k: int | None) -> None:
        self.expected.append(k)

    def deviated(self, k: int, action: Action) -> bool:
        self.checked.append(k)
        return k in self.deviates_after


@dataclass
class World(Host):
    """The sound driver's scripted host (``tests.sim.driver.test_sound.Host``) with a prediction check, a vehicle
    sensed anew after the action ``anew_after`` (from 0), and the tracker's say on an overtake."""

    prediction: Prediction = field(default_factory=Prediction)
    anew_after: int | None = None
    refuse: bool = False
    anew_asked: int = 0

    def predicting(self, plan_id: int, seen: tuple[Reading, ...], states: tuple[State, ...]) -> Prediction:
        return self.prediction

    def sensed_anew(self) -> bool:
        self.anew_asked += 1
        return self.anew_asked - 1 == self.anew_after

    def refused(self, actions: tuple[Action, ...], under_way: tuple[Action, ...]) -> bool:
        return self.refuse


def decide(world: World, *answers: Answer, pending: tuple[Action, ...] = (), replan: bool = True) -> PaperDriver:
    driver = PaperDriver(world, Scripted(list(answers)), PAPER_GRID, replan)  # type: ignore[arg-type]
    driver.pending = pending
    assert perform(driver.decision(), world.step)
    return driver


def acted(world: World) -> list[Action]:
    return [a for a, _, _ in world.executor.acted]


def test_a_plan_runs_at_most_ten_actions_each_checked_against_its_prediction_the_rest_left_for_the_next() -> None:
    world = World()
    driver = decide(world, answer(Status.PLAN, *TWELVE))
    assert acted(world) == [Action.DRIVE] * TEN and driver.pending == TWELVE[TEN:]
    assert world.prediction.checked == list(range(TEN))
    assert world.prediction.expected == [x for k in range(TEN) for x in (k, None)]  # implied gaps only while acting
    assert world.summary.actions == TEN and world.summary.replans == 0 and world.executor.resets == 1


@pytest.mark.parametrize("replan", [True, False])
def test_a_deviation_beyond_the_tolerance_replans_after_its_action_only_where_the_loop_replans_on_it(
        replan: bool) -> None:
    world = World(prediction=Prediction({2}))
    driver = decide(world, answer(Status.PLAN, *TWELVE), replan=replan)
    ran = 3 if replan else TEN
    assert len(acted(world)) == ran and driver.pending == TWELVE[ran:]
    assert world.prediction.checked == list(range(ran))  # checked (and traced) after every action either way
    assert world.summary.replans == int(replan)


def test_a_vehicle_sensed_anew_replans_after_the_action_whose_sweep_shows_it() -> None:
    world = World(anew_after=1)
    driver = decide(world, answer(Status.PLAN, *TWELVE))
    assert len(acted(world)) == 2 and driver.pending == TWELVE[2:] and world.summary.replans == 1


@pytest.mark.parametrize("status", [Status.NO_PLAN, Status.NO_PLAN_WITHIN_HORIZON, Status.INCOMPLETE])
def test_without_a_plan_the_plan_under_way_goes_on_for_at_most_ten_actions_and_is_recorded(status: Status) -> None:
    world = World()
    driver = decide(world, answer(status), pending=TWELVE)
    assert acted(world) == [Action.DRIVE] * TEN and driver.pending == TWELVE[TEN:]
    [(kind, cause, _)] = world.reported("kept")  # type: ignore[misc]
    assert (kind, cause) == (FailureKind.PLANNER, status.value) and not world.reported("fail")
    assert world.executor.resets == 1 and world.summary.actions == TEN


def test_without_a_plan_or_one_under_way_the_av_waits_in_lane_and_that_is_a_failure() -> None:
    world = World()
    driver = decide(world, answer(Status.NO_PLAN))
    [(kind, cause, _)] = world.reported("fail")  # type: ignore[misc]
    assert (kind, cause) == (FailureKind.PLANNER, "no_plan") and not acted(world) and driver.pending == ()
    assert len(world.commands) == round(LOOP.wait_s / DT) and world.doing == "waiting without a plan"


@pytest.mark.parametrize("pending", [TWELVE, ()])
def test_a_dropped_sweep_keeps_the_plan_under_way_else_is_a_sensing_failure_and_a_wait(
        pending: tuple[Action, ...]) -> None:
    world = World(sweep=None)
    decide(world, pending=pending)
    report = "kept" if pending else "fail"
    [(kind, _, _)] = world.reported(report)  # type: ignore[misc]
    assert kind is FailureKind.SENSING and len(world.reported("kept" if not pending else "fail")) == 0
    assert world.containment is world.next_monitor  # measured from an empty snapshot
    assert len(acted(world)) == (TEN if pending else 0)


@pytest.mark.parametrize(("held_m", "at_m"), [(TRACKING.position_m - 0.1, TRACKING.position_m - 0.1),
                                                (TRACKING.position_m + 0.1, 0.0)])
def test_an_overtake_the_tracker_refuses_drives_on_in_lane_for_a_sweep_the_reference_held_within_the_envelope(
        held_m: float, at_m: float) -> None:
    world = World(refuse=True)
    world.executor.x_ref_m = held_m
    decide(world, answer(Status.PLAN, Action.RIGHT_LANE_CHANGE, Action.ACCELERATE))
    # one step at the common speed in lane: the next is a sweep (the scripted world sweeps every step)
    assert not acted(world) and world.commands == [(float(PAPER_GRID.speed), lane_y(Lane.LEFT), 0.0)]
    assert world.executor.x_ref_m == pytest.approx(at_m) and world.doing.startswith("driving on in lane")


def test_a_plan_with_nothing_to_overtake_drives_on_from_a_reference_at_the_car() -> None:
    world = World()
    world.executor.x_ref_m = 40.0
    decide(world, answer(Status.PLAN))
    assert acted(world) == [Action.DRIVE] and world.executor.resets == 1
    assert world.executor.x_ref_m == 4.0 and world.doing == "drive (nothing to overtake)"  # a metre a scripted step


def test_a_plan_that_stands_in_the_common_frame_starts_its_reference_where_that_frame_puts_the_av() -> None:
    """From a car at 9 m/s a plan that starts by speeding up is planned again in its first speed's frame; where that
    plan starts otherwise, the first stands (a frame fallback, counted), and its reference starts where the common
    speed's frame puts the AV (``spec.motion.reference_offset_m``), not at the car."""
    from types import SimpleNamespace

    from spec.motion import action_speed_mps, reference_offset_m

    world = World()
    world.pose = lambda: SimpleNamespace(x_m=0.0, y_m=1.75, along_mps=9.0)  # type: ignore[method-assign]
    offsets: list[float] = []
    reset = world.executor.reset_reference

    def recorded(ahead_m: float = 0.0) -> None:
        offsets.append(ahead_m)
        reset(ahead_m)

    world.executor.reset_reference = recorded  # type: ignore[method-assign]
    decide(world, answer(Status.PLAN, Action.ACCELERATE, Action.DRIVE), answer(Status.PLAN, Action.DRIVE))
    want = reference_offset_m(9.0, float(PAPER_GRID.speed), action_speed_mps(Action.ACCELERATE, PAPER_GRID))
    assert want != 0.0 and offsets == [pytest.approx(want)] and world.summary.frame_fallbacks == 1
    assert acted(world) == [Action.ACCELERATE, Action.DRIVE]
