"""The sound model's commitment semantics in the interpreter: its proofs (``Proofs``) for the answer
``spec.commitment`` composes, and the checker every engine's answer is validated by (``validate``).

The proofs are ``spec.sound``'s: a sequence known whole is checked step by step, each step's window ending where the
ramp into the next starts (``SoundRules.step_violation``'s ``following``), and its end by the minimal-risk manoeuvre
(``continuation_violation``); the prediction is the paper's rules over integer offsets (``oracle.offsets``).
The pipeline (``oracle.planner``) asks the final model, then the preparations model, as for any answer.
"""

from __future__ import annotations

import heapq
from collections.abc import Container, Iterable, Sequence
from dataclasses import dataclass
from functools import lru_cache

from oracle import bitplan, sound
from oracle.interpreter import problem_goal, problem_step
from oracle.offsets import OffsetSearch
from oracle.search import depth_first
from oracle.sound import Refusal, rules_for, start
from spec.actions import Action
from spec.answers import Commit, Limits, SearchResult, Status, Strategy
from spec.commitment import answer, commitment, lane_after, split
from spec.cost import COST_DOC, COST_TERMS, action_cost
from spec.escapes import Escape
from spec.rules import disabled_reason
from spec.scenario import Problem
from spec.sound import SoundRules, SoundState, Violation
from spec.state import Collision, State


def _sound_rules(problem: Problem) -> SoundRules:
    rules = rules_for(problem)
    if not isinstance(rules, SoundRules):
        raise ValueError("the commitment semantics needs the sound model's physical checks")
    return rules


@dataclass(frozen=True, slots=True)
class Proved:
    """An escape proved after a sequence of committed actions: which one, and the state it ends in."""

    escape: Escape
    end: SoundState


def sequence_refusal(rules: SoundRules, state: SoundState, actions: Sequence[Action]) -> tuple[
        str | None, SoundState]:
    """Why ``actions`` from ``state``, known whole, are not safe at every instant (each step's window ending where
    the ramp into the next starts: ``SoundRules.step_violation``'s ``following``; the last one's at its end, where
    the minimal-risk manoeuvre takes over), or None; and the state they end in (where they got to)."""
    for n, action in enumerate(actions):
        following = actions[n + 1] if n + 1 < len(actions) else None
        found = rules.step_violation(state, action, following)
        if found is not None:
            return f"{action.value}, {_short(found)}", state
        state = rules.after(state, action)
    return None, state


def escape_after(rules: SoundRules, state: SoundState, committed: Sequence[Action],
                 allowed: Sequence[Escape]) -> Proved | None:
    """The first of ``allowed`` escapes from the lane ``committed`` ends in such that the committed actions and the
    escape's, as one sequence, are safe at every instant and end safe for ever under the minimal-risk manoeuvre
    (an escape keeps its actions' lane guards but not the model's count of lane changes)."""
    lane = lane_after(state.lane, committed)
    for escape in allowed:
        if escape.from_lane is not lane:
            continue
        why, end = sequence_refusal(rules, state, (*committed, *escape.actions))
        if why is None and rules.continuation_violation(end) is None:
            return Proved(escape, end)
    return None


def no_escape_reason(rules: SoundRules, state: SoundState, committed: Sequence[Action],
                     allowed: Sequence[Escape]) -> str:
    """Why no escape of ``allowed`` is proved after ``committed``: each one's first refusal, in short (the conflict,
    the vehicle, when)."""
    lane, reasons = lane_after(state.lane, committed), []
    for escape in allowed:
        if escape.from_lane is not lane:
            continue
        why, end = sequence_refusal(rules, state, (*committed, *escape.actions))
        if why is None:
            found = rules.continuation_violation(end)
            why = "after it, " + (_short(found) if found is not None else "safe")
        reasons.append(f"{escape.kind.value} ({', '.join(a.value for a in escape.actions) or 'in lane'}): {why}")
    return "; ".join(reasons) or f"no escape allowed from the {lane.value} lane"


