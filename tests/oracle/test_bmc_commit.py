"""Z3's proofs for the commitment semantics (``oracle.bmc_commit``), composed by ``spec.commitment``: sequence by
sequence the interpreter's, and its answers the interpreter's (the prediction as long; as cheap under optimal)."""

from __future__ import annotations

from dataclasses import replace

import pytest

from oracle import commit
from oracle.bmc_commit import Z3, display_states
from oracle.interpreter import replay
from oracle.planner import solve
from spec.actions import Action
from spec.answers import Answer, Strategy
from spec.assumptions import profile
from spec.commitment import guarded, paper_problem
from spec.cost import total_cost
from spec.escapes import COMMIT
from spec.grid import grid_for
from spec.library import builtin
from spec.models import ModelKind
from spec.scenario import Scenario, make_scenario, problem_for
from spec.sound import Sound
from tests.conftest import COMMITTED_BUILT_INS, committed_answers, paper_start_collision


@pytest.mark.parametrize(("lane", "left", "right", "bounds"), [
    ("left", [21], [38], "paper"), ("right", [24], [45], "paper"), ("left", [27, 30], [], "default"),
    ("right", [22, 26], [40], "default"),
])
def test_z3_holds_every_short_sequence_as_the_interpreter_does(lane: str, left: list[int], right: list[int],
                                                               bounds: str) -> None:
    scenario = replace(make_scenario(lane, left, right, 1), sound=Sound(profile(bounds), commitment=COMMIT))
    problem = problem_for(scenario, ModelKind.FINAL)
    ours, theirs = commit.proofs(problem), Z3(problem)
    assert (theirs.start_violation() is None) == (ours.start_violation() is None)
    proved = 0
    for first in Action:
        for second in Action:
            for seq in ((first,), (first, second), (first, second, Action.LEFT_LANE_CHANGE)):
                if not guarded(scenario.lane, seq):
                    continue
                for goal in (False, True):
                    assert theirs.holds(seq, goal) == ours.holds(seq, goal), (seq, goal)
                    proved += ours.holds(seq, goal)
    assert proved > 0


@pytest.mark.parametrize(("bounds", "cell", "sequence"), [
    ("paper", 23, (Action.ACCELERATE, Action.DRIVE)),
    ("default", 24, (Action.ACCELERATE, Action.BRAKE)),
])
def test_z3_proves_a_fast_step_only_with_its_window_cut(bounds: str, cell: int, sequence: tuple[Action, ...]) -> None:
    """The cut windows of ``spec.windows`` reach Z3's check (``tests/promela/test_commit.py`` says why they matter)."""
    scenario = replace(make_scenario("left", [cell], [], 1, grid=grid_for(10.5)),
                       sound=Sound(profile(bounds), commitment=COMMIT))
    problem = problem_for(scenario, ModelKind.FINAL)
    assert commit.proofs(problem).rules.step_violation(commit.proofs(problem).first, sequence[0]) is not None
    assert Z3(problem).holds(sequence, False)


@pytest.mark.parametrize("name", COMMITTED_BUILT_INS)
@pytest.mark.parametrize("bounds", ["paper", "default"])
def test_z3s_commitments_are_the_interpreters(name: str, bounds: str) -> None:
    """Shortest: a prediction as long; optimal: as cheap under the paper's rules; each split as the interpreter
    splits it (``plan`` validates), its display states the interpreter's."""
    for strategy in (Strategy.SHORTEST, Strategy.OPTIMAL):
        ours, theirs = committed_answers(name, bounds, strategy, "z3")
        assert isinstance(ours, Answer) and isinstance(theirs, Answer)
        if ours.commit is None or theirs.commit is None or theirs.model is None:
            assert (ours.commit is None) == (theirs.commit is None)
            continue
        checked = commit.validate(problem_for(ours_scenario(name, bounds), theirs.model),
                                  (*theirs.commit.committed, *theirs.commit.predicted))
        assert checked.valid and checked.commit == theirs.commit and checked.states == theirs.states
        whole = [(*a.commit.committed, *a.commit.predicted) for a in (ours, theirs) if a.commit is not None]
        assert len(whole[0]) == len(whole[1])
        if strategy is Strategy.OPTIMAL:
            paper = paper_problem(problem_for(ours_scenario(name, bounds), theirs.model))
            costs = [total_cost(zip(w, replay(paper, w, "check")[1:])) for w in whole]
            assert costs[0] == costs[1]


def ours_scenario(name: str, bounds: str) -> Scenario:
    found = builtin(name)
    assert found is not None
    return replace(found.load(), sound=Sound(profile(bounds), commitment=COMMIT))


def test_z3s_display_states_are_the_interpreters() -> None:
    scenario = replace(make_scenario("left", [21], [38], 1), sound=Sound(profile("paper"), commitment=COMMIT))
    problem = problem_for(scenario, ModelKind.FINAL)
    actions = (Action.ACCELERATE, Action.RIGHT_LANE_CHANGE, Action.ACCELERATE, Action.LEFT_LANE_CHANGE)
    assert display_states(problem, actions) == commit.states_along(problem, actions)


def test_the_prediction_starts_where_the_paper_rules_see_a_collision() -> None:
    """Z3's paper encoding leaves the prediction's start unchecked (the sound model checked it): the move back."""
    scenario = paper_start_collision()
    for strategy in (Strategy.SHORTEST, Strategy.OPTIMAL):
        ours, theirs = solve(scenario, strategy), solve(scenario, strategy, engine="z3")
        assert (theirs.model, theirs.commit) == (ours.model, ours.commit)
        assert ours.commit is not None and ours.commit.committed == (Action.LEFT_LANE_CHANGE,)
