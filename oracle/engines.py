"""The engine registry: every engine is registered once, with the strategies it answers.

Later engines (spin, z3) register here; tests are parametrised over ``ENGINES`` and fail
when an engine skips a strategy it claims.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass

from oracle import bitplan, offsets
from oracle.answer import Limits, SearchResult
from spec.errors import ScenarioError
from spec.scenario import Problem

Solver = Callable[[Problem, str, Limits], SearchResult]


@dataclass(frozen=True, slots=True)
class Engine:
    """A registered engine: its name, the strategies it answers, and how it solves a problem."""

    name: str
    strategies: tuple[str, ...]
    solve: Solver
    description: str
    #: Given a problem with no plan within the horizon, proves (NO_PLAN) or not that none exists at all.
    prove_beyond: Callable[[Problem], SearchResult] | None = None


ENGINES: dict[str, Engine] = {}

#: Modules that register further engines when imported (each issue adds its own line).
ENGINE_MODULES: tuple[str, ...] = ("promela.engine", "oracle.bmc")


def load_engines() -> dict[str, Engine]:
    """Import every engine module so that the registry is complete, and return it."""
    for module in ENGINE_MODULES:
        importlib.import_module(module)
    return ENGINES


def register(engine: Engine) -> Engine:
    """Add an engine to the registry (once)."""
    if engine.name in ENGINES:
        raise ValueError(f"engine {engine.name!r} registered twice")
    ENGINES[engine.name] = engine
    return engine


def get_engine(name: str) -> Engine:
    """The engine called ``name``; bad names are bad input."""
    load_engines()
    try:
        return ENGINES[name]
    except KeyError:
        raise ScenarioError("--engine", name, f"unknown engine (known: {', '.join(ENGINES)})") from None


def check_strategy(engine: Engine, strategy: str) -> None:
    """Raise bad input when ``engine`` does not answer ``strategy``."""
    if strategy not in engine.strategies:
        raise ScenarioError(
            "--strategy", strategy, f"engine {engine.name} answers {', '.join(engine.strategies)} only"
        )


def _interpreter(problem: Problem, strategy: str, limits: Limits) -> SearchResult:
    """The reference engine: DFS over offsets for sensible, bitset BFS for shortest.

    The bitset search is bounded by the horizon (at most a few milliseconds), so only
    the depth-first search watches the limits.
    """
    if strategy == "shortest":
        return bitplan.shortest(problem)
    return offsets.sensible(problem, limits.max_states, limits.timeout_s)


INTERPRETER = register(
    Engine("interpreter", ("sensible", "shortest"), _interpreter, "Python reference interpreter and planners",
           bitplan.beyond_horizon)
)
