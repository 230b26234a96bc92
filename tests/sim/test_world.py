"""Traffic rules, sensors and the discretiser against ground truth."""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest

from sim.discretiser import cell_of, discretise, targets
from sim.scene import Scene
from sim.sensors import Reading, sweep
from sim.traffic import left_gap_cells, oncoming_gap_cells
from sim.vehicle import KinematicCar
from spec.constants import AV_CELL, SEGMENT_M
from spec.errors import ScenarioError
from spec.lanes import Lane
from spec.physical import TRAFFIC

SEED = 20261122


def test_oncoming_respawn_odds_match_the_paper() -> None:
    rng = np.random.default_rng(SEED)
    counts = Counter(oncoming_gap_cells(rng) for _ in range(20000))
    for gap, odds in zip(TRAFFIC.oncoming_gap_cells, TRAFFIC.oncoming_gap_odds, strict=True):
        assert counts[gap] / 20000 == pytest.approx(float(odds), abs=0.015)


def test_left_respawn_is_uniform_and_never_makes_four_in_a_row() -> None:
    rng = np.random.default_rng(SEED)
    gaps, run = [], 1
    for _ in range(20000):
        gap = left_gap_cells(rng, run)
        run = run + 1 if gap == 1 else 1
        assert run <= TRAFFIC.max_consecutive
        gaps.append(gap)
    counts = Counter(gaps)
    assert set(counts) == set(TRAFFIC.left_respawn_cells)
    assert max(counts.values()) / min(counts.values()) < 1.6  # equal odds, less when a gap of 1 is barred


def test_discretiser_recovers_true_cells_from_random_placements() -> None:
    rng = np.random.default_rng(SEED)
    for _ in range(500):
        lane = Lane.LEFT if rng.random() < 0.5 else Lane.RIGHT
        left = sorted(rng.choice([c for c in range(0, 40) if c != AV_CELL], size=rng.integers(0, 5), replace=False))
        right = sorted(rng.choice(range(12, 50), size=rng.integers(0, 3), replace=False))
        noise = lambda: rng.uniform(-0.45, 0.45) * SEGMENT_M  # noqa: E731
        readings = [Reading(Lane.LEFT, 0, (c - AV_CELL) * SEGMENT_M + noise()) for c in left]
        readings += [Reading(Lane.RIGHT, 0, (c - AV_CELL) * SEGMENT_M + noise()) for c in right]
        scenario = discretise(tuple(readings), lane)
        assert list(scenario.left_lane) == [int(c) for c in left]
        assert list(scenario.right_lane) == [int(c) for c in right]


def test_own_lane_vehicle_is_never_put_in_the_avs_cell() -> None:
    assert discretise((Reading(Lane.LEFT, 0, -9.0),), Lane.LEFT).left_lane == (AV_CELL - 1,)
    assert discretise((Reading(Lane.LEFT, 0, 9.0),), Lane.LEFT).left_lane == (AV_CELL + 1,)
    assert discretise((Reading(Lane.LEFT, 0, 9.0),), Lane.RIGHT).left_lane == (AV_CELL,)
    assert cell_of(-10.4) == AV_CELL and cell_of(10.6) == AV_CELL + 1


def test_two_vehicles_in_one_cell_is_a_sensing_failure() -> None:
    with pytest.raises(ScenarioError, match="two vehicles in one cell"):
        discretise((Reading(Lane.LEFT, 0, 40.0), Reading(Lane.LEFT, 1, 45.0)), Lane.LEFT)


def test_targets_are_the_first_platoon_ahead() -> None:
    assert targets([5, 11, 12, 13, 14], Lane.LEFT) == 3
    assert targets([11, 13], Lane.LEFT) == 1
    assert targets([10, 11, 20], Lane.RIGHT) == 2
    assert targets([5], Lane.LEFT) == 0


def test_sensors_keep_truth_apart_and_see_past_the_car_ahead_into_the_oncoming_lane() -> None:
    scene = Scene()
    try:
        ahead = KinematicCar(scene, 12.0, scene.lane_y(Lane.LEFT), 7.0)
        hidden = KinematicCar(scene, 40.0, scene.lane_y(Lane.LEFT), 7.0)  # behind the car ahead
        oncoming = KinematicCar(scene, 40.0, scene.lane_y(Lane.RIGHT), -7.0)
        far = KinematicCar(scene, 400.0, scene.lane_y(Lane.RIGHT), -7.0)  # beyond 357 m
        result = sweep(scene, 0.0, scene.lane_y(Lane.LEFT), [ahead, hidden], [oncoming, far])
        assert {r.body for r in result.truth} == {ahead.body, hidden.body, oncoming.body}
        assert {r.body for r in result.seen} == {ahead.body, oncoming.body}
    finally:
        scene.close()
