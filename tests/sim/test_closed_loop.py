"""Short closed-loop drives: sense, discretise, plan, execute, check against the prediction."""

from __future__ import annotations

import pytest

from sim.simulator import Simulator


@pytest.mark.parametrize("seed", [1, 3, 4])
def test_one_kilometre_without_collision_and_every_plan_found(seed: int) -> None:
    heard: list[tuple[int, float]] = []
    sim = Simulator(seed, report=heard.append)
    try:
        summary = sim.drive(1.0)
    finally:
        sim.close()
    assert summary.km >= 1.0 and not summary.collisions and not summary.planner_failures
    assert len(heard) == 1 and heard[0][0] == seed and 1.0 <= heard[0][1] < 1.01  # progress after the kilometre
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
        for wall_clock in ("wall_s", "plan_ms", "plan_latency_ms"):
            run.pop(wall_clock)
    assert runs[0] == runs[1]


def test_simulate_cli_json_trace_and_plot(tmp_path) -> None:
    import json

    from tests.oracle.test_cli import run

    done = run("simulate", "--km", "0.3", "--seed", "3", "--out", str(tmp_path), "--step-tolerance", "0.05", "--json")
    runs = json.loads(done.stdout)
    assert done.returncode == 0 and runs[0]["seed"] == 3 and runs[0]["km"] >= 0.3 and runs[0]["failure"] is None
    assert runs[0]["tolerance"]["step_tolerance_cells"] == 0.05 and runs[0]["tolerance"]["violations"] > 0
    steps = [json.loads(line) for line in (tmp_path / "trace-seed3.jsonl").read_text().splitlines()]
    recorded = [v for step in steps for v in step["violations"]]
    assert len(recorded) == runs[0]["tolerance"]["violations"]  # every violation is in the trace, with its values
    assert {"step", "action", "predicted_cells", "measured_cells"} <= set(recorded[0])
    assert (tmp_path / "trace-seed3.jsonl").stat().st_size > 0 and (tmp_path / "spacetime-seed3.png").exists()
