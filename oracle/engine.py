"""The interpreter engine, registered once: DFS over offsets for sensible, bitset BFS for shortest."""

from __future__ import annotations

from oracle import bitplan, offsets, sound
from spec.answers import Limits, SearchResult, Status, Strategy
from spec.engines import Engine, register
from spec.scenario import Problem


def _solve(problem: Problem, strategy: Strategy, limits: Limits) -> SearchResult:
    """The reference engine. The bitset search is bounded by the horizon (at most a few milliseconds),
    so only the depth-first search watches the limits. A scenario with a sound model goes to ``oracle.sound``."""
    if problem.scenario.sound is not None:
        return sound.solve(problem, strategy, limits)
    if strategy is Strategy.SHORTEST:
        return bitplan.shortest(problem)
    return offsets.sensible(problem, limits)


def _beyond(problem: Problem) -> SearchResult:
    """The paper model's proof that no plan of any length exists; the sound model has none (its time is unbounded)."""
    if problem.scenario.sound is not None:
        return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), 0, sound.beyond(problem))
    return bitplan.beyond_horizon(problem)


INTERPRETER = register(
    Engine("interpreter", (Strategy.SENSIBLE, Strategy.SHORTEST), _solve, "Python reference interpreter and planners",
           _beyond, sound=True)
)
