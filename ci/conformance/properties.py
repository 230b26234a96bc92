"""Conformance properties, named and registered once: what "the engines agree with each other and with the
interpreter" means, property by property, for the command line, the reports and the tests.

Each property reads some of one scenario's *runs* (an engine with a strategy, through the
planner pipeline, unchecked: ``oracle.planner.solve``) and gives a verdict: held, failed (with
the reason), or incomplete (a run hit a limit: nothing to compare). A run that raises an engine
error is recorded as a failed ``validity``, never a reason to stop. A property applies when
enough of its runs belong to the engines selected.

Each property is registered with the *lies* it exists to catch (``LieKind``); ``ci.conformance.lies`` holds
a stub engine for every kind, and the tests show each property failing on each of its lies and
holding on the honest engines. A property without lies cannot be registered.
"""

from __future__ import annotations

import enum
import functools
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from oracle import commit, reach
from oracle.bmc import Expected, expecting
from oracle.commit import CommitValidation
from oracle.optimum import Optimum
from oracle.planner import combined_status, cost_of, least_cost, solve
from oracle.planner import verdict_for as validate
from spec.actions import Action, plan_text
from spec.answers import Answer, Commit, Limits, Status, Strategy
from spec.commitment import paper_problem
from spec.engines import answers, get_engine
from spec.errors import EngineError
from spec.models import models_for
from spec.scenario import Problem, Scenario, problem_for
from spec.state import State

#: How much deeper than the scenario's horizon the "no plan" check searches.
DEEPER = 2


class PropertyName(enum.Enum):
    """The registered properties."""

    EXISTENCE = "existence"
    VALIDITY = "validity"
    SENSIBLE_IDENTITY = "sensible_identity"
    SHORTEST_LENGTH = "shortest_length"
    TRACE_EQUALITY = "trace_equality"
    OPTIMALITY = "optimality"
    NO_PLAN_PROOF = "no_plan_proof"
    MOTION_SAFETY = "motion_safety"


class LieKind(enum.Enum):
    """The ways an engine can lie that some property exists to catch (``ci.conformance.lies``: a stub engine each)."""

    UNSAFE_PLAN = "unsafe_plan"  # an action list that collides
    WRONG_PLAN = "wrong_plan"  # an action list that does not reach the goal
    FALSE_NO_PLAN = "false_no_plan"  # "no plan within the horizon" where there is one
    FALSE_PLAN = "false_plan"  # a plan where none exists within the horizon
    INCOMPLETE_AS_ANSWER = "incomplete_as_answer"  # a search that hit its limit, answered as "no plan"
    ENGINE_ERROR = "engine_error"  # a crash or unreadable output, not an answer
    MISSING_STATE = "missing_state"  # the plan's trace lacks its last state
    EXTRA_STATE = "extra_state"  # the plan's trace has a state after its last
    SHIFTED_STATE = "shifted_state"  # the trace is one step late
    NO_STATES = "no_states"  # a plan with no trace
    OTHER_SENSIBLE_PLAN = "other_sensible_plan"  # a valid plan, but not the depth-first search's first
    LONGER_PLAN = "longer_plan"  # a valid plan, longer than the shortest
    DEARER_PLAN = "dearer_plan"  # a valid plan, dearer than the least cost
    NO_PLAN_ONE_BEYOND = "no_plan_one_beyond"  # "no plan of any length"; the shortest is one step past the horizon
    NO_PLAN_BEYOND = "no_plan_beyond"  # "no plan of any length"; the shortest is several steps past the horizon
    COMMIT_PAST_ESCAPE = "commit_past_escape"  # a committed part one action longer than its escape was proved after


class Verdict(enum.Enum):
    """A property's verdict on one scenario."""

    HELD = "held"
    FAILED = "failed"
    INCOMPLETE = "incomplete"  # a run hit a limit (time, states): nothing could be compared


@dataclass(frozen=True, slots=True)
class RunKey:
    """One engine with one strategy."""

    engine: str
    strategy: Strategy

    @property
    def label(self) -> str:
        return f"{self.engine}/{self.strategy.value}"


RUNS: tuple[RunKey, ...] = (
    RunKey("interpreter", Strategy.SENSIBLE), RunKey("spin", Strategy.SENSIBLE),
    RunKey("interpreter", Strategy.SHORTEST), RunKey("spin", Strategy.SHORTEST), RunKey("z3", Strategy.SHORTEST),
    RunKey("z3", Strategy.OPTIMAL),
)
#: What every property but optimality reads (the optimal run costs seconds: only optimality asks for it).
PLAIN_RUNS = tuple(k for k in RUNS if k.strategy is not Strategy.OPTIMAL)
SENSIBLE_RUNS = tuple(k for k in RUNS if k.strategy is Strategy.SENSIBLE)
SHORTEST_RUNS = tuple(k for k in RUNS if k.strategy is Strategy.SHORTEST)
OPTIMAL_RUN = RunKey("z3", Strategy.OPTIMAL)