def _short(found: Refusal) -> str:
    return (f"{found.conflict.value} with {found.vehicle.name} at {found.time_s:.1f} s" if isinstance(found, Violation)
            else found.describe())


def committable(problem: Problem, state: SoundState) -> tuple[dict[Action, Proved], dict[Action, str]]:
    """The first actions from the start that the sound model commits to (safe, with a proved escape after them),
    and for every other enabled action why not."""
    rules, allowed = _sound_rules(problem), commitment(problem)
    ok: dict[Action, Proved] = {}
    refused: dict[Action, str] = {}
    for action in Action:
        if disabled_reason(State(state.lane, (), (), state.lane_changes, 0), action, problem.rules) is not None:
            continue
        escapes = allowed.allowed(lane_after(state.lane, (action,)))
        proved = escape_after(rules, state, (action,), escapes)
        if proved is not None:
            ok[action] = proved
            continue
        found = rules.step_violation(state, action)
        refused[action] = found.describe() if found is not None else \
            "no escape after it: " + no_escape_reason(rules, state, (action,), escapes)
    return ok, refused


Key = tuple[int, int, int, int]  # the paper's offset form: lane changes, left offset, oncoming ticks, steps


def predict(problem: Problem, strategy: Strategy, firsts: Container[Action], limits: Limits) -> SearchResult:
    """The predicted plan: the strategy's plan under the paper's rules (``oracle.offsets``: every vehicle at the
    common speed from its cell, the paper's collisions and goals), its first action one of ``firsts`` (the ones the
    sound model commits to), at least one action long. ``sensible``: depth first in the action order; ``shortest``:
    the first shortest in the action order; ``optimal``: the least ``spec.cost``."""
    live = bitplan.live_positions(problem)
    search = OffsetSearch(problem)
    form = search.form

    def successors(key: Key) -> Iterable[tuple[Action, Key]]:
        """Only towards the goal (``bitplan.live_positions``): the same first plan, without its dead ends; a first
        action asked about (``firsts``) only once it is live, in order, as the search takes it."""
        if key[3] > 0:
            return [m for m in search.successors(key) if live(*m[1])]
        return (m for m in search.successors(key) if live(*m[1]) and m[0] in firsts)

    begin: Key = (0, 0, 0, 0)
    if strategy is Strategy.SENSIBLE:
        status, actions, _, explored, detail = depth_first(begin, successors, search.goal, limits.max_states,
                                                           limits.timeout_s)
        return SearchResult(status, actions, explored, detail)
    if strategy is Strategy.SHORTEST:
        parent: dict[Node, tuple[Node, Action] | None] = {_node(begin): None}
        layer = [begin]
        while layer:
            following = []
            for key in layer:
                for action, nxt in successors(key):
                    if _node(nxt) in parent:
                        continue
                    parent[_node(nxt)] = (_node(key), action)
                    if search.goal(nxt):
                        return SearchResult(Status.PLAN, _back(parent, _node(nxt)), len(parent))
                    following.append(nxt)
            layer = following
        return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), len(parent))
    queue: list[tuple[tuple[int, ...], int, Key, tuple[Action, ...]]] = [((0,) * len(COST_TERMS), 0, begin, ())]
    fewest: dict[Node, int] = {}
    pushed = 0
    while queue:
        cost, _, key, actions = heapq.heappop(queue)
        if fewest.get(_node(key), key[3] + 1) <= key[3]:
            continue
        fewest[_node(key)] = key[3]
        if key[3] > 0 and search.goal(key):
            return SearchResult(Status.PLAN, actions, len(fewest), f"optimal under {COST_DOC}",
                                extra={"cost": dict(zip(COST_TERMS, cost, strict=True)),
                                       "cost_order": list(COST_TERMS)})
        for action, nxt in successors(key):
            if fewest.get(_node(nxt), nxt[3] + 1) <= nxt[3]:
                continue
            pushed += 1
            added = action_cost(action, form.lanes[nxt[0]])
            heapq.heappush(queue, (tuple(a + b for a, b in zip(cost, added, strict=True)), pushed, nxt,
                                   (*actions, action)))
        if len(fewest) >= limits.max_states:
            return SearchResult(Status.INCOMPLETE, (), len(fewest), f"state limit {limits.max_states} reached")
    return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), len(fewest))


