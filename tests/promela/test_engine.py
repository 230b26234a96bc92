"""The Spin engine agrees with the interpreter, and fails loudly, never with a wrong "no plan"."""

from __future__ import annotations

import os
import subprocess
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from oracle import bitplan, offsets
from oracle.interpreter import validate
from promela import render, runner
from spec.answers import Status, Strategy
from spec.errors import EngineError, ToolMissing
from spec.library import BUILTINS
from spec.models import ModelKind
from spec.scenario import Scenario, make_scenario, problem_for
from tests.conftest import scenarios_on_grids

pytestmark = pytest.mark.requires_spin
MODELS = st.sampled_from(list(ModelKind))


def agree(scenario: Scenario, model: ModelKind, strategy: Strategy) -> None:
    """Spin's answer against the interpreter's: identical sensible plans, equal shortest lengths."""
    problem = problem_for(scenario, model)
    spin = runner.search(problem, strategy)
    ours = offsets.sensible(problem) if strategy is Strategy.SENSIBLE else bitplan.shortest(problem)
    assert (spin.status is Status.PLAN) == (ours.status is Status.PLAN), (spin, ours)
    if spin.status is Status.PLAN:
        assert validate(problem, spin.actions).valid
        assert spin.states == validate(problem, spin.actions).states
        if strategy is Strategy.SENSIBLE:
            assert spin.actions == ours.actions
        else:
            assert len(spin.actions) == len(ours.actions)


@pytest.mark.parametrize("strategy", [Strategy.SENSIBLE, Strategy.SHORTEST])
@pytest.mark.parametrize("builtin", BUILTINS, ids=lambda b: b.name)
def test_library_agrees_with_the_interpreter(builtin, strategy: Strategy) -> None:
    for model in ModelKind:
        agree(builtin.load(), model, strategy)


@given(scenarios_on_grids(), MODELS, st.sampled_from([Strategy.SENSIBLE, Strategy.SHORTEST]))
def test_generated_scenarios_agree_with_the_interpreter(scenario: Scenario, model: ModelKind,
                                                        strategy: Strategy) -> None:
    agree(scenario, model, strategy)


@pytest.mark.parametrize("name", ["paper_example", "prep_case_a", "no_plan_within_horizon"])
def test_served_compiled_once_and_compiled_every_time_give_the_same_plans(name: str) -> None:
    scenario = next(b for b in BUILTINS if b.name == name).load()
    for model in ModelKind:
        problem = problem_for(scenario, model)
        results = {"compile-once, served": runner.search(problem, Strategy.SENSIBLE),
                   "compile-once": runner.search(problem, Strategy.SENSIBLE, serve=False),
                   "compile-every-time": runner.search_compiling(problem, Strategy.SENSIBLE)}
        assert len({(r.status, r.actions, r.states, r.states_explored) for r in results.values()}) == 1
        assert all(r.extra["spin_mode"] == mode for mode, r in results.items())


def test_concurrent_runs_never_share_a_trail_and_each_thread_has_its_own_server() -> None:
    cases = [make_scenario("left", [12 + k % 3], [40 - k], 1) for k in range(12)]
    problems = [problem_for(s, ModelKind.FINAL) for s in cases]
    with ThreadPoolExecutor(max_workers=6) as pool:
        results = list(pool.map(lambda p: runner.search(p, Strategy.SENSIBLE), problems))
    for problem, result in zip(problems, results, strict=True):
        assert result.actions == offsets.sensible(problem).actions
    assert len({key[2] for key in runner._SERVERS}) > 1