@dataclass(frozen=True, slots=True)
class Run:
    """What one engine answered (or the engine error it raised), and how long it took."""

    key: RunKey
    answer: Answer | None
    error: str | None
    ms: float

    @property
    def status(self) -> Status | None:
        return None if self.answer is None else self.answer.status


class Runs:
    """One scenario's runs, each made on first use and kept."""

    def __init__(self, scenario: Scenario, limits: Limits | None = None) -> None:
        self.scenario, self.limits = scenario, limits
        self._made: dict[str, Run] = {}

    def get(self, key: RunKey) -> Run:
        if key.label not in self._made:
            expected = self._expected(key)
            started = time.perf_counter()
            try:
                with expecting(expected):
                    answer, error = solve(self.scenario, key.strategy, engine=key.engine, limits=self.limits), None
            except EngineError as err:
                answer, error = None, str(err)
            self._made[key.label] = Run(key, answer, error, (time.perf_counter() - started) * 1000)
        return self._made[key.label]

    def _expected(self, key: RunKey) -> dict[Problem, Expected]:
        """What Z3 may guess first (``oracle.bmc.expecting``): the length of a shortest plan already made, and for
        ``optimal`` the least cost the optimality property's own search finds. A guess orders Z3's checks; its answer
        is proved as without one, so a wrong reference cannot pass through (the tests hold a lying one to that)."""
        if key.engine != "z3" or _committed(self.scenario):
            return {}
        made = [r.answer for r in self._made.values() if r.key.strategy is Strategy.SHORTEST and r.answer is not None
                and r.answer.status is Status.PLAN]
        if not made:
            return {}
        problem = _problem(self.scenario, made[0])
        cost = optimum(problem).cost if key.strategy is Strategy.OPTIMAL else None
        return {problem: Expected(len(made[0].actions), None if cost is None else tuple(cost))}

    def made(self) -> list[Run]:
        return list(self._made.values())


@dataclass(frozen=True, slots=True)
class Outcome:
    verdict: Verdict
    detail: str = ""


HELD = Outcome(Verdict.HELD)
Check = Callable[[Scenario, Sequence[Run]], Outcome]


@dataclass(frozen=True, slots=True)
class Property:
    """A named property: what it checks, the runs it reads, how many of them it needs."""

    name: PropertyName
    doc: str
    runs: tuple[RunKey, ...]
    min_runs: int
    check: Check
    lies: tuple[LieKind, ...]  # what it exists to catch: it must fail on each (``ci.conformance.lies``)
    subject: RunKey | None = None  # a run the property is about: it applies only when that engine is selected

    def applies(self, engines: Sequence[str]) -> bool:
        subject_ok = self.subject is None or self.subject.engine in engines
        return subject_ok and len(self.selected(engines)) >= self.min_runs

    def selected(self, engines: Sequence[str]) -> tuple[RunKey, ...]:
        return tuple(k for k in self.runs if k.engine in engines)

    def verdict(self, scenario: Scenario, runs: Runs, engines: Sequence[str]) -> Outcome:
        """The check on the runs of the engines selected that answer ``scenario``'s model (``spec.engines.answers``:
        Z3 answers no commitment)."""
        return self.check(scenario, [runs.get(k) for k in self.selected(engines) if answers_model(k.engine, scenario)])


PROPERTIES: dict[PropertyName, Property] = {}


def register(prop: Property) -> Property:
    """Add ``prop`` to the registry: once, and never without the lies it exists to catch."""
    if not prop.lies:
        raise ValueError(f"property {prop.name.value!r} registered without its lies (ci.conformance.lies): a "
                         f"property that no lie is shown to fail cannot be trusted to catch one")
    if prop.name in PROPERTIES:
        raise ValueError(f"property {prop.name.value!r} registered twice")
    PROPERTIES[prop.name] = prop
    return prop


def _incomplete(runs: Sequence[Run]) -> Outcome | None:
    hit = [r.key.label for r in runs if r.status is Status.INCOMPLETE]
    return Outcome(Verdict.INCOMPLETE, "a limit was hit: " + ", ".join(hit)) if hit else None


@functools.lru_cache(maxsize=16)
def optimum(problem: Problem) -> Optimum:
    """The interpreter's least cost on ``problem`` (``least_cost``), found once for the optimality property and for
    Z3's guess before it."""
    return least_cost(problem)


