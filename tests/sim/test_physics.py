"""The AV's dynamics, its controllers, and contact detection, in a real PyBullet world."""

from __future__ import annotations

import numpy as np
import pytest

from sim.executor import Executor
from sim.scene import Scene
from sim.vehicle import KinematicCar, WheeledCar
from spec.actions import ACTION_RULES, Action
from spec.constants import DEFAULT_SPEED_MPS
from spec.lanes import Lane
from spec.physical import CAR


def no_traffic(_dt: float) -> bool:
    return True


@pytest.fixture
def world():
    scene = Scene()
    car = WheeledCar(scene, 0.0, scene.lane_y(Lane.LEFT))
    yield scene, car, Executor(scene, car, Lane.LEFT)
    scene.close()


def settle(executor: Executor, speed_mps: float) -> None:
    """Reach ``speed_mps`` from rest and stay there: the position reference restarts once the speed is reached."""
    executor.hold(8.0, speed_mps, no_traffic)
    executor.reset_reference()
    executor.hold(6.0, speed_mps, no_traffic)
    executor.reset_reference()


def speeds_while(scene: Scene, car: WheeledCar, target_mps: float, seconds: float) -> np.ndarray:
    out = []
    for _ in range(round(seconds / scene.dt_s)):
        car.command(target_mps, 0.0, scene.dt_s)
        scene.step()
        out.append(car.pose().speed_mps)
    return np.array(out)


def test_acceleration_and_braking_stay_within_their_limits(world) -> None:
    scene, car, _ = world
    up = speeds_while(scene, car, 2 * DEFAULT_SPEED_MPS, 6.0)
    down = speeds_while(scene, car, 0.0, 4.0)
    window = round(0.5 / scene.dt_s)  # rates over half a second, so contact jitter does not count
    rate = lambda v: np.diff(v[::window]) / 0.5  # noqa: E731
    assert rate(up).max() <= CAR.max_accel_mps2 * 1.05
    assert -rate(down).min() <= CAR.max_brake_mps2 * 1.05
    assert up[-1] == pytest.approx(2 * DEFAULT_SPEED_MPS, abs=0.3) and down[-1] < 0.2


def test_lane_keeping_holds_the_lane_centre(world) -> None:
    scene, car, executor = world
    assert executor.hold(12.0, DEFAULT_SPEED_MPS, no_traffic)
    pose = car.pose()
    assert abs(pose.y_m - scene.lane_y(Lane.LEFT)) < 0.15 and abs(pose.yaw_rad) < 0.05


@pytest.mark.parametrize("action", [Action.DRIVE, Action.ACCELERATE, Action.BRAKE])
def test_each_speed_controller_realises_its_mapping_once_at_speed(world, action: Action) -> None:
    _scene, car, executor = world
    rule = ACTION_RULES[action]
    target = float(rule.speed_factor) * DEFAULT_SPEED_MPS
    settle(executor, target)  # already at the action's speed: the mapping is exact
    assert car.pose().speed_mps == pytest.approx(target, abs=0.1)
    start = car.pose().x_m
    assert executor.run(action, no_traffic)
    expected_m = target * rule.duration_s
    assert car.pose().x_m - start == pytest.approx(expected_m, rel=0.08)


def test_accelerating_from_the_common_speed_falls_short_of_the_model(world) -> None:
    """The grid's accelerate needs 42 m in 3 s from 7 m/s; with 3 m/s^2 at most 34.5 m are possible."""
    _scene, car, executor = world
    settle(executor, DEFAULT_SPEED_MPS)
    assert car.pose().speed_mps == pytest.approx(DEFAULT_SPEED_MPS, abs=0.1)
    start = car.pose().x_m
    executor.run(Action.ACCELERATE, no_traffic)
    covered = car.pose().x_m - start
    assert 30.0 < covered <= DEFAULT_SPEED_MPS * 3 + 0.5 * CAR.max_accel_mps2 * 9 + 1.0


@pytest.mark.parametrize(("action", "to_lane"), [(Action.RIGHT_LANE_CHANGE, Lane.RIGHT)])
def test_lane_change_moves_one_lane_width_in_the_actions_time(world, action: Action, to_lane: Lane) -> None:
    scene, car, executor = world
    executor.hold(4.0, DEFAULT_SPEED_MPS, no_traffic)
    assert executor.run(action, no_traffic)
    assert abs(car.pose().y_m - scene.lane_y(to_lane)) < 0.4 and executor.lane is to_lane
    assert executor.run(Action.LEFT_LANE_CHANGE, no_traffic)
    assert abs(car.pose().y_m - scene.lane_y(Lane.LEFT)) < 0.4


def test_a_staged_crash_is_detected_as_a_contact(world) -> None:
    scene, car, executor = world
    parked = KinematicCar(scene, 25.0, scene.lane_y(Lane.LEFT), 0.0)

    def contact(_dt: float) -> bool:
        return not scene.client.getContactPoints(car.body, parked.body)

    assert not executor.hold(12.0, DEFAULT_SPEED_MPS, contact)
