"""The sound model in the interpreter: its step, plan validation and its planners (sensible, shortest, optimal).

Pure functions over frozen values, like the paper's interpreter (``oracle.interpreter``): the rules
are ``spec.sound``'s, the search is ``oracle.search.depth_first`` (sensible), an ordered
breadth-first search (shortest) or a uniform-cost search with ``spec.cost`` (optimal) over
``SoundState``s. A plan reaches the goal with every step safe
at every instant and its last state safe for ever (the minimal-risk manoeuvre); the empty plan
is held to the same. The sound model cannot prove that no plan of any length exists (time grows
without bound): beyond the horizon it says so, never "no plan".
"""

from __future__ import annotations

import heapq
import time
from collections import OrderedDict, deque
from collections.abc import Callable, Hashable, Iterator, Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import Protocol

from oracle.abstraction import offsets_of
from oracle.interpreter import problem_collision, problem_goal
from oracle.interpreter import step as paper_step
from oracle.search import depth_first
from spec.actions import Action
from spec.answers import Limits, SearchResult, Status, Strategy
from spec.cost import COST_DOC, COST_TERMS, action_cost
from spec.lanes import Lane
from spec.models import GoalRule
from spec.motion import action_speed_mps
from spec.rules import disabled_guard, disabled_reason
from spec.scenario import Problem, Scenario
from spec.sound import Checks, SoundRules, SoundState, Violation, advance
from spec.state import Collision, State

Refusal = Violation | Collision  # why a start, a step or a continuation is refused


class Rules(Protocol):
    """What the sound model's code path asks of its rules (``SoundRules``, or the paper's cells for the identity)."""

    def key(self, state: SoundState) -> Hashable: ...
    def start_violation(self, state: SoundState) -> Refusal | None: ...
    def step_violation(self, state: SoundState, action: Action) -> Refusal | None: ...
    def after(self, state: SoundState, action: Action) -> SoundState: ...
    def continuation_violation(self, state: SoundState) -> Refusal | None: ...
    def goal_holds(self, state: SoundState, goal: GoalRule) -> bool: ...
    def hopeless(self, state: SoundState, goal: GoalRule) -> bool: ...
    def beyond_reach(self, state: SoundState, goal: GoalRule, actions_left: int) -> bool: ...


@lru_cache(maxsize=64)  # a few problems at a time (a pipeline's stages); a campaign must not keep every one
def rules_for(problem: Problem) -> Rules:
    """The sound model's rules on ``problem``'s scenario (its vehicles as intervals, its phantoms)."""
    sc = problem.scenario
    sound = sc.sound
    if sound is None:
        raise ValueError("the problem's scenario has no sound model")
    if sound.checks is Checks.PAPER_CELLS:
        return PaperCells(problem)
    return _scenario_rules(sc)


@lru_cache(maxsize=32)
def _scenario_rules(sc: Scenario) -> SoundRules:
    """One scenario's rules, shared by its models (they read the scenario alone; the goal is asked per question), so
    that the preparations model's search reuses the answers the final model's found."""
    assert sc.sound is not None  # rules_for checked it
    return SoundRules(sc.sound, sc.lane, sc.left_lane, sc.right_lane, sc.grid, sc.target_indices,
                      left_m=sc.left_m, right_m=sc.right_m, left_mps=sc.left_mps, right_mps=sc.right_mps)


