"""The audit command: every combination driven, recorded, resumed, reported; bad input is one line, exit 2."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from ci.audit import AUDIT_FILE, AuditPlan, rows, run_audit
from ci.executors import ExecutorChoice
from sim.parts import DriveConfig
from tests.conftest import run_cli as run


def test_an_audit_drives_every_combination_and_resumes_without_driving_again(tmp_path: Path,
                                                                              monkeypatch: pytest.MonkeyPatch) -> None:
    plan = AuditPlan((21.0, 10.5), ("paper", "following"), ("exact",), (4,), DriveConfig(0.3, snapshots=2))
    first = run_audit(plan, str(tmp_path), ExecutorChoice())
    assert [(d.config.cell_m, d.config.traffic) for d in first] == [(21.0, "paper"), (21.0, "following"),
                                                                    (10.5, "paper"), (10.5, "following")]
    assert len((tmp_path / AUDIT_FILE).read_text().splitlines()) == 4

    import ci.audit

    def must_not_run(*_args: object) -> object:
        raise AssertionError("a recorded run was driven again")

    monkeypatch.setattr(ci.audit, "run_drive", must_not_run)
    again = run_audit(plan, str(tmp_path), ExecutorChoice())
    assert [d.summary.to_json() for d in again] == [d.summary.to_json() for d in first]
    table = rows(again)
    assert [(r.cell_m, r.traffic, r.runs) for r in table] == [(21.0, "paper", 1), (21.0, "following", 1),
                                                               (10.5, "paper", 1), (10.5, "following", 1)]
    assert all(r.km > 0.2 for r in table) and table[0].deviation  # deviations measured per action
    assert all(d.summary.snapshots for d in first)  # the first plan's scenario is always kept


def test_rates_are_per_1000_km_driven_over_every_run_of_a_combination() -> None:
    from ci.audit import Done
    from sim.summary import Failure, RunSummary
    from spec.kinds import FailureKind

    hit = Failure(FailureKind.COLLISION, "collision", "", 1.0, 1.0)
    config = DriveConfig(5.0)
    done = [Done(config, RunSummary(1, km=1.5, failures=[hit])), Done(config, RunSummary(2, km=2.5))]
    (row,) = rows(done)
    assert (row.runs, row.km, row.collisions) == (2, 4.0, 1) and row.collisions_per_1000_km == 250.0


def test_missed_opportunities_are_estimated_per_reason_from_the_checked_share() -> None:
    from collections import Counter

    from ci.audit import Done
    from sim.opportunity import OpportunityReport
    from sim.summary import RunSummary

    config = DriveConfig(5.0)
    seen = OpportunityReport({"refused": Counter(qualifying=8, checked=4, missed=1, near_miss=3),
                              "delayed": Counter(qualifying=10, checked=5, missed=5)})
    (row,) = rows([Done(config, RunSummary(1, km=2.0, opportunities=seen))])
    assert row.missed_per_1000_km == 1000 * (1 / 4 * 8) / 2.0  # refused and outside the window only
    assert row.delayed_per_1000_km == 1000 * 10 / 2.0
    unchecked = OpportunityReport({"outside_window": Counter(qualifying=3)})
    (row,) = rows([Done(config, RunSummary(1, km=2.0, opportunities=unchecked))])
    assert row.missed_per_1000_km != row.missed_per_1000_km  # NaN: qualified, never checked


def test_the_audit_command_writes_its_reports(tmp_path: Path) -> None:
    done = run("audit", "--cells", "21", "--traffic", "paper", "--sensing", "exact,noisy", "--km", "0.3",
               "--workers", "1", "--engines", "interpreter", "--snapshots", "2", "--out", str(tmp_path), "--json",
               timeout_s=300)
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)
    assert [(c["cell_m"], c["sensing"]) for c in result["combinations"]] == [(21.0, "exact"), (21.0, "noisy")]
    assert result["planning_cost"][0]["engine"] == "interpreter" and result["planning_cost"][0]["n"] >= 2
    for name in ("audit.json", "audit.md", "audit-safety.png", "audit-latency.png", AUDIT_FILE):
        assert (tmp_path / name).stat().st_size > 0


@pytest.mark.parametrize(("args", "words"), [
    (("--traffic", "paper,jam"), ["--traffic", "'jam'", "unknown model"]),
    (("--sensing", "psychic"), ["--sensing", "unknown model"]),
    (("--cells", "21,10"), ["--cell-m", "not a whole number"]),
    (("--cells", "x"), ["--cells", "number"]),
    (("--stop-rate-per-h", "-1"), ["--stop-rate-per-h", "between 0 and 108000"]),
    (("--stop-rate-per-h", "1e9"), ["--stop-rate-per-h", "between 0 and 108000"]),
    (("--miss-rate", "2"), ["--miss-rate", "between 0 and 1"]),
    (("--km", "nan"), ["--km", "finite"]),
    (("--engines", "interpreter,quantum"), ["--engine", "unknown engine"]),
    (("--traffic", "paper,paper"), ["--traffic", "given twice"]),
])
def test_bad_audit_input_is_one_line_exit_two(tmp_path: Path, args: tuple[str, ...], words: list[str]) -> None:
    done = run("audit", *args, "--out", str(tmp_path))
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    assert all(word in lines[0] for word in words), lines[0]
