"""Spin's proofs for the commitment semantics (``promela.commit``), composed by ``spec.commitment``: the
interpreter's committed parts, escapes and predictions; a malformed probe or first-action mask is refused in one
line."""

from __future__ import annotations

import os
import subprocess
from dataclasses import replace
from pathlib import Path

import pytest

from oracle import commit
from oracle.planner import plan, solve
from promela import runner
from promela import sound as sound_model
from promela.commit import Spin
from promela.render import Probe, Query, shape_of
from spec.actions import Action
from spec.answers import Answer, Limits, Status, Strategy
from spec.assumptions import profile
from spec.commitment import guarded
from spec.escapes import COMMIT, Commitment, EscapeKind
from spec.library import builtin
from spec.models import ModelKind
from spec.scenario import make_scenario, problem_for, sensed
from spec.sound import Sound
from tests.conftest import COMMITTED_BUILT_INS, committed_answers, paper_start_collision

pytestmark = pytest.mark.requires_spin

@pytest.mark.parametrize("name", COMMITTED_BUILT_INS)
@pytest.mark.parametrize("bounds", ["paper", "default"])
def test_spins_proofs_composed_give_the_interpreters_commitment(name: str, bounds: str) -> None:
    """Sensible: the same committed part, escape, prediction and display states; shortest: a prediction as long."""
    for strategy in (Strategy.SENSIBLE, Strategy.SHORTEST):
        ours, theirs = committed_answers(name, bounds, strategy, "spin")
        assert isinstance(ours, Answer) and isinstance(theirs, Answer)
        if strategy is Strategy.SENSIBLE:
            assert (theirs.commit, theirs.states) == (ours.commit, ours.states)
        elif ours.commit is not None and theirs.commit is not None:
            assert len(theirs.commit.committed) + len(theirs.commit.predicted) == \
                len(ours.commit.committed) + len(ours.commit.predicted)


@pytest.mark.parametrize("commitment", [Commitment(1), Commitment(2, (EscapeKind.MINIMAL_RISK, EscapeKind.ABORT)),
                                        Commitment(None, (EscapeKind.MINIMAL_RISK, EscapeKind.COMPLETE))])
def test_a_commitments_bounds_and_escapes_reach_spin(commitment: Commitment) -> None:
    """At most N actions, and only the escapes named: Spin's answer is the interpreter's, checked by ``plan``."""
    found = builtin("paper_example")
    assert found is not None
    scenario = replace(found.load(), sound=Sound(profile("paper"), commitment=commitment))
    theirs = plan(scenario, Strategy.SENSIBLE, engine="spin")
    assert theirs.commit == solve(scenario, Strategy.SENSIBLE).commit
    assert theirs.commit is not None and theirs.commit.escape is not None
    assert commitment.most_actions is None or len(theirs.commit.committed) <= commitment.most_actions
    assert theirs.commit.escape.kind in commitment.escapes


@pytest.mark.parametrize(("bounds", "cell", "sequence"), [
    ("paper", 23, (Action.ACCELERATE, Action.DRIVE)),
    ("paper", 23, (Action.ACCELERATE, Action.RIGHT_LANE_CHANGE, Action.LEFT_LANE_CHANGE)),
    ("paper", 25, (Action.ACCELERATE, Action.ACCELERATE, Action.DRIVE)),
    ("default", 24, (Action.ACCELERATE, Action.BRAKE)),
])
def test_a_fast_step_is_proved_only_with_its_window_cut_at_the_ramp_into_the_next(bounds: str, cell: int,
                                                                                  sequence: tuple[Action, ...]) -> None:
    """A vehicle ahead at 10.5 m cells: accelerating then slowing is safe because the AV slows from where the ramp
    starts, half a ramp before the boundary; checked to its end at its own speed (uncut) the fast step is refused.
    Spin proves each as the interpreter does."""
    from oracle.commit import proofs
    from promela.commit import Spin
    from spec.answers import Limits
    from spec.grid import grid_for

    grid = grid_for(10.5)
    scenario = replace(make_scenario("left", [cell], [], 1, grid=grid), sound=Sound(profile(bounds), commitment=COMMIT))
    problem = problem_for(scenario, ModelKind.FINAL)
    ours = proofs(problem)
    state, uncut = ours.first, []
    for action in sequence:
        uncut.append(ours.rules.step_violation(state, action))
        state = ours.rules.after(state, action)
    assert any(found is not None for found in uncut)  # each step to its end at its own speed: one refused
    assert ours.holds(sequence, False)
    assert Spin(problem, Limits()).holds(sequence, False)