def test_verifier_is_cached_and_keyed(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("OVERTAKE_CACHE", str(tmp_path))
    problem = problem_for(make_scenario("left", [12], [], 1), ModelKind.FINAL)
    first, second = runner.search(problem, Strategy.SHORTEST), runner.search(problem, Strategy.SHORTEST)
    assert (first.extra["verifier_cached"], second.extra["verifier_cached"]) == (False, True)
    assert len(list(tmp_path.glob("pan-final-overtake-v2-shortest-*/pan"))) == 1


@pytest.mark.parametrize("name", ["paper_example", "prep_case_a", "no_plan_within_horizon"])
def test_every_capacity_a_scenario_fits_gives_the_same_answer(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    scenario = next(b for b in BUILTINS if b.name == name).load()
    answers = set()
    for capacities in (render.CAPACITIES, (8,), ()):
        monkeypatch.setattr(render, "CAPACITIES", capacities)
        for model in ModelKind:
            problem = problem_for(scenario, model)
            result = runner.search(problem, Strategy.SHORTEST)
            answers.add((model, result.status, result.actions, result.states, result.states_explored))
    assert len(answers) == len(ModelKind)


# -- failure modes: one clear error, never a wrong "no plan" -------------------------------------
def fake_tool(folder: Path, name: str, script: str) -> None:
    path = folder / name
    path.write_text(f"#!/bin/sh\n{script}\n")
    path.chmod(0o755)


def test_failing_spin_is_an_engine_error(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    fake_tool(tmp_path, "spin",
              'case "$1" in -V) echo "Spin Version 0.0 fake";; *) echo "spin: crashed" >&2; exit 3;; esac')
    monkeypatch.setenv("PATH", f"{tmp_path}{os.pathsep}{os.environ['PATH']}")
    monkeypatch.setenv("OVERTAKE_CACHE", str(tmp_path / "cache"))
    runner.tool_versions.cache_clear()
    try:
        with pytest.raises(EngineError, match=r"spin -a failed.*spin: crashed"):
            runner.search(problem_for(make_scenario("left", [12], [], 1), ModelKind.FINAL), Strategy.SENSIBLE)
    finally:
        runner.tool_versions.cache_clear()


def test_missing_gcc_is_tool_missing_with_the_install_hint(monkeypatch: pytest.MonkeyPatch) -> None:
    real = runner.shutil.which
    monkeypatch.setattr(runner.shutil, "which", lambda tool: None if tool == "gcc" else real(tool))
    runner.tools_on.cache_clear()  # the tools this process found on its PATH before the lookup was changed
    try:
        with pytest.raises(ToolMissing, match=r"gcc not found.*apt-get install gcc"):
            runner.search(problem_for(make_scenario("left", [12], [], 1), ModelKind.FINAL), Strategy.SENSIBLE)
    finally:
        runner.tools_on.cache_clear()


def test_missing_spin_through_the_cli_is_one_line_exit_four(tmp_path: Path) -> None:
    fake_tool(tmp_path, "python3", "")  # PATH holds nothing else: no spin, no gcc
    env = {**os.environ, "PATH": str(tmp_path)}
    import sys

    done = subprocess.run([sys.executable, "-m", "ci.cli.main", "plan", "one_target", "--engine", "spin"],
                          capture_output=True, text=True, env=env, timeout=60)
    assert done.returncode == 4 and "spin not found" in done.stderr and "apt-get install spin" in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1


def test_time_out_is_incomplete_not_no_plan(monkeypatch: pytest.MonkeyPatch) -> None:
    problem = problem_for(make_scenario("left", [12, 14, 16], [], 3, horizon=3), ModelKind.FINAL)
    runner.search(problem, Strategy.SENSIBLE)  # make sure the verifier is compiled
    real = runner._run

    def slow_pan(args, cwd=None, env=None, timeout=None):
        if args[0].endswith("/pan") and "-r" not in args:
            raise subprocess.TimeoutExpired(args, timeout or 0)
        return real(args, cwd=cwd, env=env, timeout=timeout)

    monkeypatch.setattr(runner, "_run", slow_pan)
    result = runner.search(problem, Strategy.SENSIBLE, timeout_s=0.5, serve=False)  # served: tests/promela/test_cache
    assert result.status is Status.INCOMPLETE and "time limit" in result.detail


def test_depth_limit_is_incomplete(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(runner, "DEPTH_MARGIN", -6)  # pan's depth bound below the horizon
    problem = problem_for(make_scenario("left", [12, 14, 16], [40], 3), ModelKind.FINAL)
    result = runner.search(problem, Strategy.SENSIBLE)
    assert result.status is Status.INCOMPLETE and "max search depth too small" in result.detail


def test_no_plan_within_horizon_is_reported_as_such() -> None:
    problem = problem_for(make_scenario("left", [12, 14, 16], [], 3, horizon=3), ModelKind.FINAL)
    assert runner.search(problem, Strategy.SENSIBLE).status is Status.NO_PLAN_WITHIN_HORIZON