class PaperCells:
    """The paper's cell rules (``oracle.interpreter``) asked on the nominal cells of sound states: the identity
    check of the sound model's code path (its states, time and advance, searches, validation). Only with zero
    bounds: every vehicle at the common speed, no sensing error, no phantoms; the AV at its actions' speeds with
    instant changes is what the nominal cells already say."""

    def __init__(self, problem: Problem) -> None:
        sound, grid = problem.scenario.sound, problem.grid
        b = sound.bounds if sound is not None else None
        zero = b is not None and not b.phantoms and b.sensing_error_m == 0 and b.latency_s == 0 and all(
            s.low_mps == s.high_mps == grid.speed for s in (b.same_mps, b.oncoming_mps))
        if not zero:
            raise ValueError("the paper's cell rules hold only with zero bounds (common speed, no error, no phantoms)")
        self.problem = problem
        self.speeds = {a: action_speed_mps(a, grid) for a in Action}
        form = offsets_of(problem)
        self.track_left, self.o_saturation = form.track_left, form.o_saturation
        # The paper's rules read nothing but the key: each question answered once (a search meets a key at many
        # step counts).
        self._steps: dict[tuple[Hashable, Action], Refusal | None] = {}
        self._goals: dict[Hashable, bool] = {}

    def key(self, state: SoundState) -> Hashable:
        """The paper's search state (``oracle.offsets``): lane changes, the left lane's offset (0 when it is empty),
        oncoming ticks up to saturation; the paper's rules read nothing else."""
        left = state.t_units - state.d_cells if self.track_left else 0
        return state.lane_changes, left, min(state.t_units + state.d_cells, self.o_saturation)

    def start_violation(self, state: SoundState) -> Refusal | None:
        return problem_collision(self.problem, display(self.problem, state))

    def step_violation(self, state: SoundState, action: Action) -> Refusal | None:
        asked = (self.key(state), action)
        if asked not in self._steps:
            after = paper_step(display(self.problem, state), action, self.problem.rules, self.problem.grid)
            self._steps[asked] = after if isinstance(after, Collision) else None
        return self._steps[asked]

    def after(self, state: SoundState, action: Action) -> SoundState:
        return advance(state, action, self.problem.grid, self.speeds[action])

    def continuation_violation(self, state: SoundState) -> Refusal | None:
        return None  # the paper's rules end a plan at its goal, nothing after it

    def goal_holds(self, state: SoundState, goal: GoalRule) -> bool:
        asked = self.key(state)
        if asked not in self._goals:
            self._goals[asked] = problem_goal(self.problem, display(self.problem, state))
        return self._goals[asked]

    def hopeless(self, state: SoundState, goal: GoalRule) -> bool:
        return False

    def beyond_reach(self, state: SoundState, goal: GoalRule, actions_left: int) -> bool:
        return False


def start(problem: Problem) -> SoundState:
    """The sound model's initial state."""
    return SoundState(problem.scenario.lane, 0, 0, 0, 0, None, None)


def step(problem: Problem, state: SoundState, action: Action) -> SoundState | Refusal:
    """One decision step: the state after ``action``, or the violation that forbids it."""
    if disabled_guard(_paper(state), action, problem.rules) is not None:
        raise ValueError(disabled_reason(_paper(state), action, problem.rules))
    rules = rules_for(problem)
    found = rules.step_violation(state, action)
    return found if found is not None else rules.after(state, action)


def done(problem: Problem, state: SoundState) -> bool:
    """Whether a plan may end in ``state``: the goal holds for every position, and the state is safe for ever."""
    rules = rules_for(problem)
    return rules.goal_holds(state, problem.goal) and rules.continuation_violation(state) is None


#: The steps that keep the AV in the left lane without an overtake, in the order they are tried (``keep_lane``).
KEEP_LANE: tuple[Action, ...] = (Action.DRIVE, Action.BRAKE)


def keep_lane(problem: Problem) -> Action | None:
    """The first step of ``KEEP_LANE`` that is safe from the start, its last state safe for ever (what the AV does
    when the sound model has no overtake, or none yet); None when the AV is not in the left lane, the start itself
    is unsafe, or no step is: the assumptions no longer give the AV a safe way on."""
    state = start(problem)
    rules = rules_for(problem)
    if state.lane is not Lane.LEFT or rules.start_violation(state) is not None:
        return None
    for action in KEEP_LANE:
        after = step(problem, state, action)
        if isinstance(after, SoundState) and rules.continuation_violation(after) is None:
            return action
    return None


def display(problem: Problem, state: SoundState) -> State:
    """The paper-style state shown for a sound state: every vehicle where the common speed puts its cell (the sound
    model's sets are wider; traces show the cells for reading, and ``oracle.reach`` checks the sets)."""
    sc, t, d = problem.scenario, state.t_units, state.d_cells
    return State(state.lane, tuple(c + t - d for c in sc.left_lane), tuple(c - t - d for c in sc.right_lane),
                 state.lane_changes, state.steps)


def _paper(state: SoundState) -> State:
    """A paper state with the lane and counts of ``state`` (the guards read nothing else)."""
    return State(state.lane, (), (), state.lane_changes, state.steps)


Entry = tuple[SoundState, int, Action | None]  # a state a search reached, the entry it came from, the action


