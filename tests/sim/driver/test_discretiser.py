"""The discretiser (``sim.driver.discretiser``): readings to a scenario by the rules of ``spec.cells``, against the
places the readings were drawn at."""

from __future__ import annotations

import numpy as np
import pytest

from oracle.planner import plan
from sim.driver.discretiser import discretise
from sim.driver.readings import Reading
from spec.actions import Action
from spec.answers import Strategy
from spec.errors import ScenarioError
from spec.grid import PAPER_GRID
from spec.lanes import Lane
from spec.models import ModelKind

SEED = 20261122


def test_discretiser_recovers_true_cells_from_random_placements() -> None:
    """Left-lane vehicles anywhere within half a cell of a cell's centre, oncoming ones anywhere in the cell
    beyond it (rounded towards the AV), come out in that cell."""
    rng = np.random.default_rng(SEED)
    for _ in range(500):
        lane = Lane.LEFT if rng.random() < 0.5 else Lane.RIGHT
        av, cell_m = PAPER_GRID.av_cell, PAPER_GRID.cell
        left = sorted(rng.choice([c for c in range(0, 40) if c != av], size=rng.integers(0, 5), replace=False))
        right = sorted(rng.choice(range(12, 50), size=rng.integers(0, 3), replace=False))
        readings = [Reading(Lane.LEFT, 0, (c - av + rng.uniform(-0.45, 0.45)) * cell_m) for c in left]
        readings += [Reading(Lane.RIGHT, 0, (c - av + rng.uniform(0.0, 0.95)) * cell_m) for c in right]
        scenario = discretise(tuple(readings), lane, PAPER_GRID)
        assert list(scenario.left_lane) == [int(c) for c in left]
        assert list(scenario.right_lane) == [int(c) for c in right]


def test_discretiser_drops_what_is_outside_the_window_and_keeps_the_rest() -> None:
    far = (Reading(Lane.LEFT, 0, -11 * PAPER_GRID.cell), Reading(Lane.LEFT, 1, 3 * PAPER_GRID.cell),
           Reading(Lane.RIGHT, 2, 45 * PAPER_GRID.cell))
    scenario = discretise(far, Lane.LEFT, PAPER_GRID)
    assert scenario.left_lane == (PAPER_GRID.av_cell + 3,) and scenario.right_lane == () and scenario.targets == 1


def test_own_lane_vehicle_is_never_put_in_the_avs_cell() -> None:
    assert discretise((Reading(Lane.LEFT, 0, -9.0),), Lane.LEFT, PAPER_GRID).left_lane == (PAPER_GRID.av_cell - 1,)
    assert discretise((Reading(Lane.LEFT, 0, 9.0),), Lane.LEFT, PAPER_GRID).left_lane == (PAPER_GRID.av_cell + 1,)
    assert discretise((Reading(Lane.LEFT, 0, 9.0),), Lane.RIGHT, PAPER_GRID).left_lane == (PAPER_GRID.av_cell,)


def test_an_oncoming_vehicle_41_m_ahead_is_in_the_danger_zone_so_the_av_returns_at_once() -> None:
    """41 m ahead is cell 11 (rounded towards the AV): inside the final model's danger zone, so only the
    preparations model plans, and it sends the AV straight back to its lane."""
    scenario = discretise((Reading(Lane.RIGHT, 0, 41.0),), Lane.RIGHT, PAPER_GRID)
    answer = plan(scenario, Strategy.SENSIBLE)
    assert scenario.right_lane == (PAPER_GRID.av_cell + 1,)
    assert answer.model is ModelKind.PREPARATIONS and answer.actions == (Action.LEFT_LANE_CHANGE,)


def test_two_vehicles_in_one_cell_is_a_sensing_failure() -> None:
    with pytest.raises(ScenarioError, match="two vehicles in one cell"):
        discretise((Reading(Lane.LEFT, 0, 40.0), Reading(Lane.LEFT, 1, 45.0)), Lane.LEFT, PAPER_GRID)


def test_the_sound_models_scenario_carries_where_each_vehicle_was_sensed() -> None:
    """With ``measured`` each vehicle keeps what the snapshot said of it, in its cells' order: a reading its
    distance, a kept track (``Reading.spread_m``) its interval; without it the scenario is the cells alone."""
    readings = (Reading(Lane.LEFT, 0, 52.0), Reading(Lane.LEFT, 1, 23.0, (2.0, 3.5)), Reading(Lane.RIGHT, 2, 150.0))
    plain = discretise(readings, Lane.LEFT, PAPER_GRID)
    assert plain.left_m is None and plain.right_m is None
    scenario = discretise(readings, Lane.LEFT, PAPER_GRID, measured=True)
    assert scenario.left_lane == (PAPER_GRID.av_cell + 1, PAPER_GRID.av_cell + 2)
    assert scenario.left_m == ((21.0, 26.5), (52.0, 52.0)) and scenario.right_m == ((150.0, 150.0),)


def test_the_sound_models_scenario_carries_each_vehicles_measured_speed_where_its_lane_has_them_all() -> None:
    """Tracks' speed intervals (``Reading.speed_mps``) become the scenario's ``left_mps`` / ``right_mps`` in its
    cells' order; two readings in one cell are one vehicle over the hull of both; a lane with a reading whose speed
    was not told keeps its lane's speeds (None), and the paper's rules read cells alone."""
    av = PAPER_GRID.av_cell
    readings = (Reading(Lane.LEFT, 0, 52.0, speed_mps=(6.0, 7.0)), Reading(Lane.LEFT, 1, 23.0, speed_mps=(0.0, 1.0)),
                Reading(Lane.LEFT, 3, 25.0, speed_mps=(2.0, 3.0)), Reading(Lane.RIGHT, 2, 150.0))
    scenario = discretise(readings, Lane.LEFT, PAPER_GRID, measured=True)
    assert scenario.left_lane == (av + 1, av + 2)
    assert scenario.left_mps == ((0.0, 3.0), (6.0, 7.0)) and scenario.right_mps is None
    assert discretise((readings[0], readings[3]), Lane.LEFT, PAPER_GRID).left_mps is None
    untold = (*readings[:2], Reading(Lane.LEFT, 3, 25.0))
    assert discretise(untold, Lane.LEFT, PAPER_GRID, measured=True).left_mps is None