Node = tuple[int, int, int, bool]  # a search node: the offsets, and whether an action was taken


def _node(key: Key) -> Node:
    """What a search visits a key as: its offsets, and whether it is past the start. The start is a node of its own
    (its successors are the committable actions only, and it is never the goal): a plan that comes back to the
    start's offsets (a drive that moves nothing) is a plan, not a revisit."""
    return (*key[:3], key[3] > 0)


def _back(parent: dict[Node, tuple[Node, Action] | None], key: Node) -> tuple[Action, ...]:
    actions = []
    link = parent[key]
    while link is not None:
        key, action = link
        actions.append(action)
        link = parent[key]
    return tuple(reversed(actions))


class Interpreter:
    """The interpreter's proofs of one problem (``spec.commitment.Proofs``), each sequence answered once."""

    def __init__(self, problem: Problem) -> None:
        self.problem, self.rules, self.first = problem, _sound_rules(problem), start(problem)
        self._held: dict[tuple[tuple[Action, ...], bool], bool] = {}

    def start_violation(self) -> str | None:
        hit = self.rules.start_violation(self.first)
        return None if hit is None else hit.describe()

    def prefetch(self, asked: Sequence[tuple[tuple[Action, ...], bool]]) -> None:
        """Nothing: each sequence is proved when asked (a depth-first prediction asks few)."""

    def holds(self, actions: Sequence[Action], goal: bool) -> bool:
        key = (tuple(actions), goal)
        if key not in self._held:
            why, end = sequence_refusal(self.rules, self.first, actions)
            self._held[key] = why is None and (not goal or self.rules.goal_holds(end, self.problem.goal)) \
                and self.rules.continuation_violation(end) is None
        return self._held[key]

    def predict(self, strategy: Strategy, firsts: Container[Action], limits: Limits) -> SearchResult:
        return predict(self.problem, strategy, firsts, limits)

    def no_plan_beyond(self) -> bool:
        return bitplan.beyond_horizon(self.problem).status is Status.NO_PLAN

    def why_not(self, action: Action) -> str:
        found = self.rules.step_violation(self.first, action)
        if found is not None:
            return found.describe()
        escapes = commitment(self.problem).allowed(lane_after(self.first.lane, (action,)))
        return "no escape after it: " + no_escape_reason(self.rules, self.first, (action,), escapes)

    def states(self, actions: Sequence[Action]) -> tuple[State, ...]:
        return states_along(self.problem, actions)


@lru_cache(maxsize=64)
def proofs(problem: Problem) -> Interpreter:
    """The interpreter's proofs of ``problem``, kept for the last few problems: the pipeline's validation of an
    answer asks the same sequences again."""
    return Interpreter(problem)


def solve(problem: Problem, strategy: Strategy, limits: Limits) -> SearchResult:
    """The interpreter's answer under the commitment semantics (``spec.commitment.answer``)."""
    return answer(problem, strategy, limits, proofs(problem))


def states_along(problem: Problem, actions: Sequence[Action]) -> tuple[State, ...]:
    """The display states along ``actions`` under the sound model's rules (the initial one first)."""
    rules, state = _sound_rules(problem), start(problem)
    shown = [sound.display(problem, state)]
    for action in actions:
        state = rules.after(state, action)
        shown.append(sound.display(problem, state))
    return tuple(shown)


