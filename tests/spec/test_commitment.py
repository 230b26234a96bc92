"""The commitment semantics' composition (``spec.commitment``): which escape, how long a committed part, what each
"no plan" means, from scripted proofs (each engine's own proofs are held to the interpreter's in its layer's tests and
by cross-validation)."""

from __future__ import annotations

from collections.abc import Container, Sequence
from dataclasses import replace

from spec.actions import ACTION_RULES, Action
from spec.answers import Limits, SearchResult, Status, Strategy
from spec.assumptions import profile
from spec.commitment import Firsts, ProofIncomplete, answer, enabled_firsts, split
from spec.escapes import COMMIT, Commitment, EscapeKind
from spec.lanes import Lane
from spec.models import ModelKind
from spec.scenario import Problem, make_scenario, problem_for
from spec.sound import Sound
from spec.state import State

A, D, B, R, L = (Action.ACCELERATE, Action.DRIVE, Action.BRAKE, Action.RIGHT_LANE_CHANGE, Action.LEFT_LANE_CHANGE)


class Scripted:
    """Proofs that hold exactly the sequences given (goal or not), predict a fixed plan, and record what is asked."""

    def __init__(self, proved: set[tuple[tuple[Action, ...], bool]], plan: tuple[Action, ...] | None,
                 start: str | None = None, beyond: bool = False) -> None:
        self.proved, self.plan, self.start, self.beyond = proved, plan, start, beyond
        self.asked: list[tuple[tuple[Action, ...], bool]] = []

    def start_violation(self) -> str | None:
        return self.start

    def prefetch(self, asked: Sequence[tuple[tuple[Action, ...], bool]]) -> None:
        self.hinted = list(asked)

    def holds(self, actions: Sequence[Action], goal: bool) -> bool:
        self.asked.append((tuple(actions), goal))
        return (tuple(actions), goal) in self.proved

    def predict(self, strategy: Strategy, firsts: Container[Action], limits: Limits) -> SearchResult:
        if self.plan is None or self.plan[0] not in firsts:
            return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), 3)
        return SearchResult(Status.PLAN, self.plan, 3)

    def no_plan_beyond(self) -> bool:
        return self.beyond

    def why_not(self, action: Action) -> str:
        return "scripted"

    def states(self, actions: Sequence[Action]) -> tuple[State, ...]:
        return tuple(State(Lane.LEFT, (), (), 0, n) for n in range(len(actions) + 1))


def _problem(commitment: Commitment = COMMIT) -> Problem:
    scenario = make_scenario("left", [26], [40], targets=1)
    return problem_for(replace(scenario, sound=Sound(profile("paper"), commitment=commitment)), ModelKind.FINAL)


def test_the_committed_part_is_the_longest_prefix_an_escape_is_proved_after() -> None:
    plan = (A, R, A, A, L)
    proofs = Scripted({((A, R, L), False), ((A,), False)}, plan)  # abort after the move out, nothing later
    found = answer(_problem(), Strategy.SENSIBLE, Limits(), proofs)
    assert found.status is Status.PLAN and found.commit is not None
    assert found.commit.committed == (A, R) and found.commit.predicted == (A, A, L)
    assert found.commit.escape is not None and found.commit.escape.kind is EscapeKind.ABORT
    assert len(found.states) == 3


def test_an_escape_is_proved_with_every_one_of_its_actions() -> None:
    """The completion (accelerate, then back) is proved as the committed part followed by both of its actions."""
    plan = (R, D, D, L)
    proofs = Scripted({((R, A, L), False)}, plan)
    committed, escape = split(_problem(), plan, proofs)
    assert committed == (R,) and escape is not None and escape.actions == (A, L)
    assert ((R, L), False) in proofs.asked  # the abort first, in ESCAPES' order


def test_a_whole_plan_needs_its_goal_and_fits_within_the_most_actions() -> None:
    plan = (A, R, L)
    safe_without_goal = Scripted({(plan, False), ((A,), False)}, plan)  # safe for ever, the goal not for all
    assert split(_problem(), plan, safe_without_goal) == (plan, next(
        e for e in COMMIT.allowed(Lane.LEFT) if not e.actions))  # committed whole, the escape kept
    whole = Scripted({(plan, True), ((A,), False)}, plan)
    assert split(_problem(), plan, whole) == (plan, None)
    assert split(_problem(Commitment(2)), plan, whole)[0] == (A,)  # too long to commit to whole


def test_no_committable_first_action_is_no_plan_and_a_committable_one_without_a_prediction_is_not() -> None:
    none = answer(_problem(), Strategy.SENSIBLE, Limits(), Scripted(set(), (A, R, L)))
    assert none.status is Status.NO_PLAN and "no committed step is provable" in none.detail
    firsts = Scripted({((D,), False)}, (A, R, L))
    within = answer(_problem(), Strategy.SENSIBLE, Limits(), firsts)
    assert within.status is Status.NO_PLAN_WITHIN_HORIZON and "(drive)" in within.detail
    beyond = answer(_problem(), Strategy.SENSIBLE, Limits(), Scripted({((D,), False)}, None, beyond=True))
    assert beyond.status is Status.NO_PLAN


def test_an_unsafe_start_names_the_lanes_first_escape_unproved() -> None:
    found = answer(_problem(), Strategy.SENSIBLE, Limits(), Scripted(set(), None, start="too close"))
    assert found.status is Status.UNSAFE_START and found.commit is not None and not found.commit.escape_proved
    assert "too close" in found.detail


def test_firsts_proves_each_first_action_once_when_asked() -> None:
    proofs = Scripted({((D,), False)}, None)
    firsts = Firsts(proofs, _problem())
    assert D in firsts and D in firsts and A not in firsts and "drive" not in firsts
    assert [a for a, _ in proofs.asked].count((D,)) == 1


def test_a_proof_that_hits_its_limit_makes_the_answer_incomplete_never_a_refusal() -> None:
    class Limited(Scripted):
        def holds(self, actions: Sequence[Action], goal: bool) -> bool:
            raise ProofIncomplete("time limit 0.1 s reached")

    found = answer(_problem(), Strategy.SENSIBLE, Limits(), Limited(set(), (A, R, L)))
    assert found.status is Status.INCOMPLETE and "time limit" in found.detail


def test_while_a_sideways_move_is_under_way_no_lane_change_is_a_first_action() -> None:
    """The move under way is the AV's lane change, to finish or to undo: ``enabled_firsts`` and ``Firsts`` keep to the
    lane, for every engine (each composes its answer here)."""
    for lane in Lane:
        scenario = replace(make_scenario(lane.value, [], [], 0), sound=Sound(profile("default"), commitment=COMMIT))
        moving = replace(scenario, sound=replace(scenario.sound, sideways_s=1.0))
        still, under_way = (enabled_firsts(problem_for(s, ModelKind.FINAL)) for s in (scenario, moving))
        assert any(ACTION_RULES[a].changes_lane for a in still)
        assert under_way == tuple(a for a in still if not ACTION_RULES[a].changes_lane)
        proofs = _Anything()
        firsts = Firsts(proofs, problem_for(moving, ModelKind.FINAL))  # type: ignore[arg-type]
        assert [a for a in Action if a in firsts] == list(under_way) and set(proofs.asked) <= set(under_way)


class _Anything:
    """Proofs that hold every sequence, and remember each one's first action."""

    def __init__(self) -> None:
        self.asked: list[Action] = []

    def holds(self, actions: Sequence[Action], goal: bool) -> bool:
        self.asked.append(actions[0])
        return True
