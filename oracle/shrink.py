"""Shrink a failing scenario to a minimal reproducer a person can read.

Greedy and deterministic: try removing each vehicle, lowering the target count and the
horizon, and moving each vehicle one cell towards the AV; keep any change after which
the scenario still fails; stop when no single change does. The result is 1-minimal: no
single one of these changes keeps it failing.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterator
from dataclasses import replace

from oracle.conform import disagreements
from oracle.planner import plan
from spec.answers import Limits, Strategy
from spec.engines import Engine
from spec.errors import EngineError, ScenarioError
from spec.files import scenario_to_dict
from spec.scenario import Scenario, make_scenario

Predicate = Callable[[Scenario], bool]


def shrink(scenario: Scenario, fails: Predicate, max_checks: int = 5000) -> tuple[Scenario, int]:
    """The smallest failing scenario reachable by single changes, and the number of checks made."""
    current, checks = scenario, 0
    improved = True
    while improved and checks < max_checks:
        improved = False
        for candidate in _smaller(current):
            checks += 1
            if fails(candidate):
                current, improved = candidate, True
                break
            if checks >= max_checks:
                break
    return current, checks


def _smaller(s: Scenario) -> Iterator[Scenario]:
    """Valid scenarios one change smaller than ``s``, most drastic first."""
    targets = set(s.target_indices)
    for i in range(len(s.left_lane)):
        left = s.left_lane[:i] + s.left_lane[i + 1:]
        yield from _valid(s, left=left, targets=s.targets - (i in targets))
    for i in range(len(s.right_lane)):
        yield from _valid(s, right=s.right_lane[:i] + s.right_lane[i + 1:])
    if s.targets:
        yield from _valid(s, targets=s.targets - 1)
    for h in sorted({s.horizon // 2, s.horizon - 1}):
        if 0 <= h < s.horizon:
            yield from _valid(s, horizon=h)
    av_cell = s.grid.av_cell
    for i, cell in enumerate(s.left_lane):
        yield from _valid(s, left=(*s.left_lane[:i], _toward(cell, av_cell), *s.left_lane[i + 1:]))
    for i, cell in enumerate(s.right_lane):
        yield from _valid(s, right=(*s.right_lane[:i], _toward(cell, av_cell), *s.right_lane[i + 1:]))


def _toward(cell: int, av_cell: int) -> int:
    return cell - 1 if cell > av_cell else cell + 1


def _valid(s: Scenario, left: tuple[int, ...] | None = None, right: tuple[int, ...] | None = None,
           targets: int | None = None, horizon: int | None = None) -> Iterator[Scenario]:
    """The changed scenario, if it is still valid and actually different."""
    try:
        changed = replace(make_scenario(s.lane, list(s.left_lane if left is None else left),
                                        list(s.right_lane if right is None else right),
                                        s.targets if targets is None else targets, s.model,
                                        s.horizon if horizon is None else horizon, grid=s.grid), sound=s.sound)
    except ScenarioError:
        return
    if changed != s:
        yield changed


def engines_disagree(engines: list[Engine], strategy: Strategy, limits: Limits | None = None) -> Predicate:
    """The predicate "these engines disagree on this scenario" (an engine error, such as an invalid plan or a "no
    plan" the interpreter contradicts, counts: it is the disagreement the pipeline caught)."""
    def fails(scenario: Scenario) -> bool:
        try:
            answers = [plan(scenario, strategy, engine=e, limits=limits) for e in engines]
        except EngineError:
            return True
        return bool(disagreements(answers))

    return fails


def to_toml(scenario: Scenario, comment: str = "") -> str:
    """The scenario as a scenario file (TOML), readable and loadable by every command."""
    lines = [f"# {line}" for line in comment.splitlines()]
    data = scenario_to_dict(scenario)
    lines += [f"{key} = {json.dumps(value)}" for key, value in data.items() if not isinstance(value, dict)]
    for key, table in data.items():  # tables (the sound model's bounds) after the plain keys, as TOML requires
        if isinstance(table, dict):
            lines += ["", f"[{key}]", *(f"{k} = {json.dumps(v)}" for k, v in table.items())]
    return "\n".join(lines) + "\n"
