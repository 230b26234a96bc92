"""What counts as engines agreeing, and `plan --engine all`."""

from __future__ import annotations

import json
from dataclasses import replace

from oracle.answer import Answer, Status
from oracle.conform import disagreement, disagreements
from oracle.planner import plan
from spec.actions import Action
from spec.library import builtin
from spec.models import ModelKind
from tests.oracle.test_cli import run

A, D = Action.ACCELERATE, Action.DRIVE
BASE = Answer(Status.PLAN, ModelKind.FINAL, "one", "sensible", (A, D), (), 0, 0.0)


def test_identical_answers_agree() -> None:
    assert disagreement(BASE, replace(BASE, engine="two")) is None


def test_plan_against_no_plan_disagrees() -> None:
    other = replace(BASE, engine="two", status=Status.NO_PLAN_WITHIN_HORIZON, actions=())
    assert disagreement(BASE, other) == "one says plan, two says no_plan_within_horizon"


def test_no_plan_and_no_plan_within_horizon_agree() -> None:
    a = replace(BASE, status=Status.NO_PLAN, actions=())
    assert disagreement(a, replace(a, status=Status.NO_PLAN_WITHIN_HORIZON)) is None


def test_sensible_plans_must_be_identical_and_shortest_only_equally_long() -> None:
    other = replace(BASE, engine="two", actions=(D, A))
    assert "sensible plans differ" in (disagreement(BASE, other) or "")
    short = replace(BASE, strategy="shortest")
    assert disagreement(short, replace(short, actions=(D, A))) is None
    assert "lengths differ" in (disagreement(short, replace(short, actions=(D,))) or "")


def test_models_must_match() -> None:
    assert "model" in (disagreement(BASE, replace(BASE, model=ModelKind.PREPARATIONS)) or "")


def test_incomplete_is_compared_with_nothing() -> None:
    assert disagreements([BASE, replace(BASE, status=Status.INCOMPLETE, actions=())]) == []


def test_interpreter_strategies_agree_on_the_library() -> None:
    for name in ("paper_example", "prep_case_a", "no_plan_boxed_in"):
        scenario = builtin(name).load()  # type: ignore[union-attr]
        assert disagreements([plan(scenario, "shortest"), plan(scenario, "shortest")]) == []


def test_plan_engine_all_json() -> None:
    done = run("plan", "one_target", "--engine", "all", "--json")
    result = json.loads(done.stdout)
    assert done.returncode == 0 and result["agree"] is True and result["disagreements"] == []
    assert {a["engine"] for a in result["answers"]} >= {"interpreter"}
