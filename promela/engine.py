"""The Spin engine, registered once: compile-once planning with Spin's DFS (sensible) and BFS (shortest)."""

from __future__ import annotations

from oracle.answer import Limits, SearchResult
from oracle.engines import Engine, register
from promela import runner
from spec.scenario import Problem


def _solve(problem: Problem, strategy: str, limits: Limits) -> SearchResult:
    """Spin's default depth-first search for sensible, its breadth-first search for shortest."""
    return runner.search(problem, strategy, limits.timeout_s)


SPIN = register(Engine("spin", ("sensible", "shortest"), _solve,
                       "Spin model checker, verifier compiled once per model and cached"))
