"""Contacts and the paper's traffic: a head-on contact in the right lane and running into a vehicle in the left lane
are both collisions, and the spawn gaps follow the paper's odds (a goodness-of-fit test, seeded)."""

from __future__ import annotations

import numpy as np
from scipy.stats import chisquare

from sim.parts import DriveConfig
from sim.simulator import Simulator
from sim.traffic import left_gap_cells, oncoming_gap_cells
from spec.actions import Action
from spec.physical import TRAFFIC

FAR_M = 5_000.0
SEED = 20261123
DRAWS = 20_000
SIGNIFICANCE = 1e-3  # the chance that a correct sampler fails this test


def _alone() -> Simulator:
    """A simulator with every other vehicle far ahead, the AV at 7 m/s in its lane."""
    sim = Simulator(1, DriveConfig(1.0).parts())
    for k, car in enumerate(sim.traffic.cars()):
        car.place(FAR_M + 50 * k)
    assert sim.executor.hold(4.0, 7.0, sim._tick)
    return sim


def test_a_head_on_contact_in_the_right_lane_is_a_collision() -> None:
    sim = _alone()
    assert sim.executor.run(Action.RIGHT_LANE_CHANGE, sim._tick)
    sim.traffic.oncoming[0].place(sim.car.pose().x_m + 60.0)
    try:
        assert not sim.executor.hold(10.0, 7.0, sim._tick)  # the drive stops at the contact
        (collision,) = sim.summary.collisions
        assert "oncoming" in collision.cause and sim.safety.report.contacts == 1
    finally:
        sim.close()


def test_running_into_a_standing_vehicle_in_the_left_lane_is_a_collision() -> None:
    sim = _alone()
    ahead = sim.traffic.left[0]
    ahead.place(sim.car.pose().x_m + 30.0)
    ahead.velocity_mps = 0.0
    try:
        assert not sim.executor.hold(10.0, 7.0, sim._tick)
        (collision,) = sim.summary.collisions
        assert "left-lane" in collision.cause and sim.safety.report.contacts == 1
    finally:
        sim.close()


def test_oncoming_spawn_gaps_follow_the_papers_odds() -> None:
    rng = np.random.default_rng(SEED)
    drawn = [oncoming_gap_cells(rng) for _ in range(DRAWS)]
    counts = [drawn.count(g) for g in TRAFFIC.oncoming_gap_cells]
    expected = [float(p) * DRAWS for p in TRAFFIC.oncoming_gap_odds]
    assert sum(counts) == DRAWS and chisquare(counts, expected).pvalue > SIGNIFICANCE


def test_left_spawn_gaps_have_equal_odds_and_never_four_vehicles_without_a_gap() -> None:
    rng = np.random.default_rng(SEED)
    run, drawn, longest = 0, [], 0
    for _ in range(DRAWS):
        gap = left_gap_cells(rng, run)
        drawn.append(gap)
        run = run + 1 if gap == 1 else 1
        longest = max(longest, run)
    assert longest == TRAFFIC.max_consecutive
    free = [g for g, before in zip(drawn[1:], drawn) if before != 1]  # after a gap, every choice is open
    counts = [free.count(g) for g in TRAFFIC.left_respawn_cells]
    assert chisquare(counts).pvalue > SIGNIFICANCE
