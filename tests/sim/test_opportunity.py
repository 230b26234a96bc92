"""Missed opportunities and restarts: a what-if replay leaves the drive exactly as it was, an overtake with room
succeeds and one into oncoming traffic does not, and a collision starts the drive again rather than ending it."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest

from sim.executor import Executor
from sim.opportunity import MAX_ACCELERATES, Outcome, Refusal, Replay, WorldSave, _Attempt, overtake, refusal
from sim.parts import DriveConfig
from sim.scene import Scene
from sim.simulator import run_drive
from sim.traffic import FollowingTraffic, PaperTraffic
from sim.vehicle import WheeledCar
from spec.actions import Action
from spec.answers import Answer, Status, Strategy
from spec.grid import PAPER_GRID
from spec.lanes import Lane
from spec.models import ModelKind
from spec.motion import plan_profiles

FAR_M = 5_000.0


@pytest.fixture
def scene() -> Iterator[Scene]:
    world = Scene()
    yield world
    world.close()


def _road(scene: Scene, ahead_m: float, oncoming_m: float) -> tuple[WheeledCar, PaperTraffic]:
    """The AV at 7 m/s in its lane; one vehicle ``ahead_m`` ahead (centre to centre), one oncoming at
    ``oncoming_m``; every other vehicle far away."""
    car = WheeledCar(scene, 0.0, scene.lane_y(Lane.LEFT))
    traffic = PaperTraffic(scene, np.random.default_rng(1), 0.0)
    for k, other in enumerate(traffic.left):
        other.place(ahead_m if k == 0 else FAR_M + 50 * k)
    for k, other in enumerate(traffic.oncoming):
        other.place(oncoming_m if k == 0 else FAR_M + 50 * k)
    executor = Executor(scene, car, Lane.LEFT, PAPER_GRID)

    def tick(dt_s: float) -> bool:
        for other in traffic.left:
            other.place(other.x_m + 7.0 * dt_s)  # keep the scene's distances while the AV gets up to speed
        for other in traffic.oncoming:
            other.place(other.x_m + 7.0 * dt_s)
        return True

    assert executor.hold(6.0, 7.0, tick)
    return car, traffic


def test_an_overtake_with_an_empty_right_lane_is_a_missed_opportunity(scene: Scene) -> None:
    car, traffic = _road(scene, 25.0, FAR_M)
    target = traffic.left[0]
    before = (car.pose(), [c.x_m for c in traffic.cars()])
    outcome, accelerates = Replay(scene, car, traffic, PAPER_GRID).first_success(target)
    assert outcome is Outcome.MISSED and 1 <= accelerates <= 3
    assert (car.pose(), [c.x_m for c in traffic.cars()]) == before  # the world put back exactly


def test_an_overtake_into_a_near_oncoming_vehicle_is_no_opportunity(scene: Scene) -> None:
    car, traffic = _road(scene, 25.0, 120.0)
    outcome, accelerates = Replay(scene, car, traffic, PAPER_GRID).first_success(traffic.left[0])
    assert outcome in (Outcome.CONTACT, Outcome.NEAR_MISS) and accelerates == 0


def _from_the_start(scene: Scene, car: WheeledCar, traffic: PaperTraffic, target: object) -> tuple[Outcome, int]:
    """``first_success`` the plain way: every overtake driven from the saved moment, none from a checkpoint."""
    replay = Replay(scene, car, traffic, PAPER_GRID)
    start, speed_mps = WorldSave(scene, car, traffic), car.pose().speed_mps
    outcome = Outcome.NOT_PASSED
    try:
        for accelerates in range(1, MAX_ACCELERATES + 1):
            attempt = _Attempt(replay, target)  # type: ignore[arg-type]
            profiles = plan_profiles(overtake(accelerates), speed_mps, PAPER_GRID)
            if not all(attempt.run(action, profile) for action, profile in zip(overtake(accelerates)[:accelerates],
                                                                              profiles)):
                outcome, in_return = attempt.failed[0], False
            else:
                outcome, in_return = attempt.finish(profiles[accelerates:])
            start.restore()
            if outcome is Outcome.MISSED:
                return outcome, accelerates
            if outcome is not Outcome.NOT_PASSED and not in_return:
                break
    finally:
        start.close()
    return outcome, 0


@pytest.mark.parametrize("oncoming_m", [100.0, 180.0, 260.0, 340.0, 420.0, FAR_M])
@pytest.mark.parametrize("ahead_m", [15.0, 25.0, 60.0, 150.0])
def test_replaying_from_checkpoints_ends_as_replaying_every_overtake_from_the_start(
        scene: Scene, ahead_m: float, oncoming_m: float) -> None:
    car, traffic = _road(scene, ahead_m, oncoming_m)
    target = traffic.left[0]
    expected = _from_the_start(scene, car, traffic, target)
    before = (car.pose(), [c.x_m for c in traffic.cars()])
    assert Replay(scene, car, traffic, PAPER_GRID).first_success(target) == expected
    assert (car.pose(), [c.x_m for c in traffic.cars()]) == before


def test_a_traffic_model_saved_and_restored_moves_and_draws_the_same_again(scene: Scene) -> None:
    from sim.vehicle import Pose

    traffic = FollowingTraffic(scene, np.random.default_rng(3), 0.0)
    av = Pose(-10_000.0, 1.8, 0.0, 7.0)

    def run() -> list[float]:
        for _ in range(300):
            traffic.advance(1 / 30, av)
        traffic.respawn_behind(200.0)
        return [c.x_m for c in traffic.cars()] + [float(traffic.rng.random())]

    saved = traffic.save()
    first = run()
    traffic.restore(saved)
    assert run() == first


def test_a_world_save_restores_the_av_after_it_was_driven(scene: Scene) -> None:
    car, traffic = _road(scene, 25.0, FAR_M)
    saved = WorldSave(scene, car, traffic)
    before = car.pose()
    Executor(scene, car, Lane.LEFT, PAPER_GRID).run(Action.RIGHT_LANE_CHANGE, lambda dt: True)
    assert car.pose() != before
    saved.close()
    assert car.pose() == before


def test_checking_opportunities_changes_nothing_else_in_the_drive() -> None:
    base = DriveConfig(2.0, traffic="paper")
    plain = run_drive(1, base).to_json()
    checked = run_drive(1, DriveConfig(2.0, traffic="paper", opportunity_checks=1000)).to_json()
    counts = checked.pop("opportunities")["counts"]
    assert sum(c.get("checked", 0) for c in counts.values()) > 0  # replays did happen
    plain.pop("opportunities")
    for summary in (plain, checked):
        for timed in ("wall_s", "plan_ms", "plan_latency_ms"):
            summary.pop(timed)
    assert checked == plain


def _answer(status: Status, actions: tuple[Action, ...], stages: tuple[tuple[ModelKind, Status, str], ...]) -> Answer:
    return Answer(status, ModelKind.FINAL, "interpreter", Strategy.SENSIBLE, actions, (), 0, 0.0, "", stages)


@pytest.mark.parametrize(("answer", "why"), [
    (_answer(Status.PLAN, overtake(2), ((ModelKind.FINAL, Status.PLAN, ""),)), None),
    (_answer(Status.PLAN, (Action.DRIVE, *overtake(2)), ((ModelKind.FINAL, Status.PLAN, ""),)), Refusal.DELAYED),
    (_answer(Status.PLAN, (Action.ACCELERATE,), ((ModelKind.FINAL, Status.NO_PLAN, ""),
                                                 (ModelKind.PREPARATIONS, Status.PLAN, ""))), Refusal.REFUSED),
    (_answer(Status.NO_PLAN_WITHIN_HORIZON, (), ((ModelKind.FINAL, Status.NO_PLAN_WITHIN_HORIZON, ""),)),
     Refusal.REFUSED),
    (_answer(Status.PLAN, (), ((ModelKind.FINAL, Status.PLAN, ""),)), Refusal.OUTSIDE_WINDOW),
    (_answer(Status.INCOMPLETE, (), ((ModelKind.FINAL, Status.INCOMPLETE, ""),)), None),
])
def test_each_answer_that_starts_no_overtake_says_why(answer: Answer, why: Refusal | None) -> None:
    assert refusal(answer) is why


def test_a_collision_restarts_the_drive_when_asked_and_ends_it_otherwise() -> None:
    config = DriveConfig(1.8, traffic="following", cell_m=10.5)
    ended = run_drive(2, config)
    assert len(ended.collisions) == 1 and ended.km < 1.8 and ended.restarts == 0
    going = run_drive(2, DriveConfig(1.8, traffic="following", cell_m=10.5, restart_after_collision=True))
    assert going.km >= 1.8 and going.restarts == len(going.collisions) >= 1
    assert going.collisions[0] == ended.collisions[0]  # the same drive up to its first collision