def _problem(scenario: Scenario, answer: Answer) -> Problem:
    assert answer.model is not None  # a plan always names its model
    return problem_for(scenario, answer.model)


def _plans(runs: Sequence[Run]) -> list[Run]:
    return [r for r in runs if r.answer is not None and r.answer.status is Status.PLAN]


def _whole(answer: Answer) -> tuple[Action, ...]:
    """The action list an answer stands for: its plan; under the commitment semantics its committed part then its
    predicted continuation (one plan of the paper's rules, ``spec.escapes``)."""
    return answer.actions if answer.commit is None else (*answer.commit.committed, *answer.commit.predicted)


def _actions(run: Run) -> str:
    assert run.answer is not None
    return plan_text(_whole(run.answer))


def _committed(scenario: Scenario) -> bool:
    return scenario.sound is not None and scenario.sound.commitment is not None


# -- the checks ---------------------------------------------------------------------------------------
def existence(scenario: Scenario, runs: Sequence[Run]) -> Outcome:
    answered = [r for r in runs if r.answer is not None and r.status is not Status.INCOMPLETE]
    says = {r.key.label: r.status is Status.PLAN for r in answered}
    if len(set(says.values())) > 1:
        return Outcome(Verdict.FAILED, "; ".join(f"{r.key.label} {r.status.value}" for r in answered
                                                 if r.status is not None))
    return _incomplete(runs) or HELD


def _contradicts_stages(answer: Answer) -> str | None:
    """How an answer's status contradicts the pipeline's own stages (a limit hit, answered as "no plan"), or None."""
    if not answer.stages:
        return None
    expected = Status.PLAN if answer.stages[-1][1] is Status.PLAN else combined_status(list(answer.stages))
    if answer.status is expected:
        return None
    return f"answers {answer.status.value}, but its stages say {expected.value} ({answer.detail or '-'})"


def validity(scenario: Scenario, runs: Sequence[Run]) -> Outcome:
    problems = [f"{r.key.label} raised an engine error: {r.error}" for r in runs if r.error is not None]
    for r in runs:
        contradiction = None if r.answer is None else _contradicts_stages(r.answer)
        if contradiction is not None:
            problems.append(f"{r.key.label} {contradiction}")
    for r in _plans(runs):
        assert r.answer is not None
        if _committed(scenario) and r.answer.commit is None:
            problems.append(f"{r.key.label} plan {_actions(r)} has no committed part and escape")
            continue
        verdict = validate(_problem(scenario, r.answer), _whole(r.answer))
        if not verdict.valid:
            problems.append(f"{r.key.label} plan {_actions(r)} is invalid: {verdict.reason}")
        elif isinstance(verdict, CommitValidation) and r.answer.commit is not None and (
                verdict.commit != r.answer.commit or r.answer.actions != r.answer.commit.committed):
            problems.append(f"{r.key.label} commits to {_parts(r.answer.commit)}; the interpreter splits its plan "
                            f"into {_parts(verdict.commit)}")
    return Outcome(Verdict.FAILED, "; ".join(problems)) if problems else _incomplete(runs) or HELD


def _parts(parts: Commit | None) -> str:
    if parts is None:
        return "(none)"
    escape = "none: a whole plan" if parts.escape is None else parts.escape.describe()
    return f"[{plan_text(parts.committed)}] with escape {escape}"


def sensible_identity(scenario: Scenario, runs: Sequence[Run]) -> Outcome:
    plans = _plans(runs)
    if len(plans) == len(runs) and len({(r.answer.model, _whole(r.answer), r.answer.commit) for r in plans
                                        if r.answer}) > 1:
        return Outcome(Verdict.FAILED, "sensible plans differ: " + "; ".join(
            f"{r.key.label} {r.answer.model.value if r.answer and r.answer.model else '-'} {_actions(r)}"
            + (f", committed {_parts(r.answer.commit)}" if r.answer and r.answer.commit else "") for r in plans))
    return _incomplete(runs) or HELD


def shortest_length(scenario: Scenario, runs: Sequence[Run]) -> Outcome:
    plans = [r for r in _plans(runs) if r.answer is not None]
    if len({(r.answer.model, len(_whole(r.answer))) for r in plans if r.answer}) > 1:
        return Outcome(Verdict.FAILED, "shortest plans differ: " + "; ".join(
            f"{r.key.label} {r.answer.model.value if r.answer.model else '-'} {len(_whole(r.answer))} action(s)"
            for r in plans if r.answer))
    return _incomplete(runs) or HELD


