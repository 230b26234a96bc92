"""Lying engines: for every way a conformance property exists to catch an engine out (``LieKind``), a stub that
lies that way, so that the tests can show each property failing on each of its lies.

A lie stands in for one run (an engine with a strategy); every other run answers honestly. The
tests have each property hear each of its lies from every run it reads (``Lie.told_to``). It is
told on a scenario chosen so that it *is* a lie, which ``is_a_lie`` checks independently of the
properties (a "longer plan" is valid and longer than the shortest, a "no plan one step beyond"
scenario's shortest plan is exactly one action longer than its horizon, and so on): a lie that
turned out true would make a test that cannot fail.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import cache

from ci.conformance.properties import LieKind, Property, Run, RunKey, Runs, answers_model
from oracle.bitplan import shortest
from oracle.interpreter import enabled_actions, problem_step, validate
from oracle.optimum import lexicographic_optimum, plan_cost
from oracle.reach import exact_check
from spec.actions import Action
from spec.answers import Answer, Status, Strategy
from spec.assumptions import profile
from spec.errors import EngineError
from spec.escapes import COMMIT
from spec.library import builtin
from spec.models import ModelChoice, ModelKind, models_for
from spec.scenario import Problem, Scenario, problem_for
from spec.sound import Sound
from spec.state import Collision, State

#: What a lying engine answers, given the scenario and the honest engine's answer: an answer or an engine error.
Tell = Callable[[Scenario, Answer], "Answer | EngineError"]


@dataclass(frozen=True, slots=True)
class Lie:
    """One lie: which run tells it, on which scenario, and how it is made from the honest answer."""

    kind: LieKind
    liar: RunKey
    scenario: Callable[[], Scenario]
    tell: Tell

    def told_to(self, prop: Property) -> list[Lie]:
        """The lie as told to ``prop`` by each run it reads, or by the run it is about when it has one (optimality
        judges z3's optimal plan: its lies must come from there). So a run added to a property is lied about too."""
        liars = (prop.subject,) if prop.subject is not None else prop.runs
        scenario = self.scenario()
        return [replace(self, liar=liar) for liar in liars if answers_model(liar.engine, scenario)]


class LyingRuns(Runs):
    """A scenario's runs in which ``lie.liar`` answers the lie; the others answer honestly (from ``honest``)."""

    def __init__(self, honest: Runs, lie: Lie) -> None:
        super().__init__(honest.scenario, honest.limits)
        self.honest, self.lie = honest, lie

    def get(self, key: RunKey) -> Run:
        run = self.honest.get(key)
        if key != self.lie.liar:
            return run
        if run.answer is None:
            raise ValueError(f"{key.label} raised on {self.scenario}: no honest answer to lie about ({run.error})")
        told = self.lie.tell(self.scenario, run.answer)
        if isinstance(told, EngineError):
            return Run(key, None, str(told), run.ms)
        return Run(key, told, None, run.ms)


# -- the scenarios ------------------------------------------------------------------------------------------------
def _library(name: str) -> Scenario:
    found = builtin(name)
    if found is None:
        raise ValueError(f"no built-in scenario {name!r}")
    return found.load()


def shortest_beyond(scenario: Scenario, limit: int = 60) -> int | None:
    """The fewest actions of a plan under any model of ``scenario``'s pipeline, searching up to ``limit`` actions."""
    found = (shortest(problem_for(scenario, kind, limit)) for kind in models_for(scenario.model))
    return min((len(r.actions) for r in found if r.status is Status.PLAN), default=None)


@cache
def one_beyond() -> Scenario:
    """One target, the final model alone, the horizon one action short of the shortest plan (5 actions)."""
    scenario = replace(_library("one_target"), model=ModelChoice.FINAL)
    return replace(scenario, horizon=(shortest_beyond(scenario) or 1) - 1)


@cache
def several_beyond() -> Scenario:
    """The paper's example, the final model alone, the horizon 4: the shortest plan (7) is 3 actions longer, within
    the twice-as-deep search."""
    return replace(_library("paper_example"), model=ModelChoice.FINAL, horizon=4)


# -- the tells ----------------------------------------------------------------------------------------------------
def _model_of(scenario: Scenario, answer: Answer) -> ModelKind:
    """The model an answer names, or the first its scenario's pipeline tries."""
    return answer.model or models_for(scenario.model)[0]


def _problem(scenario: Scenario, answer: Answer) -> Problem:
    return problem_for(scenario, _model_of(scenario, answer))


def colliding_actions(problem: Problem) -> tuple[Action, ...]:
    """The first action list (breadth first, in the action order) whose last action collides."""
    start = problem.scenario.initial_state()
    queue: deque[tuple[State, tuple[Action, ...]]] = deque([(start, ())])
    seen = {start}
    while queue:
        state, actions = queue.popleft()
        for action in enabled_actions(state, problem.rules):
            after = problem_step(problem, state, action)
            if isinstance(after, Collision):
                return (*actions, action)
            if after not in seen:
                seen.add(after)
                queue.append((after, (*actions, action)))
    raise ValueError(f"no action list collides in {problem.scenario}")


def _plan(answer: Answer, scenario: Scenario, actions: tuple[Action, ...]) -> Answer:
    """``answer`` with another action list, and the interpreter's states along it (a liar that keeps its story)."""
    states = validate(_problem(scenario, answer), actions).states
    return replace(answer, status=Status.PLAN, actions=actions, states=states)


def _no_plan(status: Status, detail: str, stage: Status | None = None) -> Tell:
    """Answer ``status`` with no plan; its one stage says ``stage`` (default: the same status)."""
    def tell(scenario: Scenario, answer: Answer) -> Answer:
        return replace(answer, status=status, actions=(), states=(), detail=detail,
                       stages=((_model_of(scenario, answer), stage or status, detail),))
    return tell


def _false_plan(scenario: Scenario, answer: Answer) -> Answer:
    """A plan beyond the horizon, passed off as one within it."""
    kind = _model_of(scenario, answer)
    found = lexicographic_optimum(problem_for(scenario, kind, 60))
    return replace(answer, status=Status.PLAN, model=kind, actions=found.actions,
                   states=validate(problem_for(scenario, kind, 60), found.actions).states)


def _waiting_first(scenario: Scenario, answer: Answer) -> Answer:
    """The honest plan, with one ``drive`` before it: valid here, longer and dearer, and not the first one found."""
    return _plan(answer, scenario, (Action.DRIVE, *answer.actions))


@cache
def committed_example() -> Scenario:
    """The paper's example under the paper profile's bounds and the commitment semantics: three actions committed to
    (accelerate, move out, accelerate) with the abort after them, four predicted."""
    return replace(_library("paper_example"), sound=Sound(profile("paper"), commitment=COMMIT))


def _past_escape(scenario: Scenario, answer: Answer) -> Answer:
    """The honest commitment with the first predicted action committed to as well, the same escape kept."""
    parts = answer.commit
    if parts is None or not parts.predicted or parts.escape is None:
        raise ValueError(f"no commitment with an escape and a prediction to lie about on {scenario}")
    committed = (*parts.committed, parts.predicted[0])
    return replace(answer, actions=committed, commit=replace(parts, committed=committed,
                                                             predicted=parts.predicted[1:]))


def _states(change: Callable[[tuple[State, ...]], tuple[State, ...]]) -> Tell:
    return lambda scenario, answer: replace(answer, states=change(answer.states))


LIES: dict[LieKind, Lie] = {lie.kind: lie for lie in (
    Lie(LieKind.UNSAFE_PLAN, RunKey("spin", Strategy.SENSIBLE), lambda: _library("one_target"),
        lambda s, a: _plan(a, s, colliding_actions(_problem(s, a)))),
    Lie(LieKind.WRONG_PLAN, RunKey("z3", Strategy.SHORTEST), lambda: _library("one_target"),
        lambda s, a: _plan(a, s, a.actions[:-1])),
    Lie(LieKind.FALSE_NO_PLAN, RunKey("z3", Strategy.SHORTEST), lambda: _library("one_target"),
        _no_plan(Status.NO_PLAN_WITHIN_HORIZON, "no plan within the horizon")),
    Lie(LieKind.FALSE_PLAN, RunKey("spin", Strategy.SENSIBLE), lambda: _library("no_plan_within_horizon"),
        _false_plan),
    Lie(LieKind.INCOMPLETE_AS_ANSWER, RunKey("spin", Strategy.SHORTEST), lambda: _library("one_target"),
        _no_plan(Status.NO_PLAN_WITHIN_HORIZON, "time limit reached", Status.INCOMPLETE)),
    Lie(LieKind.ENGINE_ERROR, RunKey("spin", Strategy.SHORTEST), lambda: _library("one_target"),
        lambda s, a: EngineError("pan failed (exit 1): a line the runner does not know")),
    Lie(LieKind.MISSING_STATE, RunKey("spin", Strategy.SENSIBLE), lambda: _library("one_target"),
        _states(lambda states: states[:-1])),
    Lie(LieKind.EXTRA_STATE, RunKey("z3", Strategy.SHORTEST), lambda: _library("one_target"),
        _states(lambda states: (*states, states[-1]))),
    Lie(LieKind.SHIFTED_STATE, RunKey("spin", Strategy.SHORTEST), lambda: _library("one_target"),
        _states(lambda states: states[:1] + states[:-1])),
    Lie(LieKind.NO_STATES, RunKey("z3", Strategy.SHORTEST), lambda: _library("one_target"),
        _states(lambda states: ())),
    Lie(LieKind.OTHER_SENSIBLE_PLAN, RunKey("spin", Strategy.SENSIBLE), lambda: _library("one_target"),
        _waiting_first),
    Lie(LieKind.LONGER_PLAN, RunKey("spin", Strategy.SHORTEST), lambda: _library("one_target"), _waiting_first),
    Lie(LieKind.DEARER_PLAN, RunKey("z3", Strategy.OPTIMAL), lambda: _library("one_target"), _waiting_first),
    Lie(LieKind.NO_PLAN_ONE_BEYOND, RunKey("z3", Strategy.SHORTEST), one_beyond,
        _no_plan(Status.NO_PLAN, "no plan of any length")),
    Lie(LieKind.NO_PLAN_BEYOND, RunKey("spin", Strategy.SENSIBLE), several_beyond,
        _no_plan(Status.NO_PLAN, "no plan of any length")),
    Lie(LieKind.COMMIT_PAST_ESCAPE, RunKey("spin", Strategy.SENSIBLE), committed_example, _past_escape),
)}


def is_a_lie(lie: Lie, scenario: Scenario, honest: Answer, told: Answer | EngineError) -> str | None:
    """Why ``told`` is false on ``scenario``, judged without the properties (None: it is no lie, the stub is wrong)."""
    if isinstance(told, EngineError):
        return "an engine error is not an answer" if lie.kind is LieKind.ENGINE_ERROR else None
    if lie.kind is LieKind.COMMIT_PAST_ESCAPE:
        parts = told.commit
        if parts is None or parts.escape is None:
            return None
        breach = exact_check(scenario, (*parts.committed, *parts.escape.actions))
        return None if breach is None else f"{lie.kind.value}: {breach.describe()}"
    problem = problem_for(scenario, _model_of(scenario, told))
    verdict = validate(problem, told.actions) if told.status is Status.PLAN else None
    honest_plan = honest.status is Status.PLAN
    checks: dict[LieKind, Callable[[], bool]] = {
        LieKind.UNSAFE_PLAN: lambda: verdict is not None and "collision" in verdict.reason,
        LieKind.WRONG_PLAN: lambda: verdict is not None and "goal not reached" in verdict.reason,
        LieKind.FALSE_NO_PLAN: lambda: honest_plan and told.status is Status.NO_PLAN_WITHIN_HORIZON,
        LieKind.FALSE_PLAN: lambda: not honest_plan and verdict is not None and not verdict.valid,
        LieKind.INCOMPLETE_AS_ANSWER: lambda: honest_plan and told.status is not Status.INCOMPLETE
        and any(status is Status.INCOMPLETE for _, status, _ in told.stages),
        LieKind.MISSING_STATE: lambda: len(told.states) == len(honest.states) - 1,
        LieKind.EXTRA_STATE: lambda: len(told.states) == len(honest.states) + 1,
        LieKind.SHIFTED_STATE: lambda: len(told.states) == len(honest.states) and told.states != honest.states,
        LieKind.NO_STATES: lambda: honest_plan and not told.states,
        LieKind.OTHER_SENSIBLE_PLAN: lambda: verdict is not None and verdict.valid and told.actions != honest.actions,
        LieKind.LONGER_PLAN: lambda: verdict is not None and verdict.valid and len(told.actions) > len(honest.actions),
        LieKind.DEARER_PLAN: lambda: verdict is not None and verdict.valid
        and plan_cost(problem, told.actions) > (lexicographic_optimum(problem).cost or ()),
        LieKind.NO_PLAN_ONE_BEYOND: lambda: told.status is Status.NO_PLAN
        and shortest_beyond(scenario) == scenario.horizon + 1,
        LieKind.NO_PLAN_BEYOND: lambda: told.status is Status.NO_PLAN
        and (shortest_beyond(scenario) or 0) > scenario.horizon + 1,
    }
    check = checks.get(lie.kind)
    return f"{lie.kind.value}: {lie.liar.label} on {scenario}" if check is not None and check() else None

