"""The Z3 engine against the interpreter: plan/no plan, shortest length, optimal cost, time-outs."""

from __future__ import annotations

import threading
from dataclasses import replace

import pytest
from hypothesis import given
from hypothesis import strategies as st

from oracle import bitplan, bmc, offsets, z3_engine
from oracle.interpreter import validate
from oracle.optimum import plan_cost
from spec.answers import Limits, SearchResult, Status, Strategy
from spec.cost import COST_TERMS
from spec.grid import PAPER_GRID
from spec.lanes import Lane
from spec.library import BUILTINS
from spec.models import ModelKind
from spec.scenario import Scenario, make_scenario, problem_for
from tests.conftest import scenarios, scenarios_on_grids

MODELS = st.sampled_from(list(ModelKind))


def check_shortest(scenario: Scenario, model: ModelKind) -> None:
    problem = problem_for(scenario, model)
    z, ours = bmc.shortest(problem), bitplan.shortest(problem)
    assert (z.status is Status.PLAN) == (ours.status is Status.PLAN), (z, ours)
    if z.status is Status.PLAN:
        verdict = validate(problem, z.actions)
        assert verdict.valid and verdict.states == z.states
        assert len(z.actions) == len(ours.actions)
    else:
        assert z.status is Status.NO_PLAN_WITHIN_HORIZON and "proved" in z.detail


def cost_key(problem, actions) -> tuple[int, ...]:
    return plan_cost(problem, actions)


def check_optimal(scenario: Scenario, model: ModelKind) -> None:
    problem = problem_for(scenario, model)
    best = bmc.optimal(problem)
    shortest, sensible = bitplan.shortest(problem), offsets.sensible(problem)
    assert (best.status is Status.PLAN) == (shortest.status is Status.PLAN)
    if best.status is Status.PLAN:
        assert validate(problem, best.actions).valid
        assert cost_key(problem, best.actions) <= cost_key(problem, shortest.actions)
        assert cost_key(problem, best.actions) <= cost_key(problem, sensible.actions)
        assert best.extra["cost"] == dict(zip(COST_TERMS, plan_cost(problem, best.actions), strict=True))


@pytest.mark.parametrize("builtin", BUILTINS, ids=lambda b: b.name)
def test_library_shortest_and_optimal_agree_with_the_interpreter(builtin) -> None:
    for model in ModelKind:
        check_shortest(builtin.load(), model)
        check_optimal(builtin.load(), model)


@given(scenarios_on_grids(span=30), MODELS)
def test_generated_shortest_lengths_equal_the_interpreters(scenario: Scenario, model: ModelKind) -> None:
    check_shortest(scenario, model)


@given(scenarios(horizon=8), MODELS)
def test_optimal_is_never_costlier_than_shortest_or_sensible(scenario: Scenario, model: ModelKind) -> None:
    check_optimal(scenario, model)


def test_optimal_prefers_fewer_steps_in_the_right_lane() -> None:
    problem = problem_for(next(b for b in BUILTINS if b.name == "prep_case_a").load(), ModelKind.PREPARATIONS)
    best = bmc.optimal(problem)
    assert best.extra["cost"] == {"lane_changes": 1, "right_lane_steps": 1, "brakes": 1, "length": 3}
    assert cost_key(problem, best.actions) < cost_key(problem, bitplan.shortest(problem).actions)


def test_solver_time_out_is_incomplete_never_no_plan(monkeypatch: pytest.MonkeyPatch) -> None:
    problem = problem_for(make_scenario("left", [12, 14, 16], [30, 45], 3), ModelKind.FINAL)

    class GivingUp(bmc.z3.Solver):  # a solver that always runs out of time
        def check(self, *assumptions):  # type: ignore[no-untyped-def]
            return bmc.z3.unknown

    monkeypatch.setattr(bmc.z3, "SolverFor", lambda logic: GivingUp())
    with bmc.isolated():  # a solver of its own, made with the patched SolverFor
        result = bmc.shortest(problem, Limits(timeout_s=0.001))
    assert result.status is Status.INCOMPLETE


def test_real_time_out_gives_incomplete_or_an_answer_never_a_wrong_one() -> None:
    problem = problem_for(make_scenario("right", [8, 9, 11, 12], [14, 30], 0, horizon=60), ModelKind.FINAL)
    result = bmc.shortest(problem, Limits(timeout_s=0.001))
    assert result.status in (Status.INCOMPLETE, bitplan.shortest(problem).status)


@pytest.mark.parametrize("limit_s", [None, 60.0])
def test_a_check_interrupted_before_its_limit_is_keyboard_interrupt_never_an_answer(limit_s: float | None) -> None:
    scenario = next(b for b in BUILTINS if b.name == "paper_example").load()
    problem = problem_for(replace(scenario, horizon=120), ModelKind.FINAL)  # about 5 s of solving
    stop = threading.Event()

    def interrupting() -> None:  # what Ctrl-C or a signal handler does; Z3 ignores it while no check runs
        while not stop.wait(0.05):
            bmc.z3.main_ctx().interrupt()

    thread = threading.Thread(target=interrupting, daemon=True)
    thread.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            z3_engine._solve(problem, Strategy.OPTIMAL, Limits(timeout_s=limit_s))
    finally:
        stop.set()
        thread.join()
        bmc.z3.Solver().check()  # an interrupt that came after the last check waits for the next: this one takes it


