"""The planner pipeline: the final model, then the preparations model, then "no plan"."""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, replace

from oracle import commit, sound
from oracle.interpreter import Validation, validate
from oracle.optimum import Cost, Optimum, lexicographic_optimum, plan_cost
from spec.actions import Action, plan_text
from spec.answers import Answer, Limits, SearchResult, Status, Strategy
from spec.cost import total_cost
from spec.engines import Engine, check_model, check_strategy, get_engine, parse_strategy
from spec.errors import EngineError
from spec.models import ModelChoice, ModelKind, models_for
from spec.scenario import Problem, Scenario, problem_for
from spec.state import State


def plan(
    scenario: Scenario,
    strategy: Strategy | str = Strategy.SENSIBLE,
    model: ModelChoice | None = None,
    horizon: int | None = None,
    engine: str | Engine = "interpreter",
    limits: Limits | None = None,
) -> Answer:
    """Plan for ``scenario`` with one engine; every plan returned has been validated (an invalid one, or one whose
    states differ from the interpreter's, is an ``EngineError``)."""
    eng = engine if isinstance(engine, Engine) else get_engine(engine)
    answer = solve(scenario, strategy, model, horizon, eng, limits)
    if answer.status in (Status.NO_PLAN, Status.NO_PLAN_WITHIN_HORIZON) and eng.name != REFERENCE:
        _check_no_plan(answer, scenario, model, horizon)
    if answer.status is not Status.PLAN or answer.model is None:
        return answer
    return replace(answer, states=_checked_states(eng, problem_for(scenario, answer.model, horizon), answer))


def _committed(problem: Problem) -> bool:
    sound_model = problem.scenario.sound
    return sound_model is not None and sound_model.commitment is not None


def solve(
    scenario: Scenario,
    strategy: Strategy | str = Strategy.SENSIBLE,
    model: ModelChoice | None = None,
    horizon: int | None = None,
    engine: str | Engine = "interpreter",
    limits: Limits | None = None,
) -> Answer:
    """The pipeline's answer as the engine gives it, unchecked: a plan's states are the engine's own (empty when it
    reports none). Conformance checks use it to judge each plan themselves; everything else uses ``plan``."""
    eng = engine if isinstance(engine, Engine) else get_engine(engine)
    strategy = parse_strategy(strategy)
    check_strategy(eng, strategy)
    check_model(eng, scenario)
    choice = model or scenario.model
    started = time.perf_counter()
    stages: list[tuple[ModelKind, Status, str]] = []
    explored = 0
    result = SearchResult(Status.NO_PLAN)
    kind = models_for(choice)[0]
    for kind in models_for(choice):
        problem = problem_for(scenario, kind, horizon)
        result = eng.solve(problem, strategy, (limits or Limits()).remaining(started, time.perf_counter()))
        explored += result.states_explored
        stages.append((kind, result.status, result.detail))
        if result.status in (Status.PLAN, Status.INCOMPLETE, Status.UNSAFE_START):
            break  # an unsafe start is unsafe under every model
    elapsed_ms = (time.perf_counter() - started) * 1000
    if result.status in (Status.PLAN, Status.UNSAFE_START):
        return Answer(result.status, kind, eng.name, strategy, result.actions, result.states, explored, elapsed_ms,
                      result.detail, tuple(stages), result.extra, result.commit)
    if result.status is not Status.INCOMPLETE:
        _prove_beyond(eng, scenario, horizon, stages)
    status = combined_status(stages)
    return Answer(status, kind, eng.name, strategy, (), (), explored, elapsed_ms, _summary(stages), tuple(stages),
                  result.extra)


REFERENCE = "interpreter"


def _check_no_plan(answer: Answer, scenario: Scenario, model: ModelChoice | None, horizon: int | None) -> None:
    """Another engine's "no plan" against the interpreter's (its bitset search: milliseconds at the default
    horizon): a plan it finds makes the "no plan" an engine error, never an answer (a verifier from the wrong cache
    slot, or an encoding that lost a move, would otherwise pass as "no plan")."""
    reference = solve(scenario, Strategy.SHORTEST, model, horizon, REFERENCE)
    if reference.status is Status.PLAN:
        kind = reference.model.value if reference.model else "-"
        raise EngineError(f"engine {answer.engine} says {answer.status.value}, but the interpreter finds a plan "
                          f"({kind} model): {plan_text(reference.actions)}")


