"""Cross-validation of the sound model: ``--model sound`` campaigns record their bounds, every property holds on the
library, a campaign resumed under other bounds is refused naming the difference, an engine that answers only the
paper's rules is refused naming both, hypothesis draws bounds from its stated choices, reproducers keep the bounds."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ci.cli.crossval import _model
from ci.conformance.crossval import DRAWN, VERDICTS_FILE
from ci.conformance.hypo import ERROR_CHOICES, LATENCY_CHOICES, SPEED_CHOICES, drawn_sound, scenarios
from oracle.shrink import to_toml
from oracle.sound import reachable_sets
from spec.answers import SearchResult, Status, Strategy
from spec.assumptions import profile
from spec.engines import ENGINES, Engine, register
from spec.errors import OptionError
from spec.files import load_scenario
from spec.grid import PAPER_GRID
from spec.lanes import Lane
from spec.library import builtin
from spec.physical import LOOP
from spec.scenario import Scenario, make_scenario, problem_for
from spec.sound import Sound
from tests.conftest import run_cli


def _crossval(out: Path, *args: str) -> tuple[int, str, dict[str, Any] | None]:
    done = run_cli("crossval", "--engines", "interpreter", "--workers", "1", "--out", str(out), "--json", *args,
                   timeout_s=300)
    return done.returncode, done.stderr, (json.loads(done.stdout) if done.stdout.strip() else None)


def test_a_sound_campaign_on_the_library_holds_and_records_its_bounds(tmp_path: Path) -> None:
    code, stderr, data = _crossval(tmp_path, "--model", "sound", "--bounds", "paper")
    assert code == 0, stderr
    assert data is not None and data["campaign"]["model"] == "sound"
    assert data["campaign"]["bounds"]["same_mps"] == [7.0, 7.0]
    assert data["rule_coverage"] == {}  # the paper's rules are not the sound model's: none shown
    header = (tmp_path / "summary.md").read_text().splitlines()[2]
    assert "the sound model, bounds" in header and header.endswith("semantics whole.")
    records = [json.loads(line) for line in (tmp_path / VERDICTS_FILE).read_text().splitlines()]
    assert records and all(r["result"]["scenario"]["bounds"]["same_mps"] == [7.0, 7.0] for r in records)


def test_the_three_engines_agree_on_the_library_with_the_loops_planning_latency(tmp_path: Path) -> None:
    """The snapshot aged by the loop's budget (``Sound.age_m``: every interval widened, every phantom nearer), as the
    closed loop plans: every property holds across the interpreter, Spin and Z3; a bad latency is one line, exit 2."""
    latency = repr(LOOP.plan_budget_s)
    done = run_cli("crossval", "--engines", "interpreter,spin,z3", "--workers", "2", "--out", str(tmp_path), "--json",
                   "--model", "sound", "--latency-s", latency, timeout_s=600)
    assert done.returncode == 0, done.stderr
    data = json.loads(done.stdout)
    assert data["campaign"]["bounds"]["latency_s"] == LOOP.plan_budget_s
    assert all(p["failed"] == 0 and p["incomplete"] == 0 and p["held"] == p["checked"] > 0
               for p in data["properties"].values()), data["properties"]
    for bad in ("-1", "nan", "2"):
        code, stderr, _ = _crossval(tmp_path / bad, "--model", "sound", "--latency-s", bad)
        assert code == 2 and len(stderr.strip().splitlines()) == 1 and "--latency-s" in stderr, stderr


def test_a_campaign_resumed_under_other_bounds_is_refused_naming_the_difference(tmp_path: Path) -> None:
    code, stderr, _ = _crossval(tmp_path, "--model", "sound", "--properties", "existence")
    assert code == 0, stderr
    code, stderr, _ = _crossval(tmp_path, "--model", "sound", "--properties", "existence", "--same-mps", "6..8")
    lines = stderr.strip().splitlines()
    assert code == 2 and len(lines) == 1, stderr
    assert "--same-mps" in lines[0] or "--bounds" in lines[0]
    assert "same_mps [4.9, 9.1] there, [6.0, 8.0] here" in lines[0] and "--fresh" in lines[0]
    code, stderr, _ = _crossval(tmp_path, "--properties", "existence")  # the paper's rules: refused as well
    assert code == 2 and "--model" in stderr and "the paper's rules here" in stderr
    code, stderr, _ = _crossval(tmp_path, "--model", "sound", "--properties", "existence", "--same-mps", "6..8",
                                "--fresh")
    assert code == 0, stderr


def test_an_engine_that_answers_only_the_paper_rules_is_refused_naming_both() -> None:
    def solve(*_: object) -> SearchResult:
        return SearchResult(Status.NO_PLAN)

    paper_only = Engine("paper-only-test", (Strategy.SHORTEST,), solve, "a stand-in answering the paper's rules")
    register(paper_only)
    try:
        with pytest.raises(OptionError) as refused:
            _model("sound", lambda s: s, PAPER_GRID, "library", ("interpreter", "paper-only-test"))
        text = str(refused.value)
        assert "--engines" in text and "paper-only-test" in text and "--model sound" in text
        assert "interpreter" in text  # the engines that can answer it are named
    finally:
        del ENGINES["paper-only-test"]


def test_the_model_option_decides_the_campaign_s_assumptions() -> None:
    keep = lambda s: s  # noqa: E731  (no sound option given)
    assert _model("paper", keep, PAPER_GRID, "library", ("interpreter",)) is None
    assert _model("sound", keep, PAPER_GRID, "hypothesis", ("interpreter",)) == DRAWN
    chosen = _model("sound", keep, PAPER_GRID, "exhaustive", ("interpreter",))
    assert isinstance(chosen, Sound) and chosen.bounds == profile("default")


@settings(max_examples=60, deadline=None)
@given(st.data())
def test_hypothesis_draws_bounds_from_the_stated_choices_only(data: st.DataObject) -> None:
    sound = data.draw(drawn_sound())
    b = sound.bounds
    assert b.same_mps in SPEED_CHOICES and b.oncoming_mps in SPEED_CHOICES and b.sensing_error_m in ERROR_CHOICES
    assert b.latency_s in LATENCY_CHOICES
    scenario = data.draw(scenarios(PAPER_GRID, 10, DRAWN))
    assert scenario.sound is not None and scenario.sound.bounds.same_mps in SPEED_CHOICES


def test_a_reproducer_scenario_keeps_its_bounds_and_shows_the_reachable_sets(tmp_path: Path) -> None:
    base = builtin("one_target")  # has a plan under the paper profile
    assert base is not None
    scenario: Scenario = replace(base.load(), sound=Sound(profile("paper")))
    path = tmp_path / "repro.toml"
    path.write_text(to_toml(scenario, "a reproducer"))
    assert load_scenario(path) == scenario
    from oracle.planner import solve

    answer = solve(scenario, Strategy.SHORTEST)
    assert answer.status is Status.PLAN and answer.model is not None
    lines = reachable_sets(problem_for(scenario, answer.model), answer.actions)
    assert len(lines) == len(answer.actions) + 1
    assert all("L0" in line and "phantom-R+" in line for line in lines)


def test_bounds_a_record_of_an_older_version_lacks_are_named_as_not_recorded() -> None:
    from ci.conformance.crossval import _difference

    here = {"same_mps": [4.9, 9.1], "latency_s": 0.0}
    assert _difference(here, {"same_mps": [4.9, 9.1]}) == "latency_s not recorded there, 0.0 here"
    assert _difference(here, {"same_mps": [6.0, 8.0], "latency_s": 0.0}) == "same_mps [6.0, 8.0] there, [4.9, 9.1] here"


def test_a_commitment_campaigns_summary_names_the_semantics_it_held_the_engines_to(tmp_path: Path) -> None:
    """The bounds' own table says ``whole`` (the campaign applies its semantics to each scenario): the header says
    the campaign's."""
    code, stderr, data = _crossval(tmp_path, "--model", "sound", "--bounds", "paper", "--semantics", "commit",
                                   "--properties", "existence")
    assert code == 0, stderr
    assert data is not None and data["campaign"]["semantics"] == "commit"
    header = (tmp_path / "summary.md").read_text().splitlines()[2]
    assert header.endswith("semantics commit.") and "'semantics'" not in header


