"""Campaigns: runs recorded as they finish, resumed from the record, the same wherever they run."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest

import ci.simulation.campaign
from ci.shared.executors import ExecutorChoice, ExecutorKind
from ci.simulation.campaign import RUNS_FILE, simulate
from sim.parts import DriveConfig
from sim.summary import Failure, RunSummary
from spec.errors import OptionError
from spec.kinds import FailureKind

SHORT = DriveConfig(km=0.2)


def test_summary_round_trips_through_json() -> None:
    summary = RunSummary(5, km=1.5, sim_time_s=200.0, overtakes=3, plans=7, plan_ms=[0.5, 1.25],
                         failures=[Failure(FailureKind.COLLISION, "collision with an oncoming vehicle", "+4.0 m", 1.4,
                                           199.0)])
    summary.tolerance.check(1, 1, "accelerate", "left_lane[0]", -21.0, 30.0, 16.0, 0.0)
    again = RunSummary.from_json(json.loads(json.dumps(summary.to_json())))
    assert again.to_json() == summary.to_json()
    assert again.failure == summary.failures[0] and again.tolerance.violations_by_action == {"accelerate": 1}


def test_a_campaign_resumes_from_its_record_without_running_finished_seeds(tmp_path: Path,
                                                                           monkeypatch: pytest.MonkeyPatch) -> None:
    first = simulate(SHORT, [3], str(tmp_path))
    assert (tmp_path / "trace-seed3.jsonl").stat().st_size and (tmp_path / "spacetime-seed3.png").exists()

    def must_not_run(*_args: object, **_kwargs: object) -> RunSummary:
        raise AssertionError("a recorded run was run again")

    monkeypatch.setattr(ci.simulation.campaign, "run_drive", must_not_run)
    seen: list[tuple[int, bool]] = []
    again = simulate(SHORT, [3], str(tmp_path), on_done=lambda s, resumed: seen.append((s.seed, resumed)))
    assert [r.to_json() for r in again] == [r.to_json() for r in first] and seen == [(3, True)]
    # other parameters: not the same campaign; its traces would overwrite these, so it is refused, naming why
    with pytest.raises(OptionError, match=r"km = 0\.2, this campaign asks 0\.3"):
        simulate(DriveConfig(km=0.3), [3], str(tmp_path))
    with pytest.raises(OptionError, match=r"faults = '', this campaign asks 'dropped-sweep=0\.5/30'"):
        simulate(replace(SHORT, faults="dropped-sweep=0.5"), [3], str(tmp_path))


def test_a_half_written_record_is_run_again_and_fresh_forgets_the_record(tmp_path: Path) -> None:
    simulate(SHORT, [3], str(tmp_path))
    log = tmp_path / RUNS_FILE
    log.write_text(log.read_text()[:-40])  # cut short, as by an interruption
    calls: list[bool] = []
    simulate(SHORT, [3], str(tmp_path), on_done=lambda _s, resumed: calls.append(resumed))
    assert calls == [False] and log.read_text().count("\n") == 1  # the torn line removed, the run recorded again
    simulate(SHORT, [3], str(tmp_path), on_done=lambda _s, resumed: calls.append(resumed), fresh=True)
    assert calls == [False, False] and log.read_text().count("\n") == 1


def test_a_local_dask_cluster_gives_the_runs_one_process_gives(tmp_path: Path) -> None:
    here = simulate(SHORT, [3, 4], str(tmp_path / "here"))
    there = simulate(SHORT, [3, 4], str(tmp_path / "dask"), ExecutorChoice(ExecutorKind.DASK, 2))
    strip = lambda r: {k: v for k, v in r.to_json().items() if k not in ("wall_s", "plan_ms", "plan_latency_ms")}  # noqa: E731
    assert [strip(r) for r in here] == [strip(r) for r in there]
