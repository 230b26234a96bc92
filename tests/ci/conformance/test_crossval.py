"""Cross-validation: every registered property holds on the library (its lies: tests/ci/conformance/test_lies.py);
findings never stop a campaign; a campaign resumes; reproducers are written; bad input is one line, exit 2."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest

from ci.conformance.crossval import VERDICTS_FILE, Campaign, Space, check_scenario, parse_space, recorded, run_sweep
from ci.conformance.properties import PROPERTIES, PropertyName, Runs, Verdict
from ci.conformance.repro import reproduce
from ci.shared.executors import ExecutorChoice
from spec.answers import Answer, Status, Strategy
from spec.errors import EngineError, OptionError
from spec.grid import PAPER_GRID
from spec.library import BUILTINS, builtin
from spec.scenario import Scenario
from tests.conftest import run_cli

ALL_ENGINES = ("interpreter", "spin", "z3")


@pytest.mark.requires_spin
@pytest.mark.parametrize("name", list(PROPERTIES), ids=lambda n: n.value)
def test_every_registered_property_applies_to_all_engines_and_holds_on_the_library(name: PropertyName) -> None:
    prop = PROPERTIES[name]
    assert prop.applies(ALL_ENGINES)
    for entry in BUILTINS:
        scenario = entry.load()
        outcome = prop.verdict(scenario, Runs(scenario), ALL_ENGINES)
        assert outcome.verdict is Verdict.HELD, f"{entry.name}: {outcome.detail}"


def test_a_campaign_records_an_engine_error_as_a_finding_and_goes_on(tmp_path: Path,
                                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    import ci.conformance.properties

    real = ci.conformance.properties.solve
    calls = {"n": 0}

    def flaky(scenario: Scenario, strategy: Strategy, **kw: object) -> Answer:
        calls["n"] += 1
        if scenario.targets == 2:
            raise EngineError("pan failed (exit 1): boom")
        return real(scenario, strategy, **kw)  # type: ignore[arg-type]

    monkeypatch.setattr(ci.conformance.properties, "solve", flaky)
    campaign = Campaign("library", (PropertyName.VALIDITY, PropertyName.EXISTENCE), ("interpreter",))
    scenarios = [b.load() for b in BUILTINS]
    results = run_sweep(campaign, scenarios, tmp_path, ExecutorChoice())
    assert len(results) == len(BUILTINS)  # every scenario checked
    failed = [r for r in results if r["verdicts"]["validity"][0] == "failed"]
    assert failed and all("boom" in r["verdicts"]["validity"][1] for r in failed)
    assert len((tmp_path / VERDICTS_FILE).read_text().splitlines()) == len(BUILTINS)


def test_a_campaign_resumes_without_checking_again_and_skips_a_torn_line(tmp_path: Path,
                                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    campaign = Campaign("library", (PropertyName.VALIDITY,), ("interpreter",))
    scenarios = [b.load() for b in BUILTINS[:4]]
    first = run_sweep(campaign, scenarios[:3], tmp_path, ExecutorChoice())
    with (tmp_path / VERDICTS_FILE).open("a") as log:
        log.write('{"campaign": {"source": "libr')  # a kill -9 in the middle of a line
    import ci.conformance.crossval

    checked: list[int] = []
    real = ci.conformance.crossval.check_batch

    def counting(batch: list[dict[str, object]], *args: object, **kw: object) -> object:
        checked.append(len(batch))
        return real(batch, *args, **kw)  # type: ignore[arg-type]

    monkeypatch.setattr(ci.conformance.crossval, "check_batch", counting)
    again = run_sweep(campaign, scenarios, tmp_path, ExecutorChoice())
    assert checked == [1] and again[:3] == first
    assert len(recorded(tmp_path / VERDICTS_FILE, campaign)) == 4
    lines = (tmp_path / VERDICTS_FILE).read_text().splitlines()
    assert len(lines) == 4 and all(line.endswith("}") for line in lines)  # the torn line was removed


def test_an_exhaustive_space_names_its_size_and_yields_every_valid_scenario() -> None:
    space = parse_space("left=1@8..10,right=1@12..13,lanes=left", PAPER_GRID)
    assert space == Space(1, (8, 10), 1, (12, 13), (space.lanes[0],))
    assert space.candidates() == (1 + 3) * (1 + 2) * 1 * 4
    scenarios = list(space.scenarios(PAPER_GRID, None))
    assert len(scenarios) == len(set(scenarios)) and 0 < len(scenarios) <= space.candidates()
    assert all(s.targets <= sum(1 for c in s.left_lane if c >= PAPER_GRID.av_cell) for s in scenarios)
    with pytest.raises(OptionError, match="--space"):
        parse_space("left=2@8..300,right=1@1..2", PAPER_GRID)


def test_check_scenario_reports_the_rules_it_exercised() -> None:
    result = check_scenario(builtin("oncoming_forces_wait").load(), [PropertyName.VALIDITY],  # type: ignore[union-attr]
                            ("interpreter",), None)
    assert result["verdicts"]["validity"][0] == "held"
    assert {"guard: lane", "collision: oncoming, on a tick", "model: final"} <= set(result["rules"])
    assert "model: preparations" not in result["rules"]  # the final model had a plan: the next is not consulted


def test_a_reproducer_is_a_scenario_file_a_test_and_traces(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import ci.conformance.properties

    real = ci.conformance.properties.solve

    def wrong(scenario: Scenario, strategy: Strategy, **kw: object) -> Answer:
        answer = real(scenario, strategy, **kw)  # type: ignore[arg-type]
        if kw.get("engine") == "z3" and answer.status is Status.PLAN and answer.actions:
            return replace(answer, actions=answer.actions[:-1])  # drops the last action: invalid
        return answer

    monkeypatch.setattr(ci.conformance.properties, "solve", wrong)
    scenario = builtin("two_targets").load()  # type: ignore[union-attr]
    written = reproduce(PropertyName.VALIDITY, scenario, ("interpreter", "z3"), None, tmp_path, 1, "two_targets")
    assert written["verdict"] == "failed" and "z3/shortest" in written["detail"]
    assert written["vehicles"] <= len(scenario.left_lane) + len(scenario.right_lane)
    for key in ("scenario_file", "test_file", "traces_file"):
        assert Path(written[key]).stat().st_size > 0
    assert "first difference" in Path(written["traces_file"]).read_text()
    compile(Path(written["test_file"]).read_text(), written["test_file"], "exec")


def test_crossval_on_the_library_exits_zero_and_writes_its_reports(tmp_path: Path) -> None:
    done = run_cli("crossval", "--engines", "interpreter,z3", "--properties", "existence,validity,shortest_length",
                   "--workers", "1", "--out", str(tmp_path), "--json", timeout_s=300)
    assert done.returncode == 0, done.stderr
    data = json.loads(done.stdout)
    assert data["properties"]["validity"] == {"checked": len(BUILTINS), "held": len(BUILTINS), "failed": 0,
                                              "incomplete": 0}
    assert set(data["latency"]) == {"interpreter/sensible", "interpreter/shortest", "z3/shortest"}
    for name in ("summary.json", "summary.md", "junit.xml", VERDICTS_FILE):
        assert (tmp_path / name).stat().st_size > 0


def test_crossval_with_hypothesis_prints_its_seed_and_records_verdicts(tmp_path: Path) -> None:
    done = run_cli("crossval", "--source", "hypothesis", "--seed", "11", "--engines", "interpreter",
                   "--properties", "validity,no_plan_proof", "--workers", "1", "--out", str(tmp_path), "--json",
                   timeout_s=300)
    assert done.returncode == 0, done.stderr
    assert "seed 11" in done.stderr
    data = json.loads(done.stdout)
    assert data["properties"]["validity"]["checked"] > 0 and data["properties"]["no_plan_proof"]["checked"] > 0


def test_count_spreads_its_scenarios_evenly_through_the_source_in_order() -> None:
    from ci.conformance.crossval import spread

    space = list(parse_space("left=2@8..12,right=1@12..16,lanes=both", PAPER_GRID).scenarios(PAPER_GRID, None))
    picked = spread(space, 5)
    assert len(picked) == 5 and picked[0] == space[0] and picked[-1] in space[len(space) * 4 // 5:]
    assert [space.index(s) for s in picked] == sorted(space.index(s) for s in picked)  # in the space's order
    assert spread(space, len(space) + 1) == space and spread(space, None) == space


def test_a_campaign_with_a_verdict_not_reached_and_none_failed_exits_3_and_records_its_count(tmp_path: Path) -> None:
    """Z3 given no time: every verdict that needs it is incomplete, none failed: "nothing is claimed" (exit 3),
    not "a property failed" (6); --count 2 checks two of the library's scenarios and is part of the record."""
    done = run_cli("crossval", "--engines", "interpreter,z3", "--properties", "existence,shortest_length",
                   "--count", "2", "--timeout", "0.0001", "--workers", "1", "--max-reproducers", "0",
                   "--out", str(tmp_path), "--json", timeout_s=300)
    assert done.returncode == 3, done.stderr
    data = json.loads(done.stdout)
    assert data["properties"]["existence"] == {"checked": 2, "held": 0, "failed": 0, "incomplete": 2}
    assert data["campaign"]["count"] == 2


