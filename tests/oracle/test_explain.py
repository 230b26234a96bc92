"""Explanations name a minimal blocking set: alone it leaves no plan, and without any one of them there is one."""

from __future__ import annotations

import json

import pytest

from oracle.explain import explain, keep_only
from oracle.planner import plan
from spec.answers import Status
from spec.lanes import Lane
from spec.library import BUILTINS, builtin
from spec.scenario import make_scenario
from tests.conftest import run_cli as run

NO_PLAN = [b for b in BUILTINS if b.expected.status is not Status.PLAN]


@pytest.mark.parametrize("case", NO_PLAN, ids=lambda b: b.name)
def test_library_no_plan_scenarios_are_explained_minimally(case) -> None:
    scenario = case.load()
    result = explain(scenario)
    assert not result.has_plan and result.reduced is not None
    assert plan(result.reduced).status is not Status.PLAN
    for vehicle in result.blocking:  # checked here again, independently of explain's own check
        assert plan(keep_only(scenario, set(result.blocking) - {vehicle})).status is Status.PLAN


def test_boxed_in_is_blamed_on_the_vehicle_alongside_and_the_oncoming_one() -> None:
    result = explain(builtin("no_plan_boxed_in").load())  # type: ignore[union-attr]
    assert set(result.blocking) == {(Lane.LEFT, 2), (Lane.RIGHT, 0)}


def test_removing_a_target_keeps_the_other_targets() -> None:
    scenario = make_scenario("left", [12, 14, 16], [], 3)
    reduced = keep_only(scenario, {(Lane.LEFT, 0), (Lane.LEFT, 2)})
    assert reduced.left_lane == (12, 16) and reduced.targets == 2


def test_a_scenario_with_a_plan_is_not_explained() -> None:
    assert explain(builtin("paper_example").load()).has_plan  # type: ignore[union-attr]


def test_cli_explain_json() -> None:
    done = run("explain", "no_plan_boxed_in", "--json")
    result = json.loads(done.stdout)
    assert done.returncode == 0 and not result["has_plan"] and len(result["blocking"]) == 2
    assert all(r["status"] == "plan" for r in result["removals"])
