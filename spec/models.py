"""The two models (final, preparations), their collision rules and their goals."""

from __future__ import annotations

import enum
from dataclasses import dataclass
from fractions import Fraction

from spec.lanes import Lane


class ModelKind(enum.Enum):
    """The paper's two Promela models."""

    FINAL = "final"
    PREPARATIONS = "preparations"


class ModelChoice(enum.Enum):
    """What a scenario or the CLI asks for: one model, or the paper's pipeline."""

    AUTO = "auto"
    FINAL = "final"
    PREPARATIONS = "preparations"


class GoalKind(enum.Enum):
    """The three goals: the overtake itself and the two preparation cases."""

    OVERTAKE = "overtake"
    RETURN_LEFT = "return_left"  # preparations, case A (AV starts in the right lane)
    CLOSE_GAP = "close_gap"  # preparations, case B (AV starts in the left lane)


@dataclass(frozen=True, slots=True)
class ModelRules:
    """Collision and guard parameters of one model."""

    kind: ModelKind
    danger_m: Fraction  # an oncoming vehicle within this distance of the AV's cell collides (a whole number of cells)
    max_lane_changes: int

    def __hash__(self) -> int:
        """Without the fraction: rules key the collision spans' cache on every step, and hashing it is slow."""
        return hash((self.kind.value, self.max_lane_changes))


@dataclass(frozen=True, slots=True)
class GoalRule:
    """A goal as a conjunction of declarative conditions every engine reads."""

    kind: GoalKind
    av_lane: Lane | None  # the AV must be in this lane, or None: either lane
    targets_behind: bool  # every target is at a cell below the AV's
    nearest_target_m: Fraction | None  # the nearest target is ahead of the AV, at most this far (false without targets)
    oncoming_passed: bool  # every oncoming vehicle is at or behind the AV's cell


MODEL_RULES: dict[ModelKind, ModelRules] = {
    ModelKind.FINAL: ModelRules(ModelKind.FINAL, danger_m=Fraction(21), max_lane_changes=2),  # one paper cell
    ModelKind.PREPARATIONS: ModelRules(ModelKind.PREPARATIONS, danger_m=Fraction(0), max_lane_changes=1),
}

GOAL_RULES: dict[GoalKind, GoalRule] = {
    GoalKind.OVERTAKE: GoalRule(GoalKind.OVERTAKE, Lane.LEFT, True, None, False),
    GoalKind.RETURN_LEFT: GoalRule(GoalKind.RETURN_LEFT, Lane.LEFT, False, None, True),
    GoalKind.CLOSE_GAP: GoalRule(GoalKind.CLOSE_GAP, None, False, Fraction(21), True),  # the next paper cell
}

#: The planner pipeline of the paper: the final model first, then the preparations model.
PIPELINE: tuple[ModelKind, ...] = (ModelKind.FINAL, ModelKind.PREPARATIONS)


def goal_kind(model: ModelKind, start_lane: Lane) -> GoalKind:
    """The goal a model pursues; the preparations goal depends on the AV's starting lane."""
    if model is ModelKind.FINAL:
        return GoalKind.OVERTAKE
    return GoalKind.RETURN_LEFT if start_lane is Lane.RIGHT else GoalKind.CLOSE_GAP


def models_for(choice: ModelChoice) -> tuple[ModelKind, ...]:
    """The models a choice tries, in order."""
    if choice is ModelChoice.AUTO:
        return PIPELINE
    return (ModelKind(choice.value),)
