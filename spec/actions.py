"""The AV's actions, their guards, and their effects, derived from the physical mapping.

Each action is described once by its physics (AV speed as a multiple of the common
speed, duration in time units, sideways move); the discrete effects every engine uses
(left-lane shift, oncoming ticks) follow from it exactly, so the two can never disagree.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from fractions import Fraction

from spec.constants import TIME_UNIT_S
from spec.errors import ActionError
from spec.lanes import Lane


class Action(enum.Enum):
    """The AV's actions, declared in the paper's preferred search order."""

    LEFT_LANE_CHANGE = "left_lane_change"
    ACCELERATE = "accelerate"
    RIGHT_LANE_CHANGE = "right_lane_change"
    DRIVE = "drive"
    BRAKE = "brake"


#: The search order every engine uses (sensible and shortest strategies).
ACTION_ORDER: tuple[Action, ...] = tuple(Action)


@dataclass(frozen=True, slots=True)
class ActionRule:
    """Guard and physics of one action; the discrete effects are derived properties."""

    action: Action
    speed_factor: Fraction  # AV speed as a multiple of every other vehicle's speed
    time_units: int  # duration in time units (one cell at the common speed)
    from_lane: Lane | None  # the lane the AV must be in, or None: any lane
    to_lane: Lane | None  # the lane the AV ends in after a lane change, or None: unchanged

    @property
    def changes_lane(self) -> bool:
        """Whether the action is a lane change (it counts against the model's limit)."""
        return self.to_lane is not None

    @property
    def left_shift_cells(self) -> int:
        """How far every left-lane vehicle moves relative to the AV (negative: closer)."""
        return _exact(self.time_units * (1 - self.speed_factor), self.action, "left shift")

    @property
    def oncoming_ticks(self) -> int:
        """How many one-cell steps every oncoming vehicle makes towards the AV."""
        return _exact(self.time_units * (1 + self.speed_factor), self.action, "ticks")

    @property
    def duration_s(self) -> float:
        """Duration of the action in seconds."""
        return self.time_units * TIME_UNIT_S

    @property
    def lateral_lanes(self) -> int:
        """Sideways move in lanes: +1 towards the right lane, -1 towards the left, 0 none."""
        if self.to_lane is None:
            return 0
        return 1 if self.to_lane is Lane.RIGHT else -1


def _exact(value: Fraction, action: Action, what: str) -> int:
    """The value as an int; a non-integer means the physical mapping is inconsistent."""
    if value.denominator != 1:
        raise ValueError(f"spec: {action.value}: {what} {value} is not a whole number of cells")
    return int(value)


ACTION_RULES: dict[Action, ActionRule] = {
    Action.LEFT_LANE_CHANGE: ActionRule(Action.LEFT_LANE_CHANGE, Fraction(1), 1, Lane.RIGHT, Lane.LEFT),
    Action.ACCELERATE: ActionRule(Action.ACCELERATE, Fraction(2), 1, None, None),
    Action.RIGHT_LANE_CHANGE: ActionRule(Action.RIGHT_LANE_CHANGE, Fraction(1), 1, Lane.LEFT, Lane.RIGHT),
    Action.DRIVE: ActionRule(Action.DRIVE, Fraction(1), 1, None, None),
    Action.BRAKE: ActionRule(Action.BRAKE, Fraction(1, 2), 2, None, None),
}


def parse_action(name: str) -> Action:
    """The action called ``name`` (its value, as in scenario files and the CLI)."""
    try:
        return Action(name.strip())
    except ValueError:
        known = ", ".join(a.value for a in Action)
        raise ActionError(f"unknown action {name.strip()!r} (known: {known})") from None