def test_a_step_is_cut_where_the_ramp_into_the_next_starts() -> None:
    """A fast step then braking: uncut, the fast step's window runs on at its speed past where the AV already
    slows; cut, it ends where the ramp into the brake starts. Spin's probe holds exactly what the interpreter's
    does, sequence by sequence, over every pair and triple of actions from both lanes."""
    from oracle.commit import proofs
    from promela.commit import Spin
    from spec.answers import Limits

    differ = 0
    for lane, left, right in (("left", [21], [38]), ("right", [24], [45]), ("left", [27, 30], [])):
        scenario = replace(make_scenario(lane, left, right, 1), sound=Sound(profile("paper"), commitment=COMMIT))
        problem = problem_for(scenario, ModelKind.FINAL)
        ours, theirs = proofs(problem), Spin(problem, Limits())
        for first in Action:
            for second in Action:
                for seq in ((first, second), (first, second, Action.LEFT_LANE_CHANGE)):
                    if not guarded(scenario.lane, seq):
                        continue  # the lane guards are the composition's (spec.commitment.Proofs)
                    for goal in (False, True):
                        assert theirs.holds(seq, goal) == ours.holds(seq, goal), (scenario, seq, goal)
                        differ += ours.holds(seq, goal)
    assert differ > 0


@pytest.mark.parametrize(("query", "why"), [
    (lambda v: v[: -len(" 0")] + " 7", "the probe"),
    (lambda v: v[: -len(" 0")] + " 1 999", "the sequence"),
    (lambda v: v[: -len(" 0")] + " 1 2 0 9", "a sequence's action"),
    (lambda v: v[: -len(" 0")] + " 1 3 0", "the sequence"),
])
def test_a_malformed_probe_is_refused_in_one_line(tmp_path: Path, query, why: str) -> None:  # type: ignore[no-untyped-def]
    """Injected by hand: the verifier exits 2 naming what is malformed, never a plan."""
    scenario = replace(make_scenario("left", [13], [], 1), sound=Sound(profile("default"), commitment=COMMIT))
    problem = problem_for(scenario, ModelKind.FINAL)
    built = runner.verifier(sound_model.shape_of(problem), Strategy.SENSIBLE)
    values = runner.scenario_values(problem)
    assert values.endswith(" 0")
    env = {**os.environ, "OVERTAKE_SCENARIO": f"{query(values)} | {runner.table_file(problem)}"}
    done = subprocess.run([str(built.path), "-E"], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=60)
    assert done.returncode == 2, done.stdout[-300:]
    assert done.stderr.strip() == f"overtake: malformed OVERTAKE_SCENARIO ({why})"


@pytest.mark.parametrize("words", [["64", "1"], ["3", "2"], ["3"]])
def test_a_malformed_first_action_mask_is_refused_in_one_line(tmp_path: Path, words: list[str]) -> None:
    problem = problem_for(make_scenario("left", [13], [], 1), ModelKind.FINAL)
    built = runner.verifier(shape_of(problem), Strategy.SENSIBLE)
    values = runner.scenario_values(problem, Query(firsts=(Action.ACCELERATE,)))
    env = {**os.environ, "OVERTAKE_SCENARIO": " ".join([*values.split(" ")[:-2], *words])}
    done = subprocess.run([str(built.path), "-E"], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=60)
    assert done.returncode == 2, done.stdout[-300:]
    assert "malformed OVERTAKE_SCENARIO" in done.stderr


