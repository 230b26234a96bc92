"""Seeded generation of valid random scenarios, shared by benchmarks and campaigns."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from spec.constants import AV_CELL, DEFAULT_HORIZON, ROAD_CELLS
from spec.errors import ScenarioError
from spec.lanes import Lane
from spec.scenario import Scenario, make_scenario


def random_scenarios(seed: int, max_left: int = 5, max_right: int = 2,
                     horizon: int = DEFAULT_HORIZON) -> Iterator[Scenario]:
    """An endless stream of valid scenarios: cells uniform over the window, targets up to 3."""
    rng = np.random.default_rng(seed)
    while True:
        lane = Lane.LEFT if rng.random() < 0.5 else Lane.RIGHT
        left = rng.choice(ROAD_CELLS + 1, size=rng.integers(0, max_left + 1), replace=False).tolist()
        right = rng.choice(ROAD_CELLS + 1, size=rng.integers(0, max_right + 1), replace=False).tolist()
        ahead = sum(1 for c in left if c >= AV_CELL)
        targets = int(rng.integers(0, min(ahead, 3) + 1))
        try:
            yield make_scenario(lane, left, right, targets, horizon=horizon)
        except ScenarioError:
            continue  # an initial collision: draw again


def balanced(seed: int, count: int, has_plan: object, **kw: int) -> list[Scenario]:
    """``count`` scenarios, half for which ``has_plan(scenario)`` holds and half for which it does not."""
    with_plan: list[Scenario] = []
    without: list[Scenario] = []
    half = count // 2
    for scenario in random_scenarios(seed, **kw):
        bucket = with_plan if has_plan(scenario) else without  # type: ignore[operator]
        if len(bucket) < (half if bucket is with_plan else count - half):
            bucket.append(scenario)
        if len(with_plan) + len(without) == count:
            return with_plan + without
    raise AssertionError("unreachable: the stream is endless")
