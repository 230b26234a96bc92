"""The built-in scenario library, shipped with the package, each with its expected outcome.

Expectations were derived by hand from the rules in SPEC.md and are checked by
tests/spec/test_library.py against every engine.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from spec.files import load_scenario
from spec.scenario import Scenario

SCENARIO_DIR = Path(__file__).parent / "scenarios"


@dataclass(frozen=True, slots=True)
class Expected:
    """The answer every engine must give for a built-in scenario."""

    status: str  # plan, no_plan, no_plan_within_horizon
    model: str  # the model whose plan it is (or the last model tried)
    sensible: tuple[str, ...] = ()  # the exact sensible plan
    shortest_length: int = 0


@dataclass(frozen=True, slots=True)
class Builtin:
    """A built-in scenario: its name, what it shows, and its expected outcome."""

    name: str
    description: str
    expected: Expected

    @property
    def path(self) -> Path:
        """The scenario file shipped with the package."""
        return SCENARIO_DIR / f"{self.name}.toml"

    def load(self) -> Scenario:
        """The validated scenario."""
        return load_scenario(self.path)


_A, _R, _L, _D, _B = "accelerate", "right_lane_change", "left_lane_change", "drive", "brake"

BUILTINS: tuple[Builtin, ...] = (
    Builtin("paper_example", "the paper's example: FV1, FV2 ahead, OV far",
            Expected("plan", "final", (_A, _R, _A, _A, _A, _A, _L), 7)),
    Builtin("one_target", "one vehicle ahead, no oncoming traffic",
            Expected("plan", "final", (_A, _R, _A, _A, _L), 5)),
    Builtin("two_targets", "two targets and a third vehicle further on",
            Expected("plan", "final", (_A, _R, _A, _A, _A, _A, _L), 7)),
    Builtin("three_targets", "three targets in one manoeuvre",
            Expected("plan", "final", (_A, _R, _A, _A, _A, _A, _A, _A, _L), 9)),
    Builtin("oncoming_forces_wait", "an oncoming vehicle must pass first",
            Expected("plan", "final", (_A, _D, _D, _D, _D, _R, _A, _A, _L), 8)),
    Builtin("prep_case_a", "case A: back into a left-lane gap",
            Expected("plan", "preparations", (_A, _A, _L), 3)),
    Builtin("prep_case_b", "case B: close the gap while OV passes",
            Expected("plan", "preparations", (_A, _A), 2)),
    Builtin("no_plan_boxed_in", "boxed in: no plan of any length",
            Expected("no_plan", "preparations")),
    Builtin("no_plan_within_horizon", "final model, horizon 3: too short",
            Expected("no_plan_within_horizon", "final")),
    Builtin("nothing_to_overtake", "no target: the empty plan",
            Expected("plan", "final", (), 0)),
)


def builtin(name: str) -> Builtin | None:
    """The built-in scenario called ``name``, if any."""
    return next((b for b in BUILTINS if b.name == name), None)
