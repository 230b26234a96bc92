"""The commitment semantics' answer (``spec.escapes``), composed once from what an engine proves.

Every engine answers the commitment semantics through ``answer``: it brings its own proofs
(``Proofs``: its translation of the sound model's steps, escapes and continuation, and of the
paper's rules for the prediction); the order they are asked in, which escape is taken, how long
the committed part is and what each "no plan" means are stated here alone. So two engines whose
proofs agree give the same answer, and cross-validation holds each engine's proofs to the others'
through the answers.

An answer is found in three steps:

1. the start: one that already breaks the specification is ``unsafe_start`` (the lane's first escape to take at
   once, unproved); one where the goal holds for every position and which is safe for ever is the empty plan, whole;
2. the **committable** first actions: enabled, and with an escape proved after them (``escape_after``: the action
   and the escape as one sequence, safe at every instant, then safe for ever); none is "no plan";
3. the **predicted** plan: the strategy's plan under the paper's rules, its first action a committable one
   (``Firsts``: each proved when the search first asks). Its **committed** part (``split``) is the whole plan when
   the sound model proves it to its goal and for ever after within ``Commitment.most_actions``, else its longest
   prefix of at most that many actions after which an escape is proved. The rest is the prediction.
"""

from __future__ import annotations

from collections.abc import Container, Sequence
from dataclasses import replace
from typing import Protocol

from spec.actions import ACTION_ORDER, ACTION_RULES, Action
from spec.answers import Commit, Limits, SearchResult, Status, Strategy
from spec.escapes import COMMIT, Commitment, Escape, unsafe_start_escape
from spec.lanes import Lane
from spec.rules import disabled_reason
from spec.scenario import Problem
from spec.state import State


class ProofIncomplete(Exception):
    """An engine's proof that hit its limit (time, states): the answer is "search incomplete", never a refusal."""


class Proofs(Protocol):
    """What one engine proves of one problem, for the commitment semantics (a proof that hits its limit raises
    ``ProofIncomplete``)."""

    def start_violation(self) -> str | None:
        """How the start already breaks the safety specification, or None."""

    def prefetch(self, asked: Sequence[tuple[tuple[Action, ...], bool]]) -> None:
        """``holds`` will be asked of (some of) these: an engine may prove them together (Spin: one run), or not."""

    def holds(self, actions: Sequence[Action], goal: bool) -> bool:
        """Whether ``actions`` from the start, known whole, are safe at every instant (each step's window ending
        where the ramp into the next starts) and end safe for ever under the minimal-risk manoeuvre; with ``goal``,
        with the goal holding for every position at their end too. The actions' lane guards are the caller's."""

    def predict(self, strategy: Strategy, firsts: Container[Action], limits: Limits) -> SearchResult:
        """The strategy's plan under the paper's rules (every vehicle at the common speed from its cell, no
        phantoms), at least one action long, its first action in ``firsts``."""

    def no_plan_beyond(self) -> bool:
        """Whether the paper's rules are proved to have no plan of any length (False: not proved)."""

    def why_not(self, action: Action) -> str:
        """Why ``action``, enabled at the start, is not committed to (for people)."""

    def states(self, actions: Sequence[Action]) -> tuple[State, ...]:
        """The display states along ``actions`` from the start (the initial one first)."""


def commitment(problem: Problem) -> Commitment:
    """The problem's commitment (``COMMIT`` when its scenario names none)."""
    sc = problem.scenario.sound
    return COMMIT if sc is None or sc.commitment is None else sc.commitment


def paper_problem(problem: Problem) -> Problem:
    """The prediction's problem: ``problem`` under the paper's rules alone (its cells, every vehicle at the common
    speed, no phantoms, the paper's collisions and goals)."""
    s = problem.scenario
    return replace(problem, scenario=replace(s, sound=None, left_m=None, right_m=None, left_mps=None,
                                             right_mps=None))


def lane_after(lane: Lane, actions: Sequence[Action]) -> Lane:
    for action in actions:
        lane = ACTION_RULES[action].to_lane or lane
    return lane


def guarded(lane: Lane, actions: Sequence[Action]) -> bool:
    """Whether each of ``actions`` is enabled by its lane guard, from ``lane`` on (what an engine's proofs take as
    given: ``Proofs.holds``)."""
    for action in actions:
        rule = ACTION_RULES[action]
        if rule.from_lane not in (None, lane):
            return False
        lane = rule.to_lane or lane
    return True


def escape_sequences(lane: Lane, committed: Sequence[Action], allowed: Commitment) -> list[tuple[Action, ...]]:
    """The sequences ``escape_after`` proves, in order: ``committed`` then each escape allowed from where it ends."""
    return [(*committed, *escape.actions) for escape in allowed.allowed(lane_after(lane, committed))]


def escape_after(proofs: Proofs, lane: Lane, committed: Sequence[Action], allowed: Commitment) -> Escape | None:
    """The first escape ``allowed`` from the lane ``committed`` ends in (starting from ``lane``) that ``proofs``
    prove after it, with it as one sequence."""
    for escape in allowed.allowed(lane_after(lane, committed)):
        if proofs.holds((*committed, *escape.actions), goal=False):
            return escape
    return None


def enabled_firsts(problem: Problem) -> tuple[Action, ...]:
    """The actions the paper's guards enable at the start (its lane, no lane change made yet); while a sideways move
    is under way there (``spec.sound.Sound.sideways_s``), only those in lane: the move is the AV's lane change, to
    finish or to undo, never to start another over it."""
    start = State(problem.scenario.lane, (), (), 0, 0)
    sound = problem.scenario.sound
    moving = sound is not None and sound.sideways_s > 0
    return tuple(a for a in Action if disabled_reason(start, a, problem.rules) is None
                 and not (moving and ACTION_RULES[a].changes_lane))


