"""What counts as engines agreeing, and `plan --engine all`."""

from __future__ import annotations

from dataclasses import replace

from oracle.conform import disagreement, disagreements
from oracle.planner import plan
from spec.actions import Action
from spec.answers import Answer, Status, Strategy
from spec.library import BUILTINS
from spec.models import ModelKind

A, D = Action.ACCELERATE, Action.DRIVE
BASE = Answer(Status.PLAN, ModelKind.FINAL, "one", Strategy.SENSIBLE, (A, D), (), 0, 0.0)


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
    short = replace(BASE, strategy=Strategy.SHORTEST)
    assert disagreement(short, replace(short, actions=(D, A))) is None
    assert "lengths differ" in (disagreement(short, replace(short, actions=(D,))) or "")


def test_models_must_match() -> None:
    assert "model" in (disagreement(BASE, replace(BASE, model=ModelKind.PREPARATIONS)) or "")


def test_incomplete_is_compared_with_nothing() -> None:
    assert disagreements([BASE, replace(BASE, status=Status.INCOMPLETE, actions=())]) == []


def test_sensible_and_shortest_agree_on_existence_and_model_and_a_shorter_copy_is_caught() -> None:
    for builtin in BUILTINS:
        scenario = builtin.load()
        sensible, shortest = plan(scenario, Strategy.SENSIBLE), plan(scenario, Strategy.SHORTEST)
        assert disagreements([sensible, shortest]) == [], builtin.name
        if shortest.actions:
            clipped = replace(shortest, engine="clipped", actions=shortest.actions[:-1])
            assert disagreements([shortest, clipped]) == [
                f"shortest lengths differ: interpreter {len(shortest.actions)} vs clipped {len(clipped.actions)}"]
