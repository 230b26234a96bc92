"""Short closed-loop drives: sense, discretise, plan, execute, check against the prediction."""

from __future__ import annotations

import pytest

import sim.parts as parts_module
from sim.driver.control import Steps
from sim.parts import DriveConfig
from sim.simulator import START_UP_S, Simulator
from spec.actions import Action
from spec.errors import ScenarioError
from spec.kinds import FailureKind, ViolationKind
from spec.physical import LOOP


def paper_simulator(seed: int, **kw: object) -> Simulator:
    """The paper's assembly (interpreter, sensible, 21 m cells) for ``seed``."""
    return Simulator(seed, DriveConfig(1.0).parts(), **kw)  # type: ignore[arg-type]


@pytest.mark.parametrize("seed", [1, 3, 4])
def test_one_kilometre_without_collision_and_every_plan_found(seed: int) -> None:
    heard: list[tuple[int, float]] = []
    sim = paper_simulator(seed, report=heard.append)
    try:
        summary = sim.drive(1.0)
    finally:
        sim.close()
    assert summary.km >= 1.0 and not summary.collisions and not summary.planner_failures
    assert len(heard) == 1 and heard[0][0] == seed and 1.0 <= heard[0][1] < 1.01  # progress after the kilometre
    assert summary.overtakes >= 1 and summary.plans > 0
    assert summary.tolerance.checks["accelerate"] > 0  # deviations are measured per action type
    assert all(isinstance(v.kind, ViolationKind) for v in summary.tolerance.violations)


def test_drives_are_reproducible_from_the_seed() -> None:
    runs = []
    for _ in range(2):
        sim = paper_simulator(7)
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

    from tests.conftest import run_cli as run

    done = run("simulate", "--km", "0.3", "--seed", "3", "--out", str(tmp_path), "--step-tolerance", "0.05", "--json")
    runs = json.loads(done.stdout)
    assert done.returncode == 0 and runs[0]["seed"] == 3 and runs[0]["km"] >= 0.3 and runs[0]["failure"] is None
    assert runs[0]["tolerance"]["step_tolerance_cells"] == 0.05 and runs[0]["tolerance"]["violations"] > 0
    steps = [json.loads(line) for line in (tmp_path / "trace-seed3.jsonl").read_text().splitlines()]
    recorded = [v for step in steps for v in step["violations"]]
    assert len(recorded) == runs[0]["tolerance"]["violations"]  # every violation is in the trace, with its values
    assert {"step", "action", "predicted_cells", "measured_cells"} <= set(recorded[0])
    assert (tmp_path / "trace-seed3.jsonl").stat().st_size > 0 and (tmp_path / "spacetime-seed3.png").exists()


def test_a_replan_that_cannot_plan_keeps_the_plan_under_way_and_says_why(monkeypatch: pytest.MonkeyPatch) -> None:
    def unusable(*_args: object, **_kwargs: object) -> None:
        raise ScenarioError("left_lane", [11, 11], "two vehicles in one cell")

    sim = paper_simulator(3)
    try:
        sim.drive(0.3)
        monkeypatch.setattr(parts_module, "discretise", unusable)
        sim.driver.pending = (Action.DRIVE,) * 12
        actions = sim.summary.actions
        assert sim.decide_once()
        # at most 10, then re-plan
        assert sim.summary.actions == actions + 10 and sim.driver.pending == (Action.DRIVE,) * 2
        kept = [(f.kind, f.cause) for f in sim.summary.kept_plans]
        assert kept == [(FailureKind.SENSING, "two vehicles in one cell")]
        assert not sim.summary.failures
        sim.driver.pending = ()
        sim.decide_once()  # no plan under way: now it is a failure
        assert [(f.kind, f.cause) for f in sim.summary.failures] == [(FailureKind.SENSING, "two vehicles in one cell")]
    finally:
        sim.close()


def test_tables_name_failure_kinds_by_their_value() -> None:
    from rich.console import Console

    from sim.summary import Failure, RunSummary
    from sim.tables import totals_table

    summary = RunSummary(1, km=2.0, plan_ms=[1.0], failures=[Failure(FailureKind.COLLISION, "hit", "detail", 1.0, 9.0)],
                         kept_plans=[Failure(FailureKind.PLANNER, "no_plan", "detail", 0.5, 4.0)])
    console = Console(record=True, width=200)
    console.print(totals_table([summary]))
    text = console.export_text()
    assert "collision: hit" in text and "kept after planner: no_plan" in text and "FailureKind" not in text


class Standing(Simulator):
    """A simulator whose AV stands wherever a decision would be taken: a world it can never get through."""

    def _one_plan(self) -> Steps:
        return (yield from self.executor.holding(LOOP.wait_s, 0.0))


@pytest.mark.parametrize("restart", [False, True])
def test_an_av_that_stands_for_the_blocked_bound_ends_its_episode_never_the_drive_hanging(restart: bool) -> None:
    """Less than a car length in ``BLOCKED_S`` of simulated time: the episode is given up as blocked (a stop, not a
    failure proper); the drive ends there, or starts again as after a collision (not counted among the restarts)."""
    from sim.simulator import BLOCKED_S

    sim = Standing(1, DriveConfig(1.0).parts(), restart_after_collision=restart)
    try:
        summary = sim.drive(0.1 if restart else 1.0)
    finally:
        sim.close()
    blocked = summary.of_kind(FailureKind.BLOCKED)
    assert blocked and summary.crash is None and summary.restarts == 0
    if restart:  # each episode's start-up moves the AV on: the drive ends its distance, blocked again and again
        assert summary.km >= 0.1 and len(blocked) >= 2
    else:
        assert len(blocked) == 1 and summary.km < 0.1
    # each episode: its start-up, the decisions' waits until the car has stopped, then the bound
    starts = [0.0] + [f.t_s for f in blocked[:-1]]
    assert all(BLOCKED_S < f.t_s - t0 <= BLOCKED_S + START_UP_S + 3 * LOOP.wait_s for f, t0 in zip(blocked, starts))


def test_the_blocked_bound_is_beyond_every_stop_and_wait_the_world_and_the_fallback_state() -> None:
    from sim.simulator import BLOCKED_S
    from spec.envelope import MINIMAL_RISK
    from spec.physical import EVENTS, SPEEDS

    longest_stop_s = (SPEEDS.mean_mps + SPEEDS.cut_sd * SPEEDS.sd_mps) / EVENTS.stop_decel_mps2 + EVENTS.stop_hold_s
    assert max(longest_stop_s, MINIMAL_RISK.return_wait_s, MINIMAL_RISK.takeover_s, LOOP.wait_s) < BLOCKED_S
