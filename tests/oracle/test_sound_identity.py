"""Identity: the sound model's code path (its states, time and advance, searches, validation), given zero bounds and
the paper's cell rules, gives the paper model's answers on the whole conformance example sweep.

What it shows: the sound model's bookkeeping and planners add nothing of their own; every difference between the
sound model's answers and the paper's comes from the physical checks (``spec.sound.SoundRules``) and the bounds.
The physical checks themselves do not reduce to the paper's cells at zero bounds, and must not: the paper's rules
allow gaps the safety specification refuses (``docs/sound.md``).
"""

from __future__ import annotations

import random
from dataclasses import replace

import pytest

from ci.conformance.crossval import parse_space
from oracle import sound
from oracle.engine import INTERPRETER
from oracle.interpreter import validate as paper_validate
from spec.actions import Action
from spec.answers import Limits, Status, Strategy
from spec.assumptions import Bounds, SpeedBounds
from spec.grid import PAPER_GRID
from spec.library import BUILTINS
from spec.models import ModelKind
from spec.scenario import Scenario, problem_for
from spec.sound import Checks, Sound
from tests.conftest import CI_PROFILE

SPACE = "left=2@8..20,right=1@12..30,lanes=both"  # the conformance example sweep (issue 12)
SPEED = PAPER_GRID.speed
ZERO = Bounds("zero", SpeedBounds(SPEED, SPEED), SpeedBounds(SPEED, SPEED), 0.0, False, "the identity check")


def _identity(scenario: Scenario) -> Scenario:
    return replace(scenario, sound=Sound(ZERO, checks=Checks.PAPER_CELLS))


def _differences(scenarios: list[Scenario]) -> list[str]:
    """Every (scenario, model, strategy) on which the two paths differ in status, plan or states."""
    out = []
    for scenario in scenarios:
        same = _identity(scenario)
        for kind in ModelKind:
            for strategy in Strategy:
                ours = sound.solve(problem_for(same, kind), strategy, Limits())
                paper = INTERPRETER.solve(problem_for(scenario, kind), strategy, Limits())
                if (ours.status, ours.actions, ours.states) != (paper.status, paper.actions, paper.states):
                    out.append(f"{scenario.lane.value} {scenario.left_lane} {scenario.right_lane} {kind.value} "
                               f"{strategy.value}: sound path {ours.status.value} {ours.actions}, paper "
                               f"{paper.status.value} {paper.actions}")
    return out


#: CI's whole sweep in this many parts, each a test of its own, so that the test run's workers share it out
SWEEP_PARTS = 8 if CI_PROFILE else 1


@pytest.mark.parametrize("part", range(SWEEP_PARTS))
def test_the_sound_code_path_with_the_papers_rules_gives_the_papers_answers_on_the_sweep(part: int) -> None:
    """The whole sweep in CI's profile (8,680 scenarios, both models, three strategies, in ``SWEEP_PARTS`` parts); a
    seeded sample of 200 by default."""
    every = list(parse_space(SPACE, PAPER_GRID).scenarios(PAPER_GRID, None))
    if CI_PROFILE:
        chosen = every[part::SWEEP_PARTS]
    else:
        seed = 2026
        print(f"seed {seed}")
        chosen = random.Random(seed).sample(every, 200)
    found = _differences(chosen)
    assert not found, f"{len(found)} differences, first: {found[:5]}"
    planned = sum(1 for s in chosen for k in ModelKind
                  if INTERPRETER.solve(problem_for(s, k), Strategy.SHORTEST, Limits()).actions)
    assert planned > len(chosen) // 4, "too few non-empty plans for the identity to say anything"


@pytest.mark.parametrize("name", [b.name for b in BUILTINS])
def test_validation_on_the_sound_path_agrees_with_the_papers(name: str) -> None:
    """Each built-in's paper plans, and each of them cut short, are judged alike by both paths."""
    scenario = next(b for b in BUILTINS if b.name == name).load()
    for kind in ModelKind:
        paper = INTERPRETER.solve(problem_for(scenario, kind), Strategy.SHORTEST, Limits())
        candidates: list[tuple[Action, ...]] = [paper.actions, paper.actions[:-1], (Action.ACCELERATE,) * 3]
        for actions in candidates:
            theirs = paper_validate(problem_for(scenario, kind), actions)
            ours = sound.validate(problem_for(_identity(scenario), kind), actions)
            assert ours.valid == theirs.valid, (kind, actions, ours.reason, theirs.reason)
            assert ours.states == theirs.states[:len(ours.states)]


def test_the_papers_cells_are_refused_with_bounds_that_are_not_zero() -> None:
    """The paper's cell rules say nothing about vehicles off the common speed: the identity path refuses them."""
    scenario = next(b for b in BUILTINS if b.name == "one_target").load()
    wide = replace(scenario, sound=Sound(replace(ZERO, sensing_error_m=0.5), checks=Checks.PAPER_CELLS))
    with pytest.raises(ValueError, match="zero bounds"):
        sound.solve(problem_for(wide, ModelKind.FINAL), Strategy.SHORTEST, Limits())


def test_no_plan_within_the_horizon_is_the_same_answer_on_both_paths() -> None:
    """Neither path claims more than its search shows (the pipeline's proof beyond the horizon is the paper's)."""
    scenario = next(b for b in BUILTINS if b.name == "two_targets").load()
    short = problem_for(_identity(scenario), ModelKind.FINAL, 3)
    assert sound.solve(short, Strategy.SHORTEST, Limits()).status is Status.NO_PLAN_WITHIN_HORIZON