class _Search:
    """One problem's successors, goal and limits for a search, its rules looked up once (hashing a problem is not
    free)."""

    def __init__(self, problem: Problem, limits: Limits | None, rules: Rules | None = None) -> None:
        self.problem, self.limits = problem, limits or Limits()
        self.deadline = None if self.limits.timeout_s is None else time.monotonic() + self.limits.timeout_s
        self.rules, self.goal, self.horizon = rules or rules_for(problem), problem.goal, problem.horizon
        self.key = self.rules.key
        # The guards read the lane and the lane changes only.
        self.enabled = {(lane, lc): [a for a in Action
                                     if disabled_guard(State(lane, (), (), lc, 0), a, problem.rules) is None]
                        for lane in Lane for lc in range(problem.rules.max_lane_changes + 1)}

    def successors(self, state: SoundState, cut: Callable[[SoundState], None] | None = None) -> Iterator[
            tuple[Action, SoundState]]:
        """The states each enabled, safe action leads to, but those from which the goal can never hold and those from
        which it cannot hold within the horizon (unless it holds there); ``cut`` hears of the latter (a proof of "no
        plan of any length" counts them as reaching the horizon)."""
        if state.steps >= self.horizon:
            return
        rules, goal = self.rules, self.goal
        for action in self.enabled[state.lane, state.lane_changes]:
            if rules.step_violation(state, action) is None:
                nxt = rules.after(state, action)
                if rules.hopeless(nxt, goal):
                    continue
                if rules.beyond_reach(nxt, goal, self.horizon - nxt.steps) and not self.done(nxt):
                    if cut is not None:
                        cut(nxt)
                    continue
                yield action, nxt

    def done(self, state: SoundState) -> bool:
        return self.rules.goal_holds(state, self.goal) and self.rules.continuation_violation(state) is None

    def stopped(self, explored: int, clock: bool = True) -> SearchResult | None:
        """"Incomplete" once the state limit is reached, or the time limit (looked at only when ``clock``)."""
        if explored >= self.limits.max_states:
            return SearchResult(Status.INCOMPLETE, (), explored, f"state limit {self.limits.max_states} reached")
        if clock and self.deadline is not None and time.monotonic() > self.deadline:
            return SearchResult(Status.INCOMPLETE, (), explored, f"time limit {self.limits.timeout_s} s reached")
        return None

    def plan(self, entries: list[Entry], entry: int, detail: str = "",
             extra: dict[str, object] | None = None) -> SearchResult:
        """The plan that led to ``entries[entry]``, its states shown as the paper's."""
        actions, states = [], [entries[entry][0]]
        while entry > 0:
            _, entry, action = entries[entry]
            if action is not None:
                actions.append(action)
            states.append(entries[entry][0])
        return SearchResult(Status.PLAN, tuple(reversed(actions)), len(entries), detail,
                            tuple(display(self.problem, s) for s in reversed(states)), extra or {})


def _trivial(problem: Problem, rules: Rules | None = None) -> SearchResult | None:
    first = start(problem)
    rules = rules or rules_for(problem)
    hit = rules.start_violation(first)
    if hit is not None:
        return SearchResult(Status.NO_PLAN, (), 1, f"initial state: {hit.describe()}")
    if rules.goal_holds(first, problem.goal) and rules.continuation_violation(first) is None:
        return SearchResult(Status.PLAN, (), 1, "goal holds in the initial state, safe for ever",
                            (display(problem, first),))
    return None


def beyond(problem: Problem) -> str:
    """What the sound model says when no plan is found within the horizon and none is proved beyond it."""
    return f"no plan within {problem.horizon} actions (a longer one may exist: the sound model's time has no end)"


#: Problems whose complete breadth-first search ended without a proof (a few: a pipeline's stages).
_UNPROVED: OrderedDict[Problem, None] = OrderedDict()


def prove_beyond(problem: Problem) -> SearchResult:
    """After a search found no plan within the horizon: "no plan" if every path is refused before it (the
    breadth-first search's proof, ``shortest``), else "no plan within the horizon"."""
    if problem not in _UNPROVED:
        found = shortest(problem)
        if found.status is Status.NO_PLAN:
            return found
    return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), 0, beyond(problem))


def sensible(problem: Problem, limits: Limits | None = None, rules: Rules | None = None) -> SearchResult:
    """Depth-first search in the action order (the paper's "sensible" plan), states with their step counts; under
    ``rules`` when given (the predicted continuation's, ``oracle.commit``), else the problem's."""
    trivial = _trivial(problem, rules)
    if trivial is not None:
        return trivial
    search = _Search(problem, limits, rules)
    key = search.key
    status, actions, states, explored, detail = depth_first(
        start(problem), search.successors, search.done, search.limits.max_states, search.limits.timeout_s,
        lambda s: (key(s), s.steps))
    if status is Status.NO_PLAN_WITHIN_HORIZON:
        detail = beyond(problem)
    return SearchResult(status, actions, explored, detail, tuple(display(problem, s) for s in states))


