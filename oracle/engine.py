"""The interpreter engine, registered once: DFS over offsets for sensible, bitset BFS for shortest."""

from __future__ import annotations

from oracle import bitplan, offsets
from spec.answers import Limits, SearchResult, Strategy
from spec.engines import Engine, register
from spec.scenario import Problem


def _solve(problem: Problem, strategy: Strategy, limits: Limits) -> SearchResult:
    """The reference engine. The bitset search is bounded by the horizon (at most a few milliseconds),
    so only the depth-first search watches the limits."""
    if strategy is Strategy.SHORTEST:
        return bitplan.shortest(problem)
    return offsets.sensible(problem, limits)


INTERPRETER = register(
    Engine("interpreter", (Strategy.SENSIBLE, Strategy.SHORTEST), _solve, "Python reference interpreter and planners",
           bitplan.beyond_horizon)
)
