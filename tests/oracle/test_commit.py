"""The commitment semantics (``oracle.commit``, ``spec.escapes``): every committed part and its escape survive every
motion within the bounds; the receding-horizon chain never breaks the specification, and breaks it without its
escapes; ``validate`` says which part fails; an unsafe start is an answer of its own."""

from __future__ import annotations

import random
from dataclasses import replace

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from oracle import bitplan, chain, commit, reach, sound
from oracle.offsets import OffsetSearch
from oracle.planner import plan, validate_pipeline
from spec.actions import Action
from spec.answers import Limits, Status, Strategy
from spec.assumptions import profile
from spec.escapes import COMMIT, Commitment, EscapeKind
from spec.files import scenario_from_dict
from spec.grid import PAPER_GRID, STANDARD_CELLS_M, Grid, grid_for
from spec.library import BUILTINS, builtin
from spec.models import PIPELINE, ModelKind
from spec.scenario import Scenario, make_scenario, problem_for
from spec.sound import Sound, sound_from
from tests.conftest import CI_PROFILE
from tests.oracle.test_sound import sound_scenarios


def committed(scenario: Scenario) -> Scenario:
    assert scenario.sound is not None
    return replace(scenario, sound=replace(scenario.sound, commitment=COMMIT))


def _check(scenario: Scenario, strategy: Strategy, motions: int, rng: random.Random) -> int:
    """An answer's committed part then its escape (or, for a whole plan, the plan and its goal) must survive the exact
    check and ``motions`` sampled motions, phantoms and corners included. The pairs driven."""
    answer = plan(scenario, strategy, limits=Limits(max_states=200_000))
    if answer.status is not Status.PLAN or answer.commit is None or answer.model is None:
        return 0
    parts = answer.commit
    path = (*parts.committed, *(parts.escape.actions if parts.escape else ()))
    goal = problem_for(scenario, answer.model).goal if parts.escape is None else None
    breach = reach.exact_check(scenario, path)
    assert breach is None, f"{scenario} {path}: {breach.describe()}"
    driven = reach.motions(scenario, path, rng, motions)
    for motion in driven:
        found = reach.run_motion(scenario, path, motion, goal)
        assert found is None, f"{scenario} {path}: {found.describe()}"
    return len(driven)


@settings(max_examples=100 if CI_PROFILE else 25)
@given(st.sampled_from(STANDARD_CELLS_M).flatmap(lambda c: sound_scenarios(Grid(c))),
       st.sampled_from(list(Strategy)), st.integers(0, 2**32 - 1))
def test_every_committed_part_and_its_escape_survive_every_motion_within_the_bounds(scenario: Scenario,
                                                                                     strategy: Strategy,
                                                                                     seed: int) -> None:
    _check(committed(scenario), strategy, 4, random.Random(seed))


@settings(max_examples=200 if CI_PROFILE else 40)
@given(st.sampled_from(STANDARD_CELLS_M).flatmap(lambda c: sound_scenarios(Grid(c))),
       st.sampled_from(list(PIPELINE)), st.sets(st.sampled_from(list(Action)), min_size=1))
def test_the_live_positions_are_exactly_those_that_still_reach_the_goal_in_time(scenario: Scenario, kind: ModelKind,
                                                                                firsts: set[Action]) -> None:
    """``bitplan.live_positions`` against every offset the prediction's search can reach, judged by recursion over
    its successors: the pruned search skips exactly the dead ends."""
    problem = problem_for(scenario, kind)
    live = bitplan.live_positions(problem)
    search = OffsetSearch(problem)
    judged: dict[tuple[int, int, int, int], bool] = {}

    def reaches(key: tuple[int, int, int, int]) -> bool:
        if key not in judged:
            nexts = [k for a, k in search.successors(key) if key[3] > 0 or a in firsts]
            judged[key] = (key[3] > 0 and search.goal(key)) or any([reaches(k) for k in nexts])
        return judged[key]

    reaches((0, 0, 0, 0))
    for key, alive in judged.items():
        if key[3] > 0:
            assert live(*key) is alive, (key, alive)