@st.composite
def same_shape(draw: st.DrawFn) -> list[Scenario]:
    """Scenarios of one shape (lane, vehicles per lane, targets, horizon), differing in their cells only: each
    the one before with one vehicle moved a cell, as an exhaustive sweep walks its space."""
    grid, lane = PAPER_GRID, draw(st.sampled_from(list(Lane)))
    n_left, n_right = draw(st.integers(0, 2)), draw(st.integers(0, 1))
    targets, horizon = draw(st.integers(0, n_left)), draw(st.integers(0, 10))
    ahead = (grid.av_cell + 1, grid.av_cell + 12)  # every left-lane vehicle ahead: the targets stay the same
    oncoming = (0, grid.av_cell + 20)

    def fits(left: list[int], right: list[int]) -> bool:
        return (len(set(left)) == len(left) and all(ahead[0] <= c <= ahead[1] for c in left)
                and all(oncoming[0] <= c <= oncoming[1] and (lane is Lane.LEFT or c != grid.av_cell) for c in right))

    left = draw(st.lists(st.integers(*ahead), min_size=n_left, max_size=n_left, unique=True))
    right = draw(st.lists(st.integers(*oncoming).filter(lambda c: fits([], [c])), min_size=n_right, max_size=n_right))
    cells = [(left, right)]
    for vehicle, delta in draw(st.lists(st.tuples(st.integers(0, n_left + n_right - 1), st.sampled_from([-1, 1])),
                                        min_size=1, max_size=6)) if n_left + n_right else []:
        left, right = list(cells[-1][0]), list(cells[-1][1])
        lane_cells, index = (left, vehicle) if vehicle < n_left else (right, vehicle - n_left)
        lane_cells[index] += delta
        if fits(left, right):
            cells.append((left, right))
    return [make_scenario(lane, left, right, targets, horizon=horizon, grid=grid) for left, right in cells]


def answer(result: SearchResult) -> tuple[object, ...]:
    """What must not depend on the solver's history: the status, the length and the least cost."""
    return result.status, len(result.actions), (result.extra or {}).get("cost")


@given(same_shape(), MODELS)
def test_answers_on_kept_solvers_equal_answers_on_fresh_ones(scenarios: list[Scenario], model: ModelKind) -> None:
    problems = [problem_for(s, model) for s in scenarios]
    for solve in (bmc.shortest, bmc.optimal):
        kept = [solve(p) for p in problems]  # one solver for the shape, problem after problem
        with bmc.isolated():
            fresh = [solve(p) for p in problems]
        assert [answer(r) for r in kept] == [answer(r) for r in fresh]
        for p, r in zip(problems, kept, strict=True):  # and each kept answer's plan is the problem's own
            if r.status is Status.PLAN:
                assert validate(p, r.actions).states == r.states


@given(scenarios(), MODELS, st.integers(0, 12), st.lists(st.integers(0, 6), min_size=len(COST_TERMS),
                                                          max_size=len(COST_TERMS)))
def test_an_expected_answer_orders_the_checks_never_decides_them(scenario: Scenario, model: ModelKind, length: int,
                                                                  cost: list[int]) -> None:
    """Whatever length and cost another engine is expected to have found (``bmc.expecting``), right or wrong, Z3
    answers what it answers without them."""
    problem = problem_for(scenario, model)
    with bmc.isolated():
        plain = [answer(solve(problem)) for solve in (bmc.shortest, bmc.optimal)]
        with bmc.expecting({problem: bmc.Expected(length, tuple(cost))}):
            guessed = [answer(solve(problem)) for solve in (bmc.shortest, bmc.optimal)]
    assert guessed == plain


def test_a_solver_that_gave_up_is_not_kept() -> None:
    problem = problem_for(next(b for b in BUILTINS if b.name == "paper_example").load(), ModelKind.FINAL)
    expected = answer(bmc.optimal(problem))
    key = (bmc.Optimal, bmc.shape(problem))
    assert key in bmc._kept
    assert bmc.optimal(problem, Limits(timeout_s=1e-9)).status is Status.INCOMPLETE
    assert key not in bmc._kept
    assert answer(bmc.optimal(problem)) == expected and key in bmc._kept


@pytest.mark.parametrize("solve", [bmc.shortest, bmc.optimal], ids=["shortest", "optimal"])
def test_an_interrupt_between_checks_is_keyboard_interrupt_or_the_right_answer_never_a_wrong_one(solve) -> None:
    problem = problem_for(next(b for b in BUILTINS if b.name == "paper_example").load(), ModelKind.FINAL)
    with bmc.isolated():
        expected = answer(solve(problem))
        bmc.z3.main_ctx().interrupt()  # Ctrl-C while no check runs: Z3 cuts short taking in the next constraints
        try:
            got = answer(solve(problem))
        except KeyboardInterrupt:
            got = expected
        finally:
            bmc.z3.Solver().check()  # take the interrupt, if the solve left it
    assert got == expected


@pytest.mark.parametrize("solve", [bmc.shortest, bmc.optimal], ids=["shortest", "optimal"])
def test_an_interrupt_just_after_a_satisfiable_check_is_keyboard_interrupt(solve, monkeypatch: pytest.MonkeyPatch
                                                                           ) -> None:
    problem = problem_for(next(b for b in BUILTINS if b.name == "paper_example").load(), ModelKind.FINAL)
    checked = bmc._check

    def then_interrupted(solver, limits, started, *assumptions):  # Ctrl-C lands as the check returns "sat"
        verdict = checked(solver, limits, started, *assumptions)
        if verdict == bmc.z3.sat:
            bmc.z3.main_ctx().interrupt()
        return verdict

    monkeypatch.setattr(bmc, "_check", then_interrupted)
    with bmc.isolated():
        try:
            with pytest.raises(KeyboardInterrupt):  # Z3 has no model to give: never a Z3Exception, never an answer
                solve(problem)
        finally:
            bmc.z3.Solver().check()  # take the interrupt, if it is still pending
