"""Every engine translates every rule of spec/: change one field of a goal or a model, and each engine follows.

Each field of ``GoalRule`` and ``ModelRules`` gets a variant that only that field decides; the
reference is the plain search over interpreter states, which evaluates ``spec.rules`` as
written. An engine that leaves a field untranslated (reads a constant, or a goal by its kind)
answers differently on these problems. A new field without a variant here fails the test.
"""

from __future__ import annotations

import dataclasses
import itertools
import shutil
from fractions import Fraction

import pytest

from ci.shared.gen import random_scenarios
from oracle import search
from spec.actions import Action
from spec.answers import Limits, SearchResult, Status, Strategy
from spec.engines import Engine, load_engines
from spec.grid import PAPER_GRID, STANDARD_CELLS_M, Grid
from spec.lanes import Lane
from spec.library import BUILTINS
from spec.models import GOAL_RULES, MODEL_RULES, GoalKind, GoalRule, ModelKind, ModelRules
from spec.rules import goal_holds
from spec.scenario import Problem, Scenario, make_scenario, problem_for
from spec.state import State

OFF = GoalRule(GoalKind.OVERTAKE, None, False, None, False)  # every goal field off: the goal always holds
BASE_RULES = MODEL_RULES[ModelKind.FINAL]

#: One variant per field: the goal or model rules in which only that field differs from the baseline.
GOAL_VARIANTS = {
    "av_lane": dataclasses.replace(OFF, av_lane=Lane.RIGHT),
    "targets_behind": dataclasses.replace(OFF, targets_behind=True),
    "nearest_target_m": dataclasses.replace(OFF, nearest_target_m=Fraction(42)),
    "oncoming_passed": dataclasses.replace(OFF, oncoming_passed=True),
}
RULE_VARIANTS = {
    "danger_m": dataclasses.replace(BASE_RULES, danger_m=Fraction(42)),
    "max_lane_changes": dataclasses.replace(BASE_RULES, max_lane_changes=1),
}
FIXED = {"kind"}  # names the rule; every engine reads the fields, never the kind


def test_every_field_of_a_goal_and_a_model_has_a_variant() -> None:
    assert {f.name for f in dataclasses.fields(GoalRule)} - FIXED == set(GOAL_VARIANTS)
    assert {f.name for f in dataclasses.fields(ModelRules)} - FIXED == set(RULE_VARIANTS)


def scenarios(grid: Grid) -> list[Scenario]:
    library = [b.load() for b in BUILTINS] if grid == PAPER_GRID else []
    return library + list(itertools.islice(random_scenarios(17, horizon=8, grid=grid), 12))


def problems() -> list[tuple[str, Problem]]:
    out = []
    for grid in (PAPER_GRID, Grid(Fraction(21, 2)), Grid(Fraction(21, 4))):
        for scenario in scenarios(grid):
            for name, goal in GOAL_VARIANTS.items():
                problem = problem_for(scenario, ModelKind.FINAL)
                out.append((f"goal.{name}", dataclasses.replace(problem, goal=goal, horizon=min(problem.horizon, 8))))
            for name, rules in RULE_VARIANTS.items():
                problem = problem_for(scenario, ModelKind.FINAL)
                goal = GOAL_RULES[GoalKind.OVERTAKE] if name == "max_lane_changes" else GOAL_VARIANTS["av_lane"]
                out.append((f"model.{name}", dataclasses.replace(problem, rules=rules, goal=goal,
                                                                 horizon=min(problem.horizon, 8))))
    return out


def passing_problems() -> list[tuple[str, Problem]]:
    """The left-lane rule where it decides differently from the paper's grid: on each finer grid, the AV in the left
    lane with its target 1 .. |shift| - 1 cells ahead, and one action to get the target behind. ``accelerate`` moves
    the target through the AV's cell to behind it: a rule that checked only where a vehicle ends would call it a
    plan; ``spec.rules.left_path`` hits it in passing."""
    out = []
    for grid in (Grid(c) for c in STANDARD_CELLS_M):
        shift = grid.left_shift(Action.ACCELERATE)
        for ahead in range(1, abs(shift)):
            scenario = make_scenario(Lane.LEFT, [grid.av_cell + ahead], [], 1, horizon=1, grid=grid)
            problem = dataclasses.replace(problem_for(scenario, ModelKind.FINAL), goal=GOAL_VARIANTS["targets_behind"])
            out.append(("rule.left_path", problem))
    return out


PROBLEMS = problems() + passing_problems()
CASES = [(engine, strategy) for engine in load_engines().values() for strategy in engine.strategies
         if strategy in (Strategy.SENSIBLE, Strategy.SHORTEST)]


def reference(problem: Problem, strategy: Strategy) -> SearchResult:
    return search.sensible(problem) if strategy is Strategy.SENSIBLE else search.shortest_reference(problem)


@pytest.mark.parametrize(("engine", "strategy"), CASES, ids=[f"{e.name}-{s.value}" for e, s in CASES])
def test_each_engine_follows_every_rule_field(engine: Engine, strategy: Strategy) -> None:
    if engine.name == "spin" and not (shutil.which("spin") and shutil.which("gcc")):
        pytest.skip("spin or gcc not installed")
    differ = []
    for field, problem in PROBLEMS:
        ours, ref = engine.solve(problem, strategy, Limits()), reference(problem, strategy)
        assert ours.status is not Status.INCOMPLETE, (field, problem)
        same = (ours.status is Status.PLAN) == (ref.status is Status.PLAN)
        if same and ref.status is Status.PLAN:
            same = ours.actions == ref.actions if strategy is Strategy.SENSIBLE else len(ours.actions) == len(
                ref.actions)
        if not same:
            differ.append((field, problem.scenario, ours.actions, ref.actions))
    assert not differ, f"{engine.name} ignores or mistranslates: {sorted({d[0] for d in differ})}; first: {differ[0]}"


def test_the_variants_matter() -> None:
    """Each variant changes some answer against the baseline, so a test that passes is not passing vacuously."""
    for field in [*(f"goal.{n}" for n in GOAL_VARIANTS), *(f"model.{n}" for n in RULE_VARIANTS)]:
        changed = False
        for name, problem in PROBLEMS:
            if name != field:
                continue
            base_goal = OFF if name.startswith("goal.") else problem.goal
            base = dataclasses.replace(problem, goal=base_goal, rules=BASE_RULES)
            a, b = search.shortest_reference(problem), search.shortest_reference(base)
            changed |= (a.status, len(a.actions)) != (b.status, len(b.actions))
        assert changed, f"{field}: no problem where it changes the answer"


def test_the_passing_problems_decide_by_the_left_path_alone() -> None:
    """On each finer grid: the target would land behind the AV, clear of its cell (a landing-only rule accepts
    ``accelerate``), yet the reference has no plan, and coverage names the rule."""
    from oracle.coverage import IN_PASSING, rules_exercised

    grids = set()
    for name, problem in PROBLEMS:
        if name != "rule.left_path":
            continue
        grid, (cell,) = problem.grid, problem.scenario.left_lane
        landing = cell + grid.left_shift(Action.ACCELERATE)
        assert landing < grid.av_cell and goal_holds(State(Lane.LEFT, (landing,), ()), problem.goal, (0,), grid)
        assert search.shortest_reference(problem).status is not Status.PLAN
        assert IN_PASSING in rules_exercised(problem.scenario)
        grids.add(grid)
    assert grids == {Grid(c) for c in STANDARD_CELLS_M} - {PAPER_GRID}