@pytest.mark.parametrize("name", [b.name for b in BUILTINS])
@pytest.mark.parametrize("bounds", ["paper", "default"])
def test_each_builtins_answer_survives_every_motion(name: str, bounds: str) -> None:
    scenario = replace(builtin(name).load(), sound=sound_from(None, bounds))
    for strategy in Strategy:
        _check(scenario, strategy, 20 if CI_PROFILE else 6, random.Random(name))


def test_the_same_checks_break_a_committed_lane_change_without_its_escape() -> None:
    """What makes the step provable is its escape: the same checks find the oncoming phantom when the AV stays in the
    right lane after it (the minimal-risk manoeuvre in that lane)."""
    scenario = replace(builtin("one_target").load(), sound=sound_from(None, "default"))
    answer = plan(scenario)
    assert answer.commit is not None and answer.commit.escape is not None
    assert answer.commit.committed == (Action.RIGHT_LANE_CHANGE,)
    assert answer.commit.escape.kind is EscapeKind.ABORT
    breach = reach.exact_check(scenario, answer.commit.committed)
    assert breach is not None and "phantom" in breach.vehicle


def test_the_built_ins_the_papers_rules_plan_are_answered_with_a_committed_part() -> None:
    """Of the built-ins with a non-empty plan of the paper's rules, under the default bounds, all but the one whose
    AV stands in the right lane beside a vehicle it cannot return in front of (``prep_case_a``) get a committed
    part with a predicted continuation to the goal."""
    planned = [b.name for b in BUILTINS if plan(b.load()).actions]
    answered = {name: plan(replace(builtin(name).load(), sound=sound_from(None, "default"))) for name in planned}
    got = sorted(name for name, a in answered.items() if a.status is Status.PLAN and a.actions)
    assert got == sorted(set(planned) - {"prep_case_a"}), got
    assert answered["prep_case_a"].status is Status.NO_PLAN
    assert "no committed step is provable" in answered["prep_case_a"].detail


def test_a_whole_proved_plan_needs_no_escape() -> None:
    """The paper's world, the target read 42 m ahead: the predicted plan is proved to its goal, whole."""
    from spec.scenario import sensed

    scenario = replace(sensed(builtin("one_target").load(), ((42.0, 42.0),)), sound=sound_from(None, "paper"))
    for strategy in Strategy:
        whole = plan(replace(scenario, sound=replace(scenario.sound, commitment=None)), strategy)  # type: ignore
        answer = plan(scenario, strategy)
        assert whole.status is Status.PLAN and answer.commit is not None
        assert answer.commit.escape is None and answer.actions == whole.actions and not answer.commit.predicted


def test_a_commitment_of_one_action_commits_one() -> None:
    scenario = replace(builtin("one_target").load(), sound=sound_from(None, "paper", phantoms=False, commit_max=1))
    answer = plan(scenario)
    assert answer.commit is not None and len(answer.actions) == 1 and answer.commit.escape is not None
    assert answer.commit.predicted


def test_without_the_escapes_of_the_right_lane_no_lane_change_is_committed() -> None:
    only = replace(builtin("one_target").load(), sound=sound_from(None, "default", escapes="minimal_risk"))
    answer = plan(only)
    assert answer.status is not Status.PLAN or Action.RIGHT_LANE_CHANGE not in answer.actions


# -- validate: which part fails -----------------------------------------------------------------------------------
def _verdict(scenario: Scenario, actions: tuple[Action, ...]) -> str:
    checked = validate_pipeline(scenario, actions, horizon=None)
    return ("valid: " if checked.verdict.valid else "invalid: ") + checked.reason


def test_validate_says_which_part_fails_and_why() -> None:
    one = replace(builtin("one_target").load(), sound=sound_from(None, "default"))
    rlc, acc, llc = Action.RIGHT_LANE_CHANGE, Action.ACCELERATE, Action.LEFT_LANE_CHANGE
    assert _verdict(one, (rlc, acc, acc, acc, llc)).startswith("valid: 1 committed action(s), escape abort")
    assert "committed part: step 1 (accelerate)" in _verdict(one, (acc, rlc, acc, acc, llc))
    assert "predicted continuation" in _verdict(one, (rlc, acc, llc))
    near = replace(make_scenario("right", [], [15], 0), sound=sound_from(None, "default"))
    assert "committed part: no escape after step 1 (accelerate)" in _verdict(near, (Action.ACCELERATE, llc))


