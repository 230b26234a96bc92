"""Z3's proofs for the commitment semantics (``oracle.bmc_commit``), composed by ``spec.commitment``: sequence by
sequence the interpreter's, and its answers the interpreter's (the prediction as long; as cheap under optimal)."""

from __future__ import annotations

from dataclasses import replace

import pytest
from hypothesis import given, settings

from oracle import commit
from oracle.bmc_commit import Z3, display_states
from oracle.interpreter import replay
from oracle.planner import solve
from spec.actions import Action
from spec.answers import Answer, Strategy
from spec.assumptions import profile
from spec.commitment import guarded, paper_problem
from spec.cost import total_cost
from spec.dynamics import Overtaken
from spec.engines import check_model, get_engine
from spec.errors import OptionError
from spec.escapes import COMMIT
from spec.grid import grid_for
from spec.lanes import Lane
from spec.library import builtin
from spec.models import ModelKind
from spec.scenario import Scenario, make_scenario, measured_speeds, problem_for, sensed
from spec.sound import Sound, sound_from
from tests.conftest import CI_PROFILE, COMMITTED_BUILT_INS, committed_answers, paper_start_collision
from tests.oracle.test_sound_measured import _overtaking, _standing_ahead, measured_scenarios


@pytest.mark.parametrize(("lane", "left", "right", "bounds"), [
    ("left", [21], [38], "paper"), ("right", [24], [45], "paper"), ("left", [27, 30], [], "default"),
    ("right", [22, 26], [40], "default"),
])
def test_z3_holds_every_short_sequence_as_the_interpreter_does(lane: str, left: list[int], right: list[int],
                                                               bounds: str) -> None:
    scenario = replace(make_scenario(lane, left, right, 0), sound=Sound(profile(bounds), commitment=COMMIT))
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
        _split_as_the_interpreters(ours_scenario(name, bounds), strategy, ours, theirs)


def _split_as_the_interpreters(scenario: Scenario, strategy: Strategy, ours: Answer, theirs: Answer) -> None:
    """Z3's split is the interpreter's split of its own prediction (``commit.validate``), its prediction as long,
    and for optimal as cheap under the paper's rules."""
    if ours.commit is None or theirs.commit is None or theirs.model is None:
        assert (ours.commit is None) == (theirs.commit is None)
        return
    checked = commit.validate(problem_for(scenario, theirs.model), (*theirs.commit.committed, *theirs.commit.predicted))
    assert checked.valid and checked.commit == theirs.commit and checked.states == theirs.states
    whole = [(*a.commit.committed, *a.commit.predicted) for a in (ours, theirs) if a.commit is not None]
    assert len(whole[0]) == len(whole[1])
    if strategy is Strategy.OPTIMAL:
        paper = paper_problem(problem_for(scenario, theirs.model))
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


# -- vehicles with their own measured speeds (spec.dynamics), under the commitment semantics ---------------------
def _same_proofs(scenario: Scenario) -> int:
    """Z3's start and every short sequence's proof equal the interpreter's; how many sequences held."""
    problem = problem_for(scenario, ModelKind.FINAL)
    ours, theirs = commit.proofs(problem), Z3(problem)
    assert (theirs.start_violation() is None) == (ours.start_violation() is None)
    if ours.start_violation() is not None:
        return 0
    held = 0
    for first in Action:
        for second in (None, *Action):
            seq = (first,) if second is None else (first, second)
            if not guarded(scenario.lane, seq):
                continue
            for goal in (False, True):
                assert theirs.holds(seq, goal) == ours.holds(seq, goal), (seq, goal)
                held += ours.holds(seq, goal)
    return held


@settings(max_examples=40 if CI_PROFILE else 10, deadline=None)
@given(measured_scenarios())
def test_z3_holds_every_short_sequence_with_measured_speeds_as_the_interpreter_does(scenario: Scenario) -> None:
    """Each measured vehicle moves by its own dynamics in Z3's conditions (``oracle.bmc_own``: some instant of a
    piece breaking one, asked of the solver) as in the interpreter's closed-form worst instants."""
    _same_proofs(replace(scenario, sound=replace(scenario.sound, commitment=COMMIT)))


@pytest.mark.parametrize("overtaken", list(Overtaken))
def test_z3_holds_the_pass_beside_a_measured_target_only_under_the_no_acceleration_profile(
        overtaken: Overtaken) -> None:
    """The AV beside a target measured at 3.5..6.5 m/s: the move back ahead of it is safe for ever only when the
    target has not sped up since the AV moved out (``tests/oracle/test_sound_measured.py``'s witness), in Z3 as in
    the interpreter."""
    scenario = _overtaking(overtaken)
    scenario = replace(scenario, sound=replace(scenario.sound, commitment=COMMIT))
    _same_proofs(scenario)
    problem = problem_for(scenario, ModelKind.FINAL)
    back = (Action.DRIVE, Action.ACCELERATE, Action.LEFT_LANE_CHANGE)
    assert Z3(problem).holds(back, False) == commit.proofs(problem).holds(back, False) == \
        (overtaken is Overtaken.NO_ACCELERATION)