def committable_in_order(problem: Problem, firsts: Container[Action]) -> tuple[Action, ...]:
    """The enabled first actions in ``firsts``, in ``ACTION_ORDER``: what an engine whose prediction takes them as
    a set asks of ``Firsts`` (only enabled ones: a proof takes its lane guards as given)."""
    enabled = enabled_firsts(problem)
    return tuple(a for a in ACTION_ORDER if a in enabled and a in firsts)


class Firsts:
    """The committable first actions, as a set a search asks about: each one proved the first time it is asked (a
    depth-first search asks only until the first live one that commits)."""

    def __init__(self, proofs: Proofs, problem: Problem) -> None:
        self.proofs, self.lane, self.allowed = proofs, problem.scenario.lane, commitment(problem)
        self.enabled = enabled_firsts(problem)
        self.proved: dict[Action, Escape | None] = {}

    def __contains__(self, action: object) -> bool:
        if not isinstance(action, Action) or action not in self.enabled:
            return False
        if action not in self.proved:
            self.proved[action] = escape_after(self.proofs, self.lane, (action,), self.allowed)
        return self.proved[action] is not None


def split(problem: Problem, actions: Sequence[Action], proofs: Proofs) -> tuple[tuple[Action, ...], Escape | None]:
    """The committed part of a predicted plan and its escape: the whole plan when it is proved to its goal and safe
    for ever after within ``most_actions``; else its longest prefix of at most ``most_actions`` actions after which an
    escape is proved (at least its first action, which the search made committable)."""
    allowed = commitment(problem)
    plan = tuple(actions)
    most = len(plan) if allowed.most_actions is None else min(allowed.most_actions, len(plan))
    lane = problem.scenario.lane
    proofs.prefetch([*([(plan, True)] if most == len(plan) else []),
                     *((seq, False) for n in range(most, 0, -1) for seq in escape_sequences(lane, plan[:n], allowed))])
    if most == len(plan) and proofs.holds(plan, goal=True):
        return plan, None
    for n in range(most, 0, -1):
        escape = escape_after(proofs, lane, plan[:n], allowed)
        if escape is not None:
            return plan[:n], escape
    raise ValueError(f"the predicted plan's first action {plan[0].value} has no escape (it was committable)")


def answer(problem: Problem, strategy: Strategy, limits: Limits, proofs: Proofs) -> SearchResult:
    """The commitment semantics' answer to ``problem`` from ``proofs`` (see the module's docstring); "search
    incomplete" when a proof or the prediction hit its limit."""
    try:
        return _answer(problem, strategy, limits, proofs)
    except ProofIncomplete as err:
        return SearchResult(Status.INCOMPLETE, (), 0, f"a proof did not finish: {err}")


def _answer(problem: Problem, strategy: Strategy, limits: Limits, proofs: Proofs) -> SearchResult:
    hit = proofs.start_violation()
    if hit is not None:
        take = unsafe_start_escape(problem.scenario.lane)
        return SearchResult(Status.UNSAFE_START, (), 1, f"the start already breaks the safety specification: {hit}; "
                            f"escape at once: {take.describe()}", commit=Commit((), take, (), escape_proved=False))
    allowed, lane = commitment(problem), problem.scenario.lane
    proofs.prefetch([((), True), *((seq, False) for a in enabled_firsts(problem)
                                   for seq in escape_sequences(lane, (a,), allowed))])
    if proofs.holds((), goal=True):
        return SearchResult(Status.PLAN, (), 1, "goal holds in the initial state, safe for ever", proofs.states(()),
                            commit=Commit((), None, ()))
    firsts = Firsts(proofs, problem)
    predicted = proofs.predict(strategy, firsts, limits)
    if predicted.status is not Status.PLAN:
        enabled = enabled_firsts(problem)
        ok = [a for a in enabled if a in firsts]
        if not ok:
            why = "; ".join(f"{a.value}: {proofs.why_not(a)}" for a in enabled)
            return SearchResult(Status.NO_PLAN, (), 1, f"no committed step is provable (the AV keeps its minimal-risk "
                                f"manoeuvre): {why}")
        if predicted.status is Status.NO_PLAN_WITHIN_HORIZON and proofs.no_plan_beyond():
            return SearchResult(Status.NO_PLAN, (), predicted.states_explored, "the paper's rules prove that no plan "
                                "of any length reaches the goal (the predicted continuation's model)")
        detail = (f"no predicted continuation reaches the goal within {problem.horizon} actions from a committable "
                  f"step ({', '.join(a.value for a in ok)}) under the paper's rules" + (
                      f": {predicted.detail}" if predicted.detail else ""))
        return replace(predicted, detail=detail, states=(), commit=None)
    committed, escape = split(problem, predicted.actions, proofs)
    return SearchResult(Status.PLAN, committed, predicted.states_explored, _detail(committed, escape, predicted),
                        proofs.states(committed), predicted.extra,
                        Commit(committed, escape, predicted.actions[len(committed):]))


def _detail(committed: tuple[Action, ...], escape: Escape | None, predicted: SearchResult) -> str:
    if escape is None:
        return "a whole plan, proved to its goal and safe for ever after" + (
            f" ({predicted.detail})" if predicted.detail else "")
    return (f"{len(committed)} committed action(s) with a proved escape; {len(predicted.actions) - len(committed)} "
            "predicted to the goal under the paper's rules")
