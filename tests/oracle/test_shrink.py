"""Shrinking a disagreement to a minimal reproducer, with an engine made to lie."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from oracle.engine import INTERPRETER
from oracle.shrink import _smaller, engines_disagree, shrink, to_toml
from spec import engines as registry
from spec.answers import Limits, SearchResult, Status, Strategy
from spec.engines import Engine
from spec.files import scenario_from_dict
from spec.scenario import Problem, make_scenario


def _liar(problem: Problem, strategy: Strategy, limits: Limits) -> SearchResult:
    """The interpreter, except that it claims no plan whenever two or more vehicles share the left lane."""
    if len(problem.scenario.left_lane) >= 2:
        return SearchResult(Status.NO_PLAN_WITHIN_HORIZON)
    return INTERPRETER.solve(problem, strategy, limits)


@pytest.fixture
def liar() -> Iterator[Engine]:
    engine = registry.register(Engine("liar", (Strategy.SENSIBLE, Strategy.SHORTEST), _liar, "test only"))
    yield engine
    del registry.ENGINES["liar"]


def test_shrinks_to_a_one_minimal_reproducer(liar: Engine) -> None:
    big = make_scenario("left", [3, 12, 14, 20, 33], [25, 47], 2)
    fails = engines_disagree([INTERPRETER, liar], Strategy.SENSIBLE)
    assert fails(big)
    small, checks = shrink(big, fails)
    assert fails(small) and checks > 0
    assert len(small.left_lane) == 2 and small.right_lane == () and small.targets == 0
    assert not any(fails(candidate) for candidate in _smaller(small))


def test_reproducer_is_a_loadable_scenario_file(liar: Engine) -> None:
    import tomllib

    scenario = make_scenario("right", [9, 12], [30], 1, horizon=7)
    text = to_toml(scenario, "why\nit fails")
    assert text.startswith("# why\n# it fails\n")
    assert scenario_from_dict(tomllib.loads(text)) == scenario


def test_agreeing_engines_have_nothing_to_shrink() -> None:
    fails = engines_disagree([INTERPRETER, INTERPRETER], Strategy.SHORTEST)
    assert not fails(make_scenario("left", [12], [30], 1))