@pytest.mark.parametrize("start_mps", [None, 3.5, 12.0])
@pytest.mark.parametrize("cell", [11, 13, 16])
def test_z3_holds_what_the_interpreter_holds_before_a_vehicle_standing_ahead(cell: int,
                                                                             start_mps: float | None) -> None:
    """A vehicle measured standing in the AV's lane: the minimal-risk manoeuvre must stop behind it, whose window
    the table builds for a standstill (``spec.sound.hold_floor_mps``)."""
    scenario = _standing_ahead(cell, start_mps)
    _same_proofs(replace(scenario, sound=replace(scenario.sound, commitment=COMMIT)))


def test_z3_holds_a_follower_faster_than_its_lanes_top_to_its_own_top() -> None:
    """A follower measured at 10 m/s, 20 m behind, above the paper profile's top: it closes in on the AV at the
    common speed for ever, so no sequence that ends in the left lane at that speed is safe for ever (its own top
    binds, ``spec.sound.rear_binds``; at its lane's top the follower would never close in). 12 m behind, it is
    nearer than the cut-in's gap at its own top already (6 + 1.5 s x 4.5 m/s): the start breaks the specification."""
    sound = sound_from(None, "paper", phantoms=False, semantics="commit")
    near = measured_speeds(sensed(make_scenario("left", [9], [], 0), [(-12.0, -12.0)]), [(10.0, 10.0)])
    near_problem = problem_for(replace(near, sound=sound), ModelKind.FINAL)
    assert Z3(near_problem).start_violation() is not None
    assert commit.proofs(near_problem).start_violation() is not None
    base = measured_speeds(sensed(make_scenario("left", [9], [], 0), [(-20.0, -20.0)]), [(10.0, 10.0)])
    scenario = replace(base, sound=sound)
    problem = problem_for(scenario, ModelKind.FINAL)
    assert Z3(problem).start_violation() is None
    _same_proofs(scenario)
    assert not Z3(problem).holds((Action.DRIVE,), False)
    assert not commit.proofs(problem).holds((Action.DRIVE,), False)


@pytest.mark.parametrize("strategy", [Strategy.SHORTEST, Strategy.OPTIMAL])
def test_z3s_commitments_with_measured_speeds_are_the_interpreters(strategy: Strategy) -> None:
    for scenario in (_overtaking(Overtaken.NO_ACCELERATION), _overtaking(Overtaken.PHYSICS), _standing_ahead(16),
                     _standing_ahead(13, 12.0)):
        scenario = replace(scenario, sound=replace(scenario.sound, commitment=COMMIT))
        ours, theirs = solve(scenario, strategy), solve(scenario, strategy, engine="z3")
        assert theirs.status is ours.status
        _split_as_the_interpreters(scenario, strategy, ours, theirs)


def test_z3_refuses_measured_speeds_in_whole_plans_naming_the_semantics() -> None:
    """Its whole-plan encoding moves every vehicle at its lane's speeds: bad input (exit 2), never a wrong answer."""
    with pytest.raises(OptionError, match=r"under --semantics whole .*answers them under --semantics commit"):
        scenario = _standing_ahead(16)
        check_model(get_engine("z3"), replace(scenario, sound=replace(scenario.sound, commitment=None)))


@pytest.mark.parametrize(("lane", "left", "right", "moving_s", "read"), [
    ("left", [], [12], 0.5, True), ("left", [12], [13], 2.0, True), ("left", [8], [13], 2.0, True),
    ("right", [11], [14], 0.5, False), ("right", [12], [], 2.0, False),
])
def test_z3_holds_every_short_sequence_from_a_move_under_way_as_the_interpreter_does(
        lane: str, left: list[int], right: list[int], moving_s: float, read: bool) -> None:
    """A sideways move under way at the start (``Sound.sideways_s``): the same proofs, sequence by sequence; where
    an oncoming vehicle is near, the move changes some of them (it is read)."""
    scenario = replace(make_scenario(lane, left, right, 0),
                       sound=Sound(profile("default"), commitment=COMMIT, sideways_s=moving_s))
    problem = problem_for(scenario, ModelKind.FINAL)
    ours, theirs = commit.proofs(problem), Z3(problem)
    still = commit.proofs(problem_for(replace(scenario, sound=replace(scenario.sound, sideways_s=0.0)),
                                      ModelKind.FINAL))
    assert (theirs.start_violation() is None) == (ours.start_violation() is None)
    changed = 0
    for seq in _short_sequences(scenario.lane):
        for goal in (False, True):
            assert theirs.holds(seq, goal) == ours.holds(seq, goal), (seq, goal)
            changed += ours.holds(seq, goal) != still.holds(seq, goal)
    assert (changed > 0) == read


def _short_sequences(lane: Lane) -> list[tuple[Action, ...]]:
    """Every sequence of at most two actions the lane guards allow from ``lane``, the empty one first."""
    return [seq for seq in [(), *((a,) for a in Action), *((a, b) for a in Action for b in Action)]
            if guarded(lane, seq)]