@pytest.mark.parametrize(("args", "words"), [
    (("--properties", "existence,psychic"), ["--properties", "'psychic'", "unknown property"]),
    (("--engines", "interpreter,quantum"), ["--engine", "unknown engine"]),
    (("--engines", "interpreter", "--properties", "sensible_identity"), ["--engines", "applies"]),
    (("--source", "exhaustive", "--space", "left=9"), ["--space", "expected"]),
    (("--timeout", "nan"), ["--timeout", "finite"]),
    (("--timeout", "0"), ["--timeout", "above 0"]),
    (("--out", "/proc/crossval"), ["--out", "cannot"]),
    (("--cell-m", "10.5"), ["--source", "library", "21 m"]),
])
def test_bad_crossval_input_is_one_line_exit_two(tmp_path: Path, args: tuple[str, ...], words: list[str]) -> None:
    full = args if "--out" in args else (*args, "--out", str(tmp_path))
    done = run_cli("crossval", *full)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    assert all(word in lines[0] for word in words), lines[0]


@pytest.mark.parametrize(("space", "code", "words"), [
    ("left=0@0..0,right=1@60..62,lanes=right", 7, "**missed**: no scenario exercised collision: left lane, in "
                                                  "passing at 10.5 m"),
    ("left=1@21..22,right=0@0..0,lanes=left", 0, "met"),
])
def test_a_finer_grid_campaign_that_never_passes_a_left_lane_vehicle_misses_its_coverage_target(
        tmp_path: Path, space: str, code: int, words: str) -> None:
    done = run_cli("crossval", "--source", "exhaustive", "--space", space, "--cell-m", "10.5", "--engines",
                   "interpreter", "--properties", "validity", "--coverage-target", "grid", "--workers", "1",
                   "--out", str(tmp_path), timeout_s=120)
    assert done.returncode == code, done.stderr
    data = json.loads((tmp_path / "summary.json").read_text())
    assert list(data["rule_coverage"]) == ["10.5 m"]
    assert "collision: left lane, in passing" in data["rule_coverage"]["10.5 m"]
    assert words in (tmp_path / "summary.md").read_text()
    junit = (tmp_path / "junit.xml").read_text()
    assert 'name="coverage-grid"' in junit and ("<failure" in junit) == (code == 7)


def test_rule_coverage_at_21_m_has_no_passing_rule_and_no_target_by_default(tmp_path: Path) -> None:
    done = run_cli("crossval", "--source", "exhaustive", "--space", "left=1@11..12,right=0@0..0,lanes=left",
                   "--engines", "interpreter", "--properties", "validity", "--workers", "1", "--out", str(tmp_path),
                   "--json", timeout_s=120)
    assert done.returncode == 0, done.stderr
    data = json.loads(done.stdout)
    assert list(data["rule_coverage"]) == ["21 m"] and data["coverage_target"] == {"target": "none", "missed": []}
    assert "collision: left lane, in passing" not in data["rule_coverage"]["21 m"]


def test_a_campaign_with_no_scenario_misses_its_coverage_target_at_its_own_cell_size() -> None:
    from ci.conformance.crossval import Summary
    from oracle.coverage import CoverageTarget

    summary = Summary(CoverageTarget.GRID, 10.5)
    assert summary.missed() == ["collision: left lane, in passing at 10.5 m"]
    assert Summary(CoverageTarget.GRID, 21.0).missed() == [] and list(summary.coverage()) == ["10.5 m"]