def test_a_walk_prints_the_display_states_and_a_start_probe_its_safety() -> None:
    scenario = replace(make_scenario("left", [21], [38], 1), sound=Sound(profile("paper"), commitment=COMMIT))
    problem = problem_for(scenario, ModelKind.FINAL)
    walked = runner.search(problem, Strategy.SENSIBLE, query=Query(probe=Probe.WALK, sequence=(
        Action.ACCELERATE, Action.RIGHT_LANE_CHANGE)))
    assert walked.status is Status.PLAN and len(walked.states) == 3 and walked.states[-1].lane.value == "right"
    assert runner.search(problem, Strategy.SENSIBLE, query=Query(probe=Probe.START)).status is Status.PLAN


def test_the_prediction_starts_where_the_paper_rules_see_a_collision() -> None:
    """Spin's paper verifier does not check the prediction's start (the sound model did): the move back, whole."""
    scenario = paper_start_collision()
    for strategy in (Strategy.SENSIBLE, Strategy.SHORTEST):
        ours, theirs = solve(scenario, strategy), solve(scenario, strategy, engine="spin")
        assert (theirs.model, theirs.commit) == (ours.model, ours.commit)
        assert ours.commit is not None and ours.commit.committed == (Action.LEFT_LANE_CHANGE,)


@pytest.mark.parametrize("start_mps,unsafe", [(5.0, True), (None, False)])
@pytest.mark.parametrize("measured", [None, ((6.5, 7.0),)])
def test_a_start_too_near_a_follower_that_keeps_its_speed_is_unsafe_in_every_engine(
        start_mps: float | None, unsafe: bool, measured: tuple[tuple[float, float], ...] | None) -> None:
    """Where followers keep their speed (``paper``), a follower 7 m behind the AV (centre to centre: bumpers clear of
    every position of the AV) closes in on an AV measured at 5 m/s, slower than it may be (7 m/s): already nearer
    than the cut-in's gap, the start itself breaks the specification, in every engine (not "no plan", which every
    step refused at its first instant would give), held to its lane's speeds or to its own measured ones. At the
    common speed it does not close in: a plan."""
    scenario = sensed(make_scenario("left", [9], [], 0), left_m=[[-7.0, -7.0]])
    scenario = replace(scenario, left_mps=measured,
                       sound=Sound(profile("paper"), start_mps=start_mps, commitment=COMMIT))
    for engine in ("interpreter", "spin", "z3"):
        answer = plan(scenario, Strategy.SHORTEST, engine=engine)
        assert (answer.status is Status.UNSAFE_START) is unsafe, (engine, answer.status, answer.detail)
    if unsafe:
        found = plan(scenario, Strategy.SENSIBLE)
        assert "behind" in (found.detail or "")


@pytest.mark.parametrize(("lane", "left", "right", "moving_s"), [
    ("left", [], [12], 0.5), ("left", [12], [13], 2.0), ("right", [11], [14], 0.5),
])
def test_spin_holds_every_short_sequence_from_a_move_under_way_as_the_interpreter_does(
        lane: str, left: list[int], right: list[int], moving_s: float) -> None:
    """A sideways move under way at the start (``Sound.sideways_s``, a table of its own start lane): Spin's
    proofs, sequence by sequence, are the interpreter's."""
    scenario = replace(make_scenario(lane, left, right, 0),
                       sound=Sound(profile("default"), commitment=COMMIT, sideways_s=moving_s))
    problem = problem_for(scenario, ModelKind.FINAL)
    ours, theirs = commit.proofs(problem), Spin(problem, Limits())
    assert (theirs.start_violation() is None) == (ours.start_violation() is None)
    asked = [(seq, goal) for seq in [(), *((a,) for a in Action), *((a, b) for a in Action for b in Action)]
             if guarded(scenario.lane, seq) for goal in (False, True)]
    theirs.prefetch(asked)
    assert [theirs.holds(*q) for q in asked] == [ours.holds(*q) for q in asked]
