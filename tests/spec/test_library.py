"""Every built-in scenario gives its expected outcome, on every registered engine and strategy."""

from __future__ import annotations

import shutil

import pytest

from oracle.planner import plan
from spec.answers import Strategy
from spec.engines import load_engines
from spec.library import BUILTINS, SCENARIO_DIR

CASES = [(b, e, s) for b in BUILTINS for e in load_engines().values() for s in e.strategies
         if s in (Strategy.SENSIBLE, Strategy.SHORTEST)]


def test_every_scenario_file_is_listed() -> None:
    assert sorted(p.stem for p in SCENARIO_DIR.glob("*.toml")) == sorted(b.name for b in BUILTINS)


@pytest.mark.parametrize(("builtin", "engine", "strategy"), CASES,
                         ids=[f"{b.name}-{e.name}-{s.value}" for b, e, s in CASES])
def test_builtin_expected_outcome(builtin, engine, strategy: Strategy) -> None:
    if engine.name == "spin" and not (shutil.which("spin") and shutil.which("gcc")):
        pytest.skip("spin or gcc not installed")
    answer = plan(builtin.load(), strategy, engine=engine)
    assert builtin.expected.matches(answer, engine.prove_beyond is not None), answer