def shortest(problem: Problem, limits: Limits | None = None, rules: Rules | None = None) -> SearchResult:
    """Breadth-first search with ordered expansion: the first shortest plan in the action order (under ``rules``
    when given).

    When the search ends without a plan, it is "no plan" (of any length) if every path of the graph it built (a
    state's moves depend on its key alone) is refused before the horizon, as the paper's bitset search says when
    a layer empties; "no plan within the horizon" otherwise."""
    trivial = _trivial(problem, rules)
    if trivial is not None:
        return trivial
    search = _Search(problem, limits, rules)
    key, first = search.key, start(problem)
    entries: list[Entry] = [(first, -1, None)]
    seen = {key(first)}
    queue = deque([0])
    moves: dict[Hashable, list[Hashable]] = {}  # key -> its successors' keys (the graph the search built)
    while queue:
        entry = queue.popleft()
        state = entries[entry][0]
        if state.steps >= problem.horizon:
            moves[key(state)] = [key(state)]  # cut by the horizon, not refused: stands for a path that goes on
        out = moves.setdefault(key(state), [])

        def cut(nxt: SoundState, out: list[Hashable] = out) -> None:  # stands for a path that reaches the horizon
            out.append(key(nxt))
            moves.setdefault(key(nxt), [key(nxt)])

        for action, nxt in search.successors(state, cut):
            out.append(key(nxt))
            if key(nxt) in seen:
                continue
            seen.add(key(nxt))
            entries.append((nxt, entry, action))
            if search.done(nxt):
                return search.plan(entries, len(entries) - 1)
            stop = search.stopped(len(entries), len(entries) % 256 == 0)
            if stop is not None:
                return stop
            queue.append(len(entries) - 1)
    longest = _longest(moves, key(first), problem.horizon)
    if longest < problem.horizon:
        return SearchResult(Status.NO_PLAN, (), len(entries),
                            f"no plan of any length: every path ends within {longest + 1} action(s), refused or "
                            "unable ever to reach the goal")
    if rules is not None:
        return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), len(entries), beyond(problem))
    _UNPROVED[problem] = None
    if len(_UNPROVED) > 16:
        _UNPROVED.popitem(last=False)
    return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), len(entries), beyond(problem))


def _longest(moves: dict[Hashable, list[Hashable]], root: Hashable, cap: int) -> int:
    """The most actions a path from ``root`` takes in the graph ``moves`` (``cap`` if it has a cycle or reaches it)."""
    depth: dict[Hashable, int] = {}
    on_path: set[Hashable] = {root}
    stack = [(root, iter(moves.get(root, ())))]
    while stack:
        node, todo = stack[-1]
        nxt = next(todo, None)
        if nxt is None:
            stack.pop()
            on_path.discard(node)
            depth[node] = max((depth[n] + 1 for n in moves.get(node, ())), default=0)
            if depth[node] >= cap:
                return cap
        elif nxt in on_path:
            return cap
        elif nxt not in depth:
            on_path.add(nxt)
            stack.append((nxt, iter(moves.get(nxt, ()))))
    return depth[root]


def optimal(problem: Problem, limits: Limits | None = None, rules: Rules | None = None) -> SearchResult:
    """The least-cost plan (``spec.cost``, lexicographic) of at most ``horizon`` actions: a uniform-cost search.

    Every cost term only grows along a plan, so the first goal state taken from the queue is least-cost (ties: the
    one pushed first). A state taken after one with the same key (``Rules.key``: everything the future depends on
    but the steps) was taken with no more steps is dominated: it costs no less (the queue's order) and has no more
    of the horizon left (under ``rules`` when given). ``tests/oracle/test_sound.py`` checks it against every plan of a
    walk."""
    trivial = _trivial(problem, rules)
    if trivial is not None:
        return trivial
    search = _Search(problem, limits, rules)
    key = search.key
    entries: list[Entry] = [(start(problem), -1, None)]
    queue: list[tuple[tuple[int, ...], int]] = [((0,) * len(COST_TERMS), 0)]  # cost, entry (ties: pushed first)
    fewest: dict[Hashable, int] = {}  # key -> the fewest steps it was taken with
    while queue:
        cost, entry = heapq.heappop(queue)
        state = entries[entry][0]
        if fewest.get(key(state), state.steps + 1) <= state.steps:
            continue
        fewest[key(state)] = state.steps
        if search.done(state):
            return search.plan(entries, entry, f"optimal under {COST_DOC}",
                               {"cost": dict(zip(COST_TERMS, cost, strict=True)), "cost_order": list(COST_TERMS)})
        for action, nxt in search.successors(state):
            if fewest.get(key(nxt), nxt.steps + 1) <= nxt.steps:
                continue
            entries.append((nxt, entry, action))
            added = action_cost(action, nxt.lane)
            heapq.heappush(queue, (tuple(a + b for a, b in zip(cost, added, strict=True)), len(entries) - 1))
        stop = search.stopped(len(entries))
        if stop is not None:
            return stop
    return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), len(entries), beyond(problem))