def _checked_states(engine: Engine, problem: Problem, result: SearchResult | Answer) -> tuple[State, ...]:
    """The states of a plan, after checking it with the interpreter: an invalid plan is an engine error (under the
    commitment semantics: the committed and predicted actions as one answer, split as the engine split them)."""
    if _committed(problem):
        if result.commit is None:
            raise EngineError(f"engine {engine.name} returned a plan without its committed part and escape")
        checked = commit.validate(problem, (*result.commit.committed, *result.commit.predicted))
        if not checked.valid:
            raise EngineError(f"engine {engine.name} returned an invalid answer: {checked.reason}")
        if checked.commit != result.commit or result.actions != result.commit.committed:
            raise EngineError(f"engine {engine.name}: its committed part or escape differs from the interpreter's "
                              f"({checked.reason})")
        return checked.states
    verdict = verdict_for(problem, result.actions)
    if not verdict.valid:
        raise EngineError(f"engine {engine.name} returned an invalid plan: {verdict.reason}")
    if result.states and result.states != verdict.states:
        n = next((i for i, (a, b) in enumerate(zip(result.states, verdict.states)) if a != b), len(result.states))
        raise EngineError(f"engine {engine.name}: its state after step {n} differs from the interpreter's")
    return verdict.states


def _prove_beyond(engine: Engine, scenario: Scenario, horizon: int | None,
                  stages: list[tuple[ModelKind, Status, str]]) -> None:
    """Upgrade stages to "no plan of any length" where the engine can prove it, last stage first.

    The pipeline's answer is "no plan" only if every stage proves it, so the first stage
    that cannot be proved ends the work; the stages before it keep their (true) bounded answer.
    """
    if engine.prove_beyond is None:
        return
    for i in reversed(range(len(stages))):
        kind, status, _ = stages[i]
        if status is Status.NO_PLAN_WITHIN_HORIZON:
            proved = engine.prove_beyond(problem_for(scenario, kind, horizon))
            stages[i] = (kind, proved.status, proved.detail)
            if proved.status is not Status.NO_PLAN:
                return


def combined_status(stages: list[tuple[ModelKind, Status, str]]) -> Status:
    """No plan at all only when every model proved it; an incomplete stage makes the answer incomplete; an unsafe
    start is one under every model."""
    statuses = {status for _, status, _ in stages}
    if Status.UNSAFE_START in statuses:
        return Status.UNSAFE_START
    if Status.INCOMPLETE in statuses:
        return Status.INCOMPLETE
    if statuses == {Status.NO_PLAN}:
        return Status.NO_PLAN
    return Status.NO_PLAN_WITHIN_HORIZON


def _summary(stages: list[tuple[ModelKind, Status, str]]) -> str:
    parts = (f"{kind.value}: {status.value}" + (f" ({detail})" if detail else "") for kind, status, detail in stages)
    return "; ".join(parts)


def least_cost(problem: Problem) -> Optimum:
    """The least cost of a plan within the horizon and one such plan, by the interpreter's own uniform-cost search:
    over the paper's offsets, or over the sound model's states when the scenario has one."""
    if problem.scenario.sound is None:
        return lexicographic_optimum(problem)
    found = sound.optimal(problem)
    if found.status is not Status.PLAN:
        return Optimum(None, (), found.states_explored)
    return Optimum(cost_of(problem, found.actions), found.actions, found.states_explored)


def cost_of(problem: Problem, actions: Sequence[Action]) -> Cost:
    """The cost of a valid action list (``spec.cost``), replayed under the paper's rules or the sound model's."""
    if problem.scenario.sound is None:
        return plan_cost(problem, tuple(actions))
    replayed = sound.validate(problem, actions)
    if not replayed.valid:
        raise ValueError(f"not a plan: {replayed.reason}")
    return total_cost(zip(actions, replayed.states[1:]))


Verdict = Validation | sound.SoundValidation | commit.CommitValidation


def verdict_for(problem: Problem, actions: Sequence[Action]) -> Verdict:
    """The interpreter's verdict on ``actions``: under the paper's rules, or the sound model's when the scenario has
    one (under its commitment semantics: committed actions with an escape, then the predicted continuation)."""
    if problem.scenario.sound is None:
        return validate(problem, actions)
    return commit.validate(problem, actions) if _committed(problem) else sound.validate(problem, actions)


@dataclass(frozen=True, slots=True)
class PipelineValidation:
    """An action list checked against the pipeline's models: valid under which model, or why under none."""

    model: ModelKind  # the model it is a plan for, or the first model tried
    verdict: Verdict
    reason: str  # the valid model's reason, or every model's, joined


def validate_pipeline(scenario: Scenario, actions: Sequence[Action], model: ModelChoice | None = None,
                      horizon: int | None = None) -> PipelineValidation:
    """Whether ``actions`` is a plan under the first model of the choice (default: the scenario's) that accepts it
    (under the sound model when the scenario has one)."""
    verdicts: list[tuple[ModelKind, Verdict]] = []
    for kind in models_for(model or scenario.model):
        verdict = verdict_for(problem_for(scenario, kind, horizon), actions)
        if verdict.valid:
            return PipelineValidation(kind, verdict, verdict.reason)
        verdicts.append((kind, verdict))
    return PipelineValidation(verdicts[0][0], verdicts[0][1], "; ".join(f"{k.value}: {v.reason}" for k, v in verdicts))