# -- an unsafe start ----------------------------------------------------------------------------------------------
def test_a_start_that_already_breaks_the_specification_is_an_answer_of_its_own() -> None:
    """The vehicle read in cell 11, the AV's next, may be clear ahead of it and far too near with the sensing error:
    never the empty plan; under the commitment semantics ``unsafe_start`` and the in-lane minimal-risk manoeuvre,
    under whole plans "no plan"."""
    start = make_scenario("left", [11, 17], [20], 0)
    answer = plan(replace(start, sound=sound_from(None, "default")))
    assert answer.status is Status.UNSAFE_START and answer.commit is not None and answer.commit.escape is not None
    assert answer.commit.escape.kind is EscapeKind.MINIMAL_RISK and not answer.commit.escape_proved
    assert "left_lane[0]" in answer.detail
    whole = plan(replace(start, sound=sound_from(None, "default", semantics="whole")))
    assert whole.status is Status.NO_PLAN and "initial state" in whole.detail
    right = plan(replace(make_scenario("right", [], [11], 0), sound=sound_from(None, "default")))
    assert right.status is Status.UNSAFE_START and right.commit is not None and right.commit.escape is not None
    assert right.commit.escape.actions == (Action.LEFT_LANE_CHANGE,)


@pytest.mark.parametrize("behind_m", [(-21.0, -21.0), (-6.5, -6.5), None])
def test_a_vehicle_behind_the_av_follows_it_however_near(behind_m: tuple[float, float] | None) -> None:
    """What the snapshot measured: the overtaken vehicle 21 m behind, or at the least gap behind (2 m, bumpers not
    clear of the AV's envelope with the sensing error), or anywhere in the cell behind the AV's (cells alone): it
    cannot be clear ahead, so it follows the AV (nothing touches the AV at a snapshot), and the start is no unsafe
    one."""
    from spec.scenario import sensed

    start = make_scenario("left", [9, 17], [20], 0)
    if behind_m is not None:
        start = sensed(start, (behind_m, (147.0, 147.0)), ((215.0, 215.0),))
    answer = plan(replace(start, sound=sound_from(None, "default")))
    assert answer.status is Status.PLAN


def test_a_step_checked_whole_refused_is_committed_with_an_escape_after_it() -> None:
    """The over-conservative refusal an independent check found: at 5.25 m, the AV in the left lane, targets at
    cells 48 and 76, ``accelerate`` was refused as if its speed were held to the step's end (13.65 m against 15.90 m
    required at 3 s); the ramp into a slower action after it starts before that end (``step_violation``'s
    ``following``), and with ``drive`` or ``brake`` in lane as its escape the step commits; the whole sequence
    survives every motion."""
    scenario = replace(make_scenario("left", [48, 76], [], 2, grid=grid_for(5.25)), sound=Sound(profile("default")))
    problem = problem_for(scenario, ModelKind.FINAL)
    rules, first = sound.rules_for(problem), sound.start(problem)
    refused = rules.step_violation(first, Action.ACCELERATE)
    assert refused is not None and refused.time_s == pytest.approx(3.0)  # held to its end: refused
    assert rules.step_violation(first, Action.ACCELERATE, Action.BRAKE) is None
    ok, _ = commit.committable(replace(problem, scenario=committed(scenario)), first)
    escape = ok[Action.ACCELERATE].escape
    assert escape.kind is EscapeKind.MINIMAL_RISK and escape.actions in ((Action.DRIVE,), (Action.BRAKE,))
    path = (Action.ACCELERATE, *escape.actions)
    assert reach.exact_check(scenario, path) is None
    assert all(reach.run_motion(scenario, path, m) is None for m in reach.motions(scenario, path, random.Random(6), 40))