def solve(problem: Problem, strategy: Strategy, limits: Limits) -> SearchResult:
    """The interpreter's answer for a problem of the sound model."""
    return {Strategy.SHORTEST: shortest, Strategy.OPTIMAL: optimal}.get(strategy, sensible)(problem, limits)


@dataclass(frozen=True, slots=True)
class SoundValidation:
    """The verdict on an action list under the sound model, with the violation that breaks it, if any."""

    valid: bool
    reason: str
    states: tuple[State, ...]  # display states: the initial one, then one per executed step
    violation: Refusal | None = None


def validate(problem: Problem, actions: Sequence[Action]) -> SoundValidation:
    """Check that ``actions`` is a plan of the sound model: enabled, safe at every instant, within the horizon, the
    goal first at the end, and the end safe for ever."""
    rules, state = rules_for(problem), start(problem)
    shown = [display(problem, state)]
    hit = rules.start_violation(state)
    if hit is not None:
        return SoundValidation(False, f"initial state: {hit.describe()}", tuple(shown), hit)
    if len(actions) > problem.horizon:
        return SoundValidation(False, f"{len(actions)} actions exceed the horizon of {problem.horizon}", tuple(shown))
    for n, action in enumerate(actions, start=1):
        if done(problem, state):
            return SoundValidation(False, f"goal already reached before step {n}", tuple(shown))
        reason = disabled_reason(_paper(state), action, problem.rules)
        if reason is not None:
            return SoundValidation(False, f"step {n}: {reason}", tuple(shown))
        result = step(problem, state, action)
        if not isinstance(result, SoundState):
            return SoundValidation(False, f"step {n} ({action.value}): {result.describe()}", tuple(shown), result)
        state = result
        shown.append(display(problem, state))
    if not rules.goal_holds(state, problem.goal):
        return SoundValidation(False, f"goal not reached for every position after {len(actions)} action(s)",
                               tuple(shown))
    after = rules.continuation_violation(state)
    if after is not None:
        return SoundValidation(False, f"no safe continuation after the plan: {after.describe()}", tuple(shown), after)
    return SoundValidation(True, "plan reaches the goal, safe at every instant and for ever after", tuple(shown))


def reachable_sets(problem: Problem, actions: Sequence[Action]) -> list[str]:
    """The reachable sets along ``actions`` (as far as they are safe), one line per state: where every vehicle can
    be at that boundary, metres ahead of the AV's reference there (the AV itself within the tracking error of it);
    for reproducers, beside the cells the traces show."""
    rules = rules_for(problem)
    if not isinstance(rules, SoundRules):
        return []
    state, lines = start(problem), []
    for n in range(len(actions) + 1):
        t_s = state.t_units * rules.unit_s
        x_m = rules.reference(state, None).position_m(t_s)
        parts = []
        for v in rules.vehicles:
            lo, hi = ((rules.same_low(v, t_s), rules.same_high(v, t_s)) if v.lane is Lane.LEFT
                      else (rules.oncoming_low(v, t_s), rules.oncoming_high(v, t_s)))
            name = (f"{'L' if v.lane is Lane.LEFT else 'R'}{v.index}" if v.index is not None
                    else f"phantom-{'L' if v.lane is Lane.LEFT else 'R'}{'+' if lo > 0 else '-'}")
            parts.append(f"{name} {lo - x_m:+.1f}..{hi - x_m:+.1f}")
        lines.append(f"step {n}, t {t_s:.2f} s, AV at {x_m:.1f} m +-{rules.sound.tracking.position_m:g}: "
                     + ", ".join(parts))
        if n == len(actions):
            break
        after = step(problem, state, actions[n])
        if not isinstance(after, SoundState):
            lines.append(f"step {n + 1} ({actions[n].value}) refused: {after.describe()}")
            break
        state = after
    return lines
