"""Properties of the planners over generated valid scenarios."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from oracle import bitplan, offsets, search
from oracle.interpreter import enabled_actions, problem_collision, problem_goal, problem_step, validate
from oracle.planner import plan
from spec.actions import Action
from spec.answers import Status, Strategy
from spec.models import ModelKind
from spec.scenario import Problem, Scenario, make_scenario, problem_for
from spec.state import Collision, State
from tests.conftest import scenarios, scenarios_on_grids

MODELS = st.sampled_from(list(ModelKind))


def all_plans(problem: Problem, max_len: int) -> list[tuple[Action, ...]]:
    """Every plan of at most ``max_len`` actions, in the action order, by brute-force enumeration.

    A prefix that collides or meets the goal cannot be extended into a plan, so the tree
    of action sequences is cut there; nothing else is pruned (no visited set).
    """
    start = problem.scenario.initial_state()
    if problem_collision(problem, start):
        return []
    found: list[tuple[Action, ...]] = []

    def walk(state: State, prefix: tuple[Action, ...]) -> None:
        if problem_goal(problem, state):
            found.append(prefix)
            return
        if len(prefix) == min(max_len, problem.horizon):
            return
        for action in enabled_actions(state, problem.rules):
            nxt = problem_step(problem, state, action)
            if not isinstance(nxt, Collision):
                walk(nxt, (*prefix, action))

    walk(start, ())
    return found


@given(scenarios_on_grids(horizon=6, max_left=4, span=25), MODELS)
def test_shortest_is_truly_shortest_and_first_in_order_by_enumeration(scenario: Scenario, model: ModelKind) -> None:
    problem = problem_for(scenario, model)
    plans = all_plans(problem, 6)
    result = bitplan.shortest(problem)
    if not plans:
        assert result.status is not Status.PLAN
        return
    best = min(len(p) for p in plans)
    first = min((p for p in plans if len(p) == best), key=lambda p: [list(Action).index(a) for a in p])
    assert result.status is Status.PLAN and result.actions == first


@given(scenarios_on_grids(), MODELS)
def test_every_returned_plan_validates_and_never_passes_the_goal_early(scenario: Scenario, model: ModelKind) -> None:
    problem = problem_for(scenario, model)
    for result in (offsets.sensible(problem), bitplan.shortest(problem)):
        if result.status is Status.PLAN:
            verdict = validate(problem, result.actions)
            assert verdict.valid, verdict.reason
            assert not any(problem_goal(problem, s) for s in verdict.states[:-1])


@given(scenarios(), MODELS)
def test_validate_reproduces_the_planners_states_exactly(scenario: Scenario, model: ModelKind) -> None:
    problem = problem_for(scenario, model)
    for result in (search.sensible(problem), bitplan.shortest(problem), search.shortest_reference(problem)):
        if result.status is Status.PLAN:
            assert validate(problem, result.actions).states == result.states


@given(scenarios(), MODELS)
def test_shortest_is_never_longer_than_sensible_and_they_agree_on_existence(
    scenario: Scenario, model: ModelKind
) -> None:
    problem = problem_for(scenario, model)
    dfs, bfs = search.sensible(problem), bitplan.shortest(problem)
    assert (dfs.status is Status.PLAN) == (bfs.status is Status.PLAN)
    if bfs.status is Status.PLAN:
        assert len(bfs.actions) <= len(dfs.actions)


@given(scenarios_on_grids(span=30), MODELS)
def test_offset_dfs_is_the_state_dfs_state_for_state_and_merged_returns_its_answer(scenario: Scenario,
                                                                                  model: ModelKind) -> None:
    problem = problem_for(scenario, model)
    ref = search.sensible(problem)
    unmerged, merged = offsets.sensible(problem, merge_saturated=False), offsets.sensible(problem)
    assert (unmerged.status, unmerged.actions, unmerged.states, unmerged.states_explored) == (
        ref.status, ref.actions, ref.states, ref.states_explored)  # one offset state per interpreter state
    if ref.status is not Status.INCOMPLETE:  # out of states, the merged search (fewer states) may still answer
        assert (merged.status, merged.actions, merged.states) == (ref.status, ref.actions, ref.states)
    assert merged.states_explored <= ref.states_explored


@given(scenarios_on_grids(span=30), MODELS, st.integers(0, 2), st.integers(-40, 40), st.integers(0, 60))
def test_past_saturation_the_oncoming_ticks_change_no_move_and_no_goal(scenario: Scenario, model: ModelKind,
                                                                      lc: int, l_off: int, beyond: int) -> None:
    unmerged = offsets.OffsetSearch(problem_for(scenario, model), merge_saturated=False)
    form, sat = unmerged.form, unmerged.form.o_saturation
    lc = min(lc, len(form.lanes) - 1)
    at_sat, later = unmerged.moves_from(lc, l_off, sat), unmerged.moves_from(lc, l_off, sat + beyond)
    assert [(a, lc2, l2) for a, (lc2, l2, _) in at_sat] == [(a, lc2, l2) for a, (lc2, l2, _) in later]
    assert form.goal(lc, l_off, sat) == form.goal(lc, l_off, sat + beyond)


@given(scenarios_on_grids(span=30), MODELS)
def test_bitset_planner_equals_the_reference_bfs(scenario: Scenario, model: ModelKind) -> None:
    problem = problem_for(scenario, model)
    fast, ref = bitplan.shortest(problem), search.shortest_reference(problem)
    assert (fast.status is Status.PLAN) == (ref.status is Status.PLAN)
    assert fast.actions == ref.actions


@given(scenarios_on_grids(span=25), MODELS)
def test_no_plan_of_any_length_is_sound(scenario: Scenario, model: ModelKind) -> None:
    problem = problem_for(scenario, model)
    if bitplan.beyond_horizon(problem).status is Status.NO_PLAN:
        longer = problem_for(scenario, model, horizon=45)
        assert bitplan.shortest(longer).status is not Status.PLAN


@given(scenarios(), st.sampled_from([Strategy.SENSIBLE, Strategy.SHORTEST]))
def test_pipeline_tries_final_then_preparations(scenario: Scenario, strategy: Strategy) -> None:
    answer = plan(scenario, strategy)
    final = problem_for(scenario, ModelKind.FINAL)
    final_has_plan = bitplan.shortest(final).status is Status.PLAN
    assert answer.stages[0][0] is ModelKind.FINAL
    if final_has_plan:
        assert answer.status is Status.PLAN and answer.model is ModelKind.FINAL
    elif answer.status is Status.PLAN:
        assert answer.model is ModelKind.PREPARATIONS


def test_incomplete_when_the_state_limit_is_hit() -> None:
    problem = problem_for(make_scenario("left", [12, 14, 16], [40], 3), ModelKind.FINAL)
    assert search.sensible(problem, max_states=5).status is Status.INCOMPLETE
    assert search.shortest_reference(problem, max_states=5).status is Status.INCOMPLETE


def test_the_merged_end_row_reaches_every_row_a_long_shift_can_reach() -> None:
    """On a 10.5 m grid brake shifts the left lane by 2 cells: from the merged end row (every l beyond it) the
    over-approximation must reach the end row itself and both rows after it, or "no plan at all" is unsound."""
    from spec.actions import Action
    from spec.grid import Grid

    problem = problem_for(make_scenario("left", [], [], 0, grid=Grid(10.5)), ModelKind.FINAL)
    space = bitplan.BitSpace(problem, -6, 6, merged_ends=True)
    brake = next(f for f in space.moves[0] if f.move.action is Action.BRAKE)
    assert brake.move.shift == 2 and space.pad == 2
    row = space.row_bits
    reached = space.image(brake, 1 << (space.pad * space.width))  # the low end row, o = 0
    rows = [r for r in range(space.rows) if (reached >> (r * space.width)) & row]
    assert rows == [space.pad, space.pad + 1, space.pad + 2]
