"""The Spin engine, registered once: compile-once planning with Spin's DFS (sensible) and BFS (shortest), for the
paper's model and for the sound model (``promela.sound``: its physical checks; the identity check's paper cell rules,
``Checks.PAPER_CELLS``, are the interpreter's only and an engine error here)."""

from __future__ import annotations

from promela import commit, runner
from spec.answers import Limits, SearchResult, Strategy
from spec.engines import Engine, register
from spec.escapes import Semantics
from spec.scenario import Problem


def _solve(problem: Problem, strategy: Strategy, limits: Limits) -> SearchResult:
    """Spin's default depth-first search for sensible, its breadth-first search for shortest; under the commitment
    semantics its proofs composed by ``spec.commitment`` (``promela.commit``)."""
    sound = problem.scenario.sound
    if sound is not None and sound.commitment is not None:
        return commit.solve(problem, strategy, limits)
    return runner.search(problem, strategy, limits.timeout_s)


SPIN = register(Engine("spin", (Strategy.SENSIBLE, Strategy.SHORTEST), _solve,
                       "Spin model checker, verifier compiled once per model and cached",
                       check_tools=runner.check_tools, sound=True, commit=True, measured_speeds=tuple(Semantics),
                       overtaken_profile=tuple(Semantics)))