@dataclass(frozen=True, slots=True)
class CommitValidation:
    """The verdict on an action list under the commitment semantics: which part fails and why, if any."""

    valid: bool
    reason: str
    states: tuple[State, ...]  # display states along the committed part (the initial one first)
    commit: Commit | None = None  # the split, when valid


def validate(problem: Problem, actions: Sequence[Action]) -> CommitValidation:
    """Whether ``actions`` is an answer of the commitment semantics: from a safe start, a non-empty committed prefix
    (safe steps, an escape proved after it, at most ``most_actions``; or the whole list, proved to the goal), the
    whole list enabled within the horizon, and reaching the goal under nominal motion (the predicted continuation),
    as ``solve`` answers. Says which part fails and why."""
    rules, first = _sound_rules(problem), start(problem)
    shown = (sound.display(problem, first),)
    hit = rules.start_violation(first)
    if hit is not None:
        return CommitValidation(False, f"unsafe start: the start already breaks the safety specification: "
                                f"{hit.describe()}", shown)
    if len(actions) > problem.horizon:
        return CommitValidation(False, f"{len(actions)} actions exceed the horizon of {problem.horizon}", shown)
    if not actions:
        whole = rules.goal_holds(first, problem.goal) and rules.continuation_violation(first) is None
        return CommitValidation(whole, "goal holds in the initial state, safe for ever" if whole else
                                "the empty list commits to nothing: the goal does not hold for every position "
                                "at the start", shown, Commit((), None, ()) if whole else None)
    state = first
    for n, action in enumerate(actions, start=1):
        reason = disabled_reason(State(state.lane, (), (), state.lane_changes, 0), action, problem.rules)
        if reason is not None:
            return CommitValidation(False, f"step {n}: {reason}", shown)
        state = rules.after(state, action)
    allowed = commitment(problem)
    escapes = allowed.allowed(lane_after(first.lane, actions[:1]))
    if escape_after(rules, first, actions[:1], escapes) is None:
        found = rules.step_violation(first, actions[0])
        if found is not None:
            return CommitValidation(False, f"committed part: step 1 ({actions[0].value}): {found.describe()}", shown)
        return CommitValidation(False, f"committed part: no escape after step 1 ({actions[0].value}): "
                                f"{no_escape_reason(rules, first, actions[:1], escapes)}", shown)
    predicted = _predicted_reason(problem, actions)
    if predicted is not None:
        return CommitValidation(False, f"predicted continuation: {predicted}", shown)
    committed, escape = split(problem, actions, proofs(problem))
    commit = Commit(committed, escape, tuple(actions[len(committed):]))
    what = ("a whole plan, proved to its goal and safe for ever after" if escape is None else
            f"{len(committed)} committed action(s), escape {escape.describe()}, {len(actions) - len(committed)} "
            "predicted under the paper's rules")
    return CommitValidation(True, what, states_along(problem, committed), commit)


def _predicted_reason(problem: Problem, actions: Sequence[Action]) -> str | None:
    """Why ``actions`` are no predicted plan (the paper's rules, ``oracle.interpreter``: each step collision-free,
    the goal first after the last, never at the start), or None when they are one."""
    state = problem.scenario.initial_state()
    for n, action in enumerate(actions, start=1):
        if n > 1 and problem_goal(problem, state):
            return f"the goal already holds under the paper's rules before step {n}"
        after = problem_step(problem, state, action)
        if isinstance(after, Collision):
            return f"step {n} ({action.value}) under the paper's rules: {after.describe()}"
        state = after
    if not problem_goal(problem, state):
        return f"the goal does not hold under the paper's rules after {len(actions)} action(s)"
    return None


def prove_beyond(problem: Problem) -> SearchResult:
    """After an answer of no plan within the horizon: "no plan" where ``solve`` proves it (no committable step, or
    no plan of any length under the paper's rules), else no plan within the horizon."""
    found = solve(problem, Strategy.SHORTEST, Limits())
    if found.status is Status.NO_PLAN:
        return found
    return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), found.states_explored, found.detail)
