"""The interpreter engine, registered once: DFS over offsets for sensible, bitset BFS for shortest, a uniform-cost
search over offsets for optimal (``oracle.optimum``, the conformance check's own search)."""

from __future__ import annotations

from oracle import bitplan, commit, offsets, sound
from oracle.interpreter import replay
from oracle.optimum import lexicographic_optimum
from oracle.search import trivial_answer
from spec.answers import Limits, SearchResult, Status, Strategy
from spec.cost import COST_DOC, COST_TERMS
from spec.engines import Engine, register
from spec.escapes import Semantics
from spec.scenario import Problem


def _solve(problem: Problem, strategy: Strategy, limits: Limits) -> SearchResult:
    """The reference engine. The bitset search is bounded by the horizon (at most a few milliseconds),
    so only the depth-first search watches the limits. A scenario with a sound model goes to ``oracle.sound``."""
    if problem.scenario.sound is not None:
        if problem.scenario.sound.commitment is not None:
            return commit.solve(problem, strategy, limits)
        return sound.solve(problem, strategy, limits)
    if strategy is Strategy.SHORTEST:
        return bitplan.shortest(problem)
    if strategy is Strategy.OPTIMAL:
        return _optimal(problem, limits)
    return offsets.sensible(problem, limits)


def _optimal(problem: Problem, limits: Limits) -> SearchResult:
    """The least-cost plan of the paper's rules, its states the interpreter's replay."""
    trivial = trivial_answer(problem)
    if trivial is not None:
        return trivial
    try:
        best = lexicographic_optimum(problem, limits.max_states)
    except MemoryError as exc:
        return SearchResult(Status.INCOMPLETE, (), limits.max_states, str(exc))
    if best.cost is None:
        return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), best.explored,
                            f"no plan within {problem.horizon} actions")
    return SearchResult(Status.PLAN, best.actions, best.explored, f"optimal under {COST_DOC}",
                        replay(problem, best.actions, "interpreter"),
                        {"cost": dict(zip(COST_TERMS, best.cost, strict=True)), "cost_order": list(COST_TERMS)})


def _beyond(problem: Problem) -> SearchResult:
    """The proof that no plan of any length exists: the paper model's bitset closure; the sound model's when every
    path is refused before the horizon (its time has no end, so no closure of all its states)."""
    if problem.scenario.sound is not None:
        if problem.scenario.sound.commitment is not None:
            return commit.prove_beyond(problem)
        return sound.prove_beyond(problem)
    return bitplan.beyond_horizon(problem)


INTERPRETER = register(
    Engine("interpreter", (Strategy.SENSIBLE, Strategy.SHORTEST, Strategy.OPTIMAL), _solve,
           "Python reference interpreter and planners", _beyond, sound=True, commit=True,
           measured_speeds=tuple(Semantics), overtaken_profile=tuple(Semantics))
)
