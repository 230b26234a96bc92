"""Reproducers people can use: a failing scenario shrunk, written as a scenario file, a ready-to-run pytest
regression test, and the engines' traces side by side up to the first step where they differ.

The message is the shrunk scenario's own failure (its property's detail), not the original's.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ci.conformance.properties import PROPERTIES, PropertyName, Run, Runs, Verdict, first_difference
from oracle import bmc
from oracle.planner import verdict_for as validate
from oracle.shrink import shrink, to_toml
from oracle.sound import reachable_sets
from spec.actions import plan_text
from spec.answers import Limits, Status
from spec.scenario import Scenario, problem_for
from spec.state import State

REPRO_DIR = "repro"
MAX_SHRINK_CHECKS = 400  # each check runs the property's engines: a bound on a reproducer's cost


def fails(name: PropertyName, engines: Sequence[str], limits: Limits) -> Any:
    """The predicate "``name`` fails on this scenario" (incomplete is not a failure: a shrink must not chase
    time-outs)."""
    def check(scenario: Scenario) -> bool:
        return PROPERTIES[name].verdict(scenario, Runs(scenario, limits), engines).verdict is Verdict.FAILED

    return check


def reproduce(name: PropertyName, scenario: Scenario, engines: Sequence[str], timeout_s: float | None, out: Path,
              number: int, origin: str) -> dict[str, Any]:
    """Shrink ``scenario`` (which fails ``name``) and write its reproducer files; what was written, as a record.
    Z3 gets a solver of its own for each problem here, as in the fresh process the regression test runs in."""
    limits = Limits(timeout_s=timeout_s)
    with bmc.isolated():
        small, checks = shrink(scenario, fails(name, engines, limits), MAX_SHRINK_CHECKS)
        runs = Runs(small, limits)
        outcome = PROPERTIES[name].verdict(small, runs, engines)
    folder = out / REPRO_DIR
    folder.mkdir(parents=True, exist_ok=True)
    stem = f"{name.value}-{number}"
    scenario_file = folder / f"{stem}.toml"
    scenario_file.write_text(to_toml(small, f"{name.value} fails: {outcome.detail}\nshrunk from {origin} "
                                            f"({checks} checks)"))
    test_file = folder / f"test_{name.value}_{number}.py"
    test_file.write_text(_test_source(name, stem, list(engines), outcome.detail))
    traces_file = folder / f"{stem}-traces.txt"
    traces_file.write_text(side_by_side(small, runs.made()))
    vehicles = len(small.left_lane) + len(small.right_lane)
    return {"property": name.value, "detail": outcome.detail, "verdict": outcome.verdict.value,
            "scenario_file": str(scenario_file), "test_file": str(test_file), "traces_file": str(traces_file),
            "vehicles": vehicles, "horizon": small.horizon, "shrink_checks": checks, "origin": origin}


def _test_source(name: PropertyName, stem: str, engines: list[str], detail: str) -> str:
    first_line = detail.replace('"', "'").splitlines()[0] if detail else ""
    return f'''"""Regression test written by `overtake crossval`: {name.value} failed on {stem}.toml.

It failed with: {first_line}
Run it with: python -m pytest {stem.replace("-", "_")} (from a checkout with the suite installed).
"""

from pathlib import Path

from ci.conformance.properties import PROPERTIES, PropertyName, Runs, Verdict
from spec.answers import Limits
from spec.files import load_scenario


def test_{name.value}_holds_on_the_reproducer() -> None:
    scenario = load_scenario(Path(__file__).with_name("{stem}.toml"))
    outcome = PROPERTIES[PropertyName("{name.value}")].verdict(scenario, Runs(scenario, Limits(timeout_s=60)),
                                                              {engines!r})
    assert outcome.verdict is Verdict.HELD, outcome.detail
'''


def compact(state: State) -> str:
    """A state in one short line: the AV's lane, both lanes' cells, lane changes so far."""
    return (f"AV {state.lane.value:<5} left {list(state.left_lane)} oncoming {list(state.right_lane)} "
            f"lc {state.lane_changes}")


def side_by_side(scenario: Scenario, runs: Sequence[Run]) -> str:
    """Each run's plan and its states beside the interpreter's replay of it, up to the first differing step."""
    lines = [f"scenario: AV in the {scenario.lane.value} lane, left {list(scenario.left_lane)}, oncoming "
             f"{list(scenario.right_lane)}, {scenario.targets} target(s), horizon {scenario.horizon}, "
             f"{scenario.grid.describe()}; states are cells (the AV's is {scenario.grid.av_cell})"
             + (f"; {scenario.sound.describe()}" if scenario.sound is not None else "; the paper's rules")]
    for run in runs:
        answer = run.answer
        if run.error is not None:
            lines.append(f"\n{run.key.label}: engine error: {run.error}")
            continue
        if answer is None or answer.status is not Status.PLAN or answer.model is None:
            lines.append(f"\n{run.key.label}: {answer.status.value if answer else '-'}")
            continue
        replay = validate(problem_for(scenario, answer.model), answer.actions)
        differ = first_difference(replay.states, answer.states) if answer.states else 0
        lines.append(f"\n{run.key.label} ({answer.model.value} model): "
                     f"{plan_text(answer.actions)}"
                     + ("" if replay.valid else f"  [invalid: {replay.reason}]"))
        lines.append(f"  {'step':>4}  {'action':<18} {'engine state':<34} interpreter state")
        last = len(answer.actions) if differ is None else differ
        for n in range(last + 1):
            action = "(start)" if n == 0 else answer.actions[n - 1].value if n <= len(answer.actions) else "(none)"
            theirs = compact(answer.states[n]) if n < len(answer.states) else "(none)"
            ours = compact(replay.states[n]) if n < len(replay.states) else "(none: the plan is invalid here)"
            mark = "  <-- first difference" if n == differ else ""
            lines.append(f"  {n:>4}  {action:<18} {theirs:<34} {ours}{mark}")
        if scenario.sound is not None:
            lines.append("  the interpreter's reachable sets along it (each vehicle's interval, metres ahead of the "
                         "AV's reference; +-inf: a phantom's unseen stretch):")
            lines += [f"    {line}" for line in reachable_sets(problem_for(scenario, answer.model), answer.actions)]
    return "\n".join(lines) + "\n"
