"""The independent optimum (the check of Z3's ``optimal``) against every plan enumerated through the interpreter."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from oracle.interpreter import enabled_actions, problem_collision, problem_goal, problem_step, validate
from oracle.optimum import lexicographic_optimum, plan_cost
from spec.actions import Action
from spec.grid import PAPER_GRID
from spec.lanes import Lane
from spec.models import ModelKind
from spec.scenario import Problem, Scenario, make_scenario, problem_for
from spec.state import State
from tests.conftest import scenarios


def every_plan(problem: Problem) -> list[tuple[Action, ...]]:
    """Every plan of at most the horizon's actions, by walking every path of the interpreter (no pruning)."""
    start = problem.scenario.initial_state()
    if problem_collision(problem, start) is not None:
        return []
    plans, paths = [], [(start, ())]
    while paths:
        state, actions = paths.pop()
        if problem_goal(problem, state):
            plans.append(actions)  # a plan ends at its first goal state
            continue
        if len(actions) == problem.horizon:
            continue
        for action in enabled_actions(state, problem.rules):
            after = problem_step(problem, state, action)
            if isinstance(after, State):
                paths.append((after, (*actions, action)))
    return plans


@st.composite
def near_traffic(draw: st.DrawFn) -> Scenario:
    """A scenario with its vehicles near the AV (cell 10 of 50), as in issue 12's example space, so that overtakes
    of three to six actions are common; horizon 6, so that every path can be walked."""
    grid = PAPER_GRID
    lane = draw(st.sampled_from(list(Lane)))
    left = draw(st.lists(st.integers(grid.av_cell - 2, grid.av_cell + 6), max_size=2, unique=True))
    right = draw(st.lists(st.integers(grid.av_cell + 2, grid.av_cell + 16), max_size=1))
    left = [c for c in left if not (lane is Lane.LEFT and c == grid.av_cell)]
    ahead = sum(1 for c in left if c >= grid.av_cell)
    return make_scenario(lane, left, right, draw(st.integers(0, ahead)), horizon=6, grid=grid)


@given(scenarios(horizon=6) | near_traffic(), st.sampled_from(list(ModelKind)))
def test_the_optimum_costs_the_least_of_every_plan_and_its_plan_is_valid(scenario: Scenario,
                                                                         model: ModelKind) -> None:
    problem = problem_for(scenario, model)
    plans = every_plan(problem)
    found = lexicographic_optimum(problem)
    if not plans:
        assert found.cost is None and found.actions == ()
        return
    assert found.cost == min(plan_cost(problem, plan) for plan in plans)
    assert validate(problem, found.actions).valid
    assert plan_cost(problem, found.actions) == found.cost