def first_difference(ours: Sequence[State], theirs: Sequence[State]) -> int | None:
    """The first step at which two traces differ (a missing state counts), or None."""
    for n, (a, b) in enumerate(zip(ours, theirs)):
        if a != b:
            return n
    return None if len(ours) == len(theirs) else min(len(ours), len(theirs))


def trace_equality(scenario: Scenario, runs: Sequence[Run]) -> Outcome:
    problems = []
    for r in _plans(runs):
        assert r.answer is not None
        reference = validate(_problem(scenario, r.answer), _whole(r.answer)).states
        if not r.answer.states:
            problems.append(f"{r.key.label} reports no states for its plan")
            continue
        n = first_difference(reference, r.answer.states)
        if n is not None:
            theirs = r.answer.states[n] if n < len(r.answer.states) else "(none)"
            ours = reference[n] if n < len(reference) else "(none)"
            problems.append(f"{r.key.label} state {n} is {theirs}, the interpreter's {ours}")
    return Outcome(Verdict.FAILED, "; ".join(problems)) if problems else _incomplete(runs) or HELD


def optimality(scenario: Scenario, runs: Sequence[Run]) -> Outcome:
    optimal = next((r for r in runs if r.key == OPTIMAL_RUN), None)
    if optimal is not None and optimal.error is not None:
        return Outcome(Verdict.FAILED, f"z3/optimal raised an engine error: {optimal.error}")
    if optimal is None or optimal.answer is None or optimal.status is not Status.PLAN:
        return _incomplete(runs) or HELD
    if _committed(scenario):
        return _optimal_prediction(scenario, runs, optimal)
    problem = _problem(scenario, optimal.answer)
    checked = validate(problem, optimal.answer.actions)
    if not checked.valid:
        return Outcome(Verdict.FAILED, f"z3/optimal plan {_actions(optimal)} is invalid: {checked.reason}")
    cost = cost_of(problem, optimal.answer.actions)
    best = optimum(problem)
    problems = []
    if best.cost != cost:
        problems.append(f"z3/optimal costs {cost}, the least cost is {best.cost} "
                        f"({plan_text(best.actions)})")
    for other in _plans(runs):
        if other is optimal or other.answer is None or other.answer.model is not optimal.answer.model:
            continue
        if not validate(problem, other.answer.actions).valid:
            continue  # validity reports it
        other_cost = cost_of(problem, other.answer.actions)
        if other_cost < cost:
            problems.append(f"{other.key.label}'s plan costs {other_cost}, less than z3/optimal's {cost}")
    return Outcome(Verdict.FAILED, "; ".join(problems)) if problems else HELD


def answers_model(engine: str, scenario: Scenario) -> bool:
    """Whether ``engine`` answers ``scenario``'s model (its semantics, its measured speeds)."""
    return answers(get_engine(engine), scenario)


def motion_safety(scenario: Scenario, runs: Sequence[Run]) -> Outcome:
    """Under the sound model, every plan's actions (under the commitment semantics its committed part then its
    escape) against the exact continuous-motion check (``oracle.reach.exact_check``): every motion inside the
    bounds, phantoms and corners included."""
    if scenario.sound is None:
        return _incomplete(runs) or HELD
    problems, checked = [], {}
    for r in _plans(runs):
        assert r.answer is not None
        parts = r.answer.commit
        escape = () if parts is None or parts.escape is None else parts.escape.actions
        path = r.answer.actions if parts is None else (*parts.committed, *escape)
        if path not in checked:  # the engines mostly agree: each path checked once
            checked[path] = reach.exact_check(scenario, path)
        breach = checked[path]
        if breach is not None:
            what = "plan" if parts is None else "committed part and escape"
            problems.append(f"{r.key.label} {what} [{plan_text(path)}] breaks: {breach.describe()}")
    return Outcome(Verdict.FAILED, "; ".join(problems)) if problems else _incomplete(runs) or HELD


