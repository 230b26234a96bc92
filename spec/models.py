"""The two models (final, preparations), their collision rules and their goals."""

from __future__ import annotations

import enum
from dataclasses import dataclass

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
    danger_radius: int  # an oncoming vehicle within this many cells of the AV collides
    max_lane_changes: int


@dataclass(frozen=True, slots=True)
class GoalRule:
    """A goal as a conjunction of declarative conditions every engine reads."""

    kind: GoalKind
    av_lane: Lane | None  # the AV must be in this lane, or None: either lane
    targets_behind: bool  # every target is at a cell below AV_CELL
    nearest_target_offset: int | None  # the nearest target is at AV_CELL + offset (false without targets)
    oncoming_passed: bool  # every oncoming vehicle is at or behind AV_CELL


MODEL_RULES: dict[ModelKind, ModelRules] = {
    ModelKind.FINAL: ModelRules(ModelKind.FINAL, danger_radius=1, max_lane_changes=2),
    ModelKind.PREPARATIONS: ModelRules(ModelKind.PREPARATIONS, danger_radius=0, max_lane_changes=1),
}

GOAL_RULES: dict[GoalKind, GoalRule] = {
    GoalKind.OVERTAKE: GoalRule(GoalKind.OVERTAKE, Lane.LEFT, True, None, False),
    GoalKind.RETURN_LEFT: GoalRule(GoalKind.RETURN_LEFT, Lane.LEFT, False, None, True),
    GoalKind.CLOSE_GAP: GoalRule(GoalKind.CLOSE_GAP, None, False, 1, True),
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
