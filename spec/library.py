"""The built-in scenario library, shipped with the package, each with its expected outcome.

Expectations were derived by hand from the rules in SPEC.md and are checked by
tests/spec/test_library.py against every engine.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from spec.actions import Action
from spec.answers import Answer, Status, Strategy
from spec.files import load_scenario
from spec.models import ModelKind
from spec.scenario import Scenario

SCENARIO_DIR = Path(__file__).parent / "scenarios"


@dataclass(frozen=True, slots=True)
class Expected:
    """The answer every engine must give for a built-in scenario."""

    status: Status
    model: ModelKind  # the model whose plan it is (or the last model tried)
    sensible: tuple[Action, ...] = ()  # the exact sensible plan
    shortest_length: int = 0

    def matches(self, answer: Answer, proves_beyond: bool) -> bool:
        """Whether ``answer`` is this expectation: status, model, and the plan its strategy pins down.

        An engine that cannot prove "no plan of any length" may answer the weaker "no plan
        within the horizon" where the expectation is "no plan".
        """
        status = answer.status
        if self.status is Status.NO_PLAN and not proves_beyond and status is Status.NO_PLAN_WITHIN_HORIZON:
            status = Status.NO_PLAN
        if status is not self.status or (answer.model is not None and answer.model is not self.model):
            return False
        if answer.strategy is Strategy.SENSIBLE:
            return answer.actions == self.sensible
        return answer.strategy is not Strategy.SHORTEST or len(answer.actions) == self.shortest_length


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


_A, _R, _L, _D = Action.ACCELERATE, Action.RIGHT_LANE_CHANGE, Action.LEFT_LANE_CHANGE, Action.DRIVE
_PLAN, _FINAL, _PREP = Status.PLAN, ModelKind.FINAL, ModelKind.PREPARATIONS

BUILTINS: tuple[Builtin, ...] = (
    Builtin("paper_example", "the paper's example: FV1, FV2 ahead, OV far",
            Expected(_PLAN, _FINAL, (_A, _R, _A, _A, _A, _A, _L), 7)),
    Builtin("one_target", "one vehicle ahead, no oncoming traffic",
            Expected(_PLAN, _FINAL, (_A, _R, _A, _A, _L), 5)),
    Builtin("two_targets", "two targets and a third vehicle further on",
            Expected(_PLAN, _FINAL, (_A, _R, _A, _A, _A, _A, _L), 7)),
    Builtin("three_targets", "three targets in one manoeuvre",
            Expected(_PLAN, _FINAL, (_A, _R, _A, _A, _A, _A, _A, _A, _L), 9)),
    Builtin("oncoming_forces_wait", "an oncoming vehicle must pass first",
            Expected(_PLAN, _FINAL, (_A, _D, _D, _D, _D, _R, _A, _A, _L), 8)),
    Builtin("prep_case_a", "case A: back into a left-lane gap",
            Expected(_PLAN, _PREP, (_A, _A, _L), 3)),
    Builtin("prep_case_b", "case B: close the gap while OV passes",
            Expected(_PLAN, _PREP, (_A, _A), 2)),
    Builtin("no_plan_boxed_in", "boxed in: no plan of any length",
            Expected(Status.NO_PLAN, _PREP)),
    Builtin("no_plan_within_horizon", "final model, horizon 3: too short",
            Expected(Status.NO_PLAN_WITHIN_HORIZON, _FINAL)),
    Builtin("nothing_to_overtake", "no target: the empty plan",
            Expected(_PLAN, _FINAL, (), 0)),
)


def builtin(name: str) -> Builtin | None:
    """The built-in scenario called ``name``, if any."""
    return next((b for b in BUILTINS if b.name == name), None)