def _optimal_prediction(scenario: Scenario, runs: Sequence[Run], optimal: Run) -> Outcome:
    """Under the commitment semantics the optimal strategy's plan is the prediction (``spec.commitment``): its
    committed and predicted actions cost, under the paper's rules, what the interpreter's optimal commitment costs,
    and no other engine's costs less (whether each is a commitment at all is ``validity``'s)."""
    assert optimal.answer is not None
    problem = _problem(scenario, optimal.answer)
    paper = paper_problem(problem)
    try:
        cost = cost_of(paper, _whole(optimal.answer))
    except ValueError as err:
        return Outcome(Verdict.FAILED, f"z3/optimal plan {_actions(optimal)} is no plan of the paper's rules: {err}")
    best = commit.solve(problem, Strategy.OPTIMAL, Limits())
    problems = []
    if best.status is Status.PLAN and best.commit is not None:
        least = cost_of(paper, (*best.commit.committed, *best.commit.predicted))
        if least != cost:
            problems.append(f"z3/optimal's prediction costs {cost}, the interpreter's least is {least} "
                            f"({plan_text((*best.commit.committed, *best.commit.predicted))})")
    for other in _plans(runs):
        if other is optimal or other.answer is None or other.answer.model is not optimal.answer.model:
            continue
        try:
            other_cost = cost_of(paper, _whole(other.answer))
        except ValueError:
            continue  # validity reports it
        if other_cost < cost:
            problems.append(f"{other.key.label}'s prediction costs {other_cost}, less than z3/optimal's {cost}")
    return Outcome(Verdict.FAILED, "; ".join(problems)) if problems else HELD


def no_plan_proof(scenario: Scenario, runs: Sequence[Run]) -> Outcome:
    claims = [r for r in runs if r.status is Status.NO_PLAN]
    if not claims:
        return _incomplete(runs) or HELD
    deeper = scenario.horizon * DEEPER
    for kind in models_for(scenario.model):
        if _committed(scenario):
            answer = commit.solve(problem_for(scenario, kind, deeper), Strategy.SHORTEST, Limits())
            if answer.status is Status.PLAN and answer.commit is not None:
                return Outcome(Verdict.FAILED, f"{', '.join(r.key.label for r in claims)} claim no plan of any "
                                               f"length; the {kind.value} model commits to one {DEEPER} times deeper: "
                                               f"{plan_text((*answer.commit.committed, *answer.commit.predicted))}")
            continue
        found = least_cost(problem_for(scenario, kind, deeper))
        if found.cost is not None:
            return Outcome(Verdict.FAILED, f"{', '.join(r.key.label for r in claims)} claim no plan of any length; "
                                           f"the {kind.value} model has one of {len(found.actions)} action(s): "
                                           f"{plan_text(found.actions)}")
    return HELD


for _prop in (
    Property(PropertyName.EXISTENCE, "every engine finds a plan within the horizon, or none does", PLAIN_RUNS, 2,
             existence, (LieKind.FALSE_NO_PLAN, LieKind.FALSE_PLAN, LieKind.INCOMPLETE_AS_ANSWER)),
    Property(PropertyName.VALIDITY, "every plan of every engine replays through the interpreter, collision-free, "
             "reaching the goal exactly at its last step; no engine raises an error or answers against its own "
             "stages", PLAIN_RUNS, 1, validity,
             (LieKind.UNSAFE_PLAN, LieKind.WRONG_PLAN, LieKind.FALSE_PLAN, LieKind.ENGINE_ERROR,
              LieKind.INCOMPLETE_AS_ANSWER, LieKind.COMMIT_PAST_ESCAPE)),
    Property(PropertyName.SENSIBLE_IDENTITY, "interpreter and Spin give identical sensible plans", SENSIBLE_RUNS, 2,
             sensible_identity, (LieKind.OTHER_SENSIBLE_PLAN,)),
    Property(PropertyName.SHORTEST_LENGTH, "every engine's shortest plan has the same length, under the same model",
             SHORTEST_RUNS, 2, shortest_length, (LieKind.LONGER_PLAN,)),
    Property(PropertyName.TRACE_EQUALITY, "the states each engine reports for its plan are the interpreter's, "
             "step by step", PLAIN_RUNS, 1, trace_equality,
             (LieKind.MISSING_STATE, LieKind.EXTRA_STATE, LieKind.SHIFTED_STATE, LieKind.NO_STATES)),
    Property(PropertyName.OPTIMALITY, "the Z3 optimal plan costs the least-cost plan an independent search finds, "
             "and no other engine's plan costs less; its plan is valid", (OPTIMAL_RUN, *PLAIN_RUNS), 1, optimality,
             (LieKind.DEARER_PLAN, LieKind.UNSAFE_PLAN), OPTIMAL_RUN),
    Property(PropertyName.NO_PLAN_PROOF, f"where an engine claims no plan of any length, a search {DEEPER} times "
             "deeper than the horizon finds none", PLAIN_RUNS, 1, no_plan_proof,
             (LieKind.NO_PLAN_ONE_BEYOND, LieKind.NO_PLAN_BEYOND)),
    Property(PropertyName.MOTION_SAFETY, "under the sound model every plan of every engine (under the commitment "
             "semantics its committed part, then its escape) survives the exact continuous-motion check",
             PLAIN_RUNS, 1, motion_safety, (LieKind.COMMIT_PAST_ESCAPE,)),
):
    register(_prop)
