"""The audit command: every combination driven, recorded, resumed, reported; bad input is one line, exit 2."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest

from ci.audit.campaign import AUDIT_FILE, AuditPlan, Tradeoff, _shape, plot_tradeoffs, rows, run_audit, tradeoffs
from ci.shared.executors import ExecutorChoice
from sim.parts import DriveConfig
from spec.assumptions import profile
from spec.scenario import make_scenario, measured_speeds
from spec.sound import Sound
from tests.conftest import run_cli as run


def test_an_audit_drives_every_combination_and_resumes_without_driving_again(tmp_path: Path,
                                                                              monkeypatch: pytest.MonkeyPatch) -> None:
    plan = AuditPlan((21.0, 10.5), ("paper", "following"), ("exact",), (4,), DriveConfig(0.3, snapshots=2))
    first = run_audit(plan, str(tmp_path), ExecutorChoice())
    assert [(d.config.cell_m, d.config.traffic) for d in first] == [(21.0, "paper"), (21.0, "following"),
                                                                    (10.5, "paper"), (10.5, "following")]
    assert len((tmp_path / AUDIT_FILE).read_text().splitlines()) == 4

    import ci.audit.campaign

    def must_not_run(*_args: object) -> object:
        raise AssertionError("a recorded run was driven again")

    monkeypatch.setattr(ci.audit.campaign, "run_drive", must_not_run)
    again = run_audit(plan, str(tmp_path), ExecutorChoice())
    assert [d.summary.to_json() for d in again] == [d.summary.to_json() for d in first]
    table = rows(again)
    assert [(r.cell_m, r.traffic, r.runs) for r in table] == [(21.0, "paper", 1), (21.0, "following", 1),
                                                               (10.5, "paper", 1), (10.5, "following", 1)]
    assert all(r.km > 0.2 for r in table) and table[0].deviation  # deviations measured per action
    assert all(d.summary.snapshots for d in first)  # the first plan's scenario is always kept


def test_rates_are_per_1000_km_driven_over_every_run_of_a_combination() -> None:
    from ci.audit.campaign import Done
    from sim.summary import Failure, RunSummary
    from spec.kinds import FailureKind

    hit = Failure(FailureKind.COLLISION, "collision", "", 1.0, 1.0)
    config = DriveConfig(5.0)
    done = [Done(config, RunSummary(1, km=1.5, failures=[hit])), Done(config, RunSummary(2, km=2.5))]
    (row,) = rows(done)
    assert (row.runs, row.km, row.collisions) == (2, 4.0, 1) and row.collisions_per_1000_km == 250.0


def test_missed_opportunities_are_estimated_per_reason_from_the_checked_share() -> None:
    from collections import Counter

    from ci.audit.campaign import Done
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


def test_an_undefined_rate_prints_as_a_dash_never_nan() -> None:
    from collections import Counter

    from ci.audit.campaign import Done, markdown, planning_cost
    from sim.opportunity import OpportunityReport
    from sim.summary import RunSummary

    unchecked = OpportunityReport({"outside_window": Counter(qualifying=3)})
    done = [Done(DriveConfig(5.0), RunSummary(1, km=0.0, opportunities=unchecked))]
    costs = planning_cost(done, ("interpreter",))  # no snapshot kept (--snapshots 0): no figure to give
    text = markdown(rows(done), costs, {})
    assert costs and costs[0].n == 0
    assert "nan" not in text.lower() and "none" not in text.lower() and "| - |" in text and "no snapshot" in text


def test_a_deviation_quantile_is_a_bound_never_above_the_largest_seen() -> None:
    from ci.audit.campaign import Done, markdown
    from sim.summary import RunSummary
    from sim.tolerance import HISTOGRAM_BINS, ToleranceReport

    bins = [0] * (HISTOGRAM_BINS + 1)
    bins[3] = 10  # every deviation in the bin (0.03, 0.04]: its edge 0.04 exceeds the largest, 0.031
    tolerance = ToleranceReport(histogram={"drive": bins}, largest={"drive": 0.031})
    (row,) = rows([Done(DriveConfig(5.0), RunSummary(1, km=1.0, tolerance=tolerance))])
    assert row.deviation["drive"] == {"p50": 0.031, "p95": 0.031, "max": 0.031}
    assert "≤ 0.031 / ≤ 0.031 / 0.031" in markdown([row], [], {})


@pytest.mark.slow  # a whole audit through the command, both models, cost on every engine: .ci/run runs it
def test_the_audit_command_writes_its_reports(tmp_path: Path) -> None:
    done = run("audit", "--cells", "21", "--traffic", "paper", "--sensing", "exact,noisy", "--km", "0.3",
               "--workers", "1", "--engines", "interpreter", "--snapshots", "2", "--out", str(tmp_path), "--json",
               timeout_s=300)
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)
    assert [(c["cell_m"], c["sensing"], c["model"]) for c in result["combinations"]] == [
        (21.0, "exact", "paper"), (21.0, "exact", "sound"), (21.0, "noisy", "paper"), (21.0, "noisy", "sound")]
    assert {c["semantics"] for c in result["combinations"] if c["model"] == "sound"} == {"commit"}
    assert result["planning_cost"][0]["engine"] == "interpreter" and result["planning_cost"][0]["n"] >= 2
    assert {c["model"] for c in result["planning_cost"]} == {"paper", "sound (commit)"}
    for name in ("audit.json", "audit.md", "audit-safety.png", "audit-latency.png", "audit-models.png",
                 "audit-tradeoff.png", AUDIT_FILE):
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


def test_an_audit_resumed_with_other_shared_settings_is_refused_naming_the_difference(tmp_path: Path) -> None:
    from ci.audit.campaign import check_resume
    from spec.errors import OptionError

    plan = AuditPlan((21.0,), ("paper",), ("exact",), (4,), DriveConfig(0.2), ("paper", "sound"))
    run_audit(plan, str(tmp_path), ExecutorChoice())
    check_resume(tmp_path / AUDIT_FILE, AuditPlan((21.0, 10.5), ("paper",), ("exact",), (4,), DriveConfig(0.2),
                                                  ("sound",), (1.0, 2.0)), "--out")  # more combinations: resumes
    with pytest.raises(OptionError, match=r"km = 0\.2.*asks 0\.3") as refused:
        run_audit(AuditPlan((21.0,), ("paper",), ("exact",), (4,), DriveConfig(0.3)), str(tmp_path), ExecutorChoice())
    assert refused.value.key == "--out"
    with pytest.raises(OptionError, match=r"faults = ''.*asks 'fake-gap=0\.1/30'"):
        check_resume(tmp_path / AUDIT_FILE, AuditPlan((21.0,), ("paper",), ("exact",), (4,),
                                                      DriveConfig(0.2, faults="fake-gap=0.1")), "--out")


def test_rows_keep_models_and_bound_scales_apart_and_split_encounters_by_attribution() -> None:
    from ci.audit.campaign import Done
    from sim.safety import SafetyReport
    from sim.summary import RunSummary

    paper, sound = DriveConfig(1.0), DriveConfig(1.0, model="sound")
    attributed = SafetyReport(attributed={"contact after": 2, "near_miss inside": 1})
    done = [Done(paper, RunSummary(1, km=2.0, overtakes=8)), Done(sound, RunSummary(1, km=2.0, overtakes=2,
                                                                                    safety=attributed)),
            Done(replace(sound, bounds_scale=2.0), RunSummary(1, km=2.0))]
    table = rows(done)
    assert [(r.model, r.bounds_scale) for r in table] == [("paper", 1.0), ("sound", 1.0), ("sound", 2.0)]
    assert table[1].attributed_count("contact", False) == 2 and table[1].attributed_count("near_miss", True) == 1
    assert table[0].overtakes == 8 and table[1].per_1000_km(table[1].overtakes) == 1000.0


def test_the_sound_models_semantics_are_combinations_of_their_own_named_in_every_table() -> None:
    from ci.audit.campaign import Done, label, markdown
    from sim.summary import RunSummary
    from spec.escapes import Semantics

    plan = AuditPlan((21.0,), ("paper",), ("exact",), (1,), DriveConfig(1.0), ("paper", "sound"),
                     semantics=(Semantics.WHOLE, Semantics.COMMIT))
    assert [(c.model, c.semantics) for c in plan.configs()] == [
        ("paper", Semantics.WHOLE), ("sound", Semantics.WHOLE), ("sound", Semantics.COMMIT)]
    table = rows([Done(c, RunSummary(1, km=2.0, overtakes=k, unsafe_starts=k)) for k, c in enumerate(plan.configs())])
    assert [label(r) for r in table] == ["paper", "sound (whole)", "sound (commit)"]
    assert AuditPlan(models=("sound",)).configs()[0].semantics is Semantics.COMMIT  # the loop's own by default
    assert [r.overtakes for r in table] == [0, 1, 2] and table[2].to_json()["semantics"] == "commit"
    assert [r.unsafe_starts for r in table] == [0, 1, 2]  # counted apart from the waits without a plan
    assert "| sound (commit) |" in markdown(table, [], {}) and "| sound (whole) |" in markdown(table, [], {})


def test_rows_count_faults_their_failures_losses_of_control_and_unreadable_snapshots() -> None:
    from ci.audit.campaign import Done, markdown
    from sim.summary import Failure, RunSummary
    from spec.kinds import FailureKind

    config = DriveConfig(1.0, faults="fake-gap=0.01,steering=0.001")
    failures = [Failure(FailureKind.COLLISION, "collision", "", 0.5, 10.0, "fake-gap"),
                Failure(FailureKind.LOSS_OF_CONTROL, "spun", "", 0.7, 12.0, "steering"),
                Failure(FailureKind.COLLISION, "collision", "", 0.9, 14.0, None),
                Failure(FailureKind.SENSING, "dropped", "", 0.95, 15.0, "fake-gap")]  # a stop: no failure
    summaries = [RunSummary(1, km=2.0, failures=failures, faults={"fake-gap": {"offered": 90, "started": 3,
                                                                              "sweeps": 60},
                                                                 "steering": {"offered": 900, "started": 1,
                                                                              "sweeps": 20}}),
                 RunSummary(2, km=2.0, faults={"fake-gap": {"offered": 80, "started": 2, "sweeps": 40}})]
    (row,) = rows([Done(config, s) for s in summaries])
    assert row.faults == {"fake-gap": {"started": 5, "sweeps": 100, "failures": 1},
                          "steering": {"started": 1, "sweeps": 20, "failures": 1},
                          "none": {"started": 0, "sweeps": 0, "failures": 1}}
    assert (row.losses_of_control, row.unreadable) == (1, 1)
    text = markdown([row], [], {})
    assert "| 21 | paper | exact | paper | 4.0 | 5 / 100 / 1 | 1 / 20 / 1 | 1 | 1 | 1 |" in text
    (plain,) = rows([Done(DriveConfig(1.0), RunSummary(1, km=2.0))])
    assert plain.faults == {} and "Faults injected" not in markdown([plain], [], {})


def test_the_headline_puts_each_models_overtakes_beside_its_collisions_per_world_over_every_cell_size() -> None:
    """A point per model and world: the cell sizes' km, overtakes and collisions added up, the collisions inside the
    assumptions apart; the sound model named with how it decided, records without a semantics as whole plans."""
    def record(cell_m: float, model: str, km: float, overtakes: int, collisions: int, inside: int = 0,
               **more: object) -> dict[str, object]:
        return {"cell_m": cell_m, "traffic": "spread", "sensing": "noisy", "model": model, "km": km,
                "overtakes": overtakes, "collisions": collisions, "attributed": {"contact inside": inside}, **more}

    points = tradeoffs([record(21, "paper", 100, 300, 40, 30), record(21, "sound", 100, 20, 3, semantics="commit"),
                        record(10.5, "paper", 50, 100, 20, 10), record(10.5, "sound", 50, 5, 0, semantics="commit"),
                        record(21, "sound", 100, 0, 0)])
    assert points == [Tradeoff("paper", "spread", "noisy", 150, 400, 60, 40),
                      Tradeoff("sound (commit)", "spread", "noisy", 150, 25, 3, 0),
                      Tradeoff("sound (whole)", "spread", "noisy", 100, 0, 0, 0)]
    assert points[0].overtakes_per_km == pytest.approx(400 / 150)
    assert points[1].collisions_per_1000_km == pytest.approx(20.0)
    figure = plot_tradeoffs(points)
    assert len(figure.axes[0].collections) >= len(points)


def test_the_cost_pass_warms_one_verifier_per_shape_not_one_per_measured_speed() -> None:
    """A served verifier reads the AV's measured speed as data: snapshots that differ only in it share one untimed
    warm-up run; another lane, another count of vehicles or measured vehicle speeds is another shape."""
    base = replace(make_scenario("left", [12], [20], 1), sound=Sound(profile("default"), start_mps=6.5))
    assert _shape(base) == _shape(replace(base, sound=replace(base.sound, start_mps=7.25)))
    assert _shape(base) != _shape(replace(base, sound=replace(base.sound, bounds=profile("paper"))))
    assert _shape(base) != _shape(replace(make_scenario("left", [12, 15], [20], 1), sound=base.sound))
    assert _shape(base) != _shape(measured_speeds(base, [(6.0, 7.0)]))