# -- the receding-horizon chain -----------------------------------------------------------------------------------
#: Worlds of 60 s per policy: CI's profile drives every grid and both profiles.
WORLDS = 60 if CI_PROFILE else 15
CHAIN_CASES = [("default", 21.0)] + ([("paper", 21.0), ("default", 10.5), ("default", 5.25)] if CI_PROFILE else [])


@pytest.mark.parametrize(("name", "cell_m"), CHAIN_CASES)
def test_the_receding_horizon_chain_never_breaks_the_specification(name: str, cell_m: float) -> None:
    """Decide, commit one action, the world moves within the bounds, decide again from a fresh snapshot (the phantoms
    at the new range edges), take the last escape while nothing new is proved: no breach, and the AV does overtake."""
    sound_model = chain.chain_sound(Sound(profile(name)))
    grid, right = grid_for(cell_m), 0
    for seed in range(WORLDS):
        world = chain.random_world(seed, sound_model, grid, 60.0)
        outcome = chain.drive(world, sound_model, grid, chain.committing, 60.0)
        assert outcome.breach is None, f"{world.describe()}: {outcome.breach.describe()}; {outcome.executed[-4:]}"
        right += outcome.lane_changes_right
    assert right >= WORLDS // 2, right


@pytest.mark.parametrize("policy", [chain.Policies.NO_ESCAPE, chain.Policies.KEEP_PREDICTED])
def test_the_chain_breaks_the_specification_without_the_escape_or_keeping_the_predicted_plan(
        policy: chain.Policies) -> None:
    """The same chain, its worlds and checks, finds what the escape rules out: committing without one, or driving on
    along the predicted plan when nothing new is proved."""
    sound_model = chain.chain_sound(Sound(profile("default")))
    for seed in range(100):
        world = chain.random_world(seed, sound_model, PAPER_GRID, 60.0)
        if chain.drive(world, sound_model, PAPER_GRID, chain.POLICY[policy], 60.0).breach is not None:
            return
    pytest.fail(f"{policy.value}: no breach in 100 worlds")


def test_a_commitment_that_is_not_kept_to_its_end_is_what_the_claim_needs() -> None:
    """The claim needs a decision at least once per committed part: committing to several actions with one escape
    after the last is what ``most_actions`` bounds (a decision commits to at most that many)."""
    scenario = replace(builtin("one_target").load(), sound=sound_from(None, "paper", phantoms=False))
    for most in (1, 2, 3):
        answer = plan(replace(scenario, sound=replace(scenario.sound, commitment=Commitment(most))))  # type: ignore
        assert answer.commit is not None and len(answer.commit.committed) <= most


@pytest.mark.parametrize(("strategy", "length"), [(Strategy.SHORTEST, 5), (Strategy.OPTIMAL, 5)])
def test_a_prediction_may_come_back_to_the_starts_offsets(strategy: Strategy, length: int) -> None:
    """On 7 m cells with no oncoming vehicle a drive moves no cell: the plan (drive, out, accelerate twice, back)
    passes through the start's offsets after one action. The prediction's start is a node of its own (only the
    committable actions leave it, and it is never the goal), so that plan is found: Z3's bounded search found it
    where a search that took the offsets for a revisit of the start answered a six-action plan."""
    scenario = scenario_from_dict({
        "lane": "left", "left_lane": [17, 33, 56, 70], "right_lane": [], "targets": 1, "horizon": 6, "cell_m": 7.0,
        "bounds": {"same_mps": [6.5, 7.5], "oncoming_mps": [4.9, 9.1], "sensing_error_m": 0.0, "phantoms": True,
                   "followers_react": True, "latency_s": 0.1, "oncoming_view_m": 52.5,
                   "escapes": ["minimal_risk", "abort"]}})
    answer = plan(scenario, strategy)
    assert answer.status is Status.PLAN and answer.commit is not None
    whole = (*answer.commit.committed, *answer.commit.predicted)
    assert len(whole) == length and whole[0] is Action.DRIVE
