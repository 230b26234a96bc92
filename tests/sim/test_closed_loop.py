"""Short closed-loop drives: sense, discretise, plan, execute, check against the prediction."""

from __future__ import annotations

import pytest

from sim.simulator import Simulator


@pytest.mark.parametrize("seed", [1, 3, 4])
def test_one_kilometre_without_collision_and_every_plan_found(seed: int) -> None:
    sim = Simulator(seed)
    try:
        summary = sim.drive(1.0)
    finally:
        sim.close()
    assert summary.km >= 1.0 and not summary.collisions and not summary.planner_failures
    assert summary.overtakes >= 1 and summary.plans > 0
    assert summary.tolerance.checks["accelerate"] > 0  # deviations are measured per action type
    assert all(v.kind in ("step", "plan") for v in summary.tolerance.violations)


def test_drives_are_reproducible_from_the_seed() -> None:
    runs = []
    for _ in range(2):
        sim = Simulator(7)
        try:
            runs.append(sim.drive(0.4).to_json())
        finally:
            sim.close()
    for run in runs:
        run.pop("wall_s")
        run["plan_ms"] = None
    assert runs[0] == runs[1]