def test_z3_is_expected_to_find_the_interpreters_shortest_length_and_least_cost() -> None:
    """A scenario's runs hand Z3 what is known before it runs (``Runs._expected``): a shortest plan's length, for
    ``optimal`` the least cost the optimality property's own search finds; nothing under the commitment semantics,
    nothing before a shortest plan is made. Z3's answers are the ones it gives on a solver of its own."""
    from ci.conformance.properties import RunKey, Runs, optimum
    from oracle import bmc
    from spec.escapes import COMMIT

    scenario = replace(make_scenario(Lane.RIGHT, [13], [25], 1), sound=Sound(profile("default")))
    runs = Runs(scenario)
    z3_shortest, z3_optimal = RunKey("z3", Strategy.SHORTEST), RunKey("z3", Strategy.OPTIMAL)
    assert runs._expected(z3_optimal) == {}
    reference = runs.get(RunKey("interpreter", Strategy.SHORTEST)).answer
    assert reference is not None and reference.status is Status.PLAN and reference.model is not None
    problem = problem_for(scenario, reference.model)
    cost = optimum(problem).cost
    assert cost is not None
    assert runs._expected(z3_shortest) == {problem: bmc.Expected(len(reference.actions), None)}
    assert runs._expected(z3_optimal) == {problem: bmc.Expected(len(reference.actions), tuple(cost))}
    assert Runs(replace(scenario, sound=replace(scenario.sound, commitment=COMMIT)))._expected(z3_optimal) == {}
    with bmc.isolated():
        alone = {k: Runs(scenario).get(k).answer for k in (z3_shortest, z3_optimal)}
        told = {k: runs.get(k).answer for k in (z3_shortest, z3_optimal)}
    for key, answer in told.items():
        other = alone[key]
        assert answer is not None and other is not None
        assert (answer.status, len(answer.actions), answer.extra.get("cost")) == \
            (other.status, len(other.actions), other.extra.get("cost")), key
