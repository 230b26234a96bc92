"""The AV's actions, their guards, and their effects, derived from the physical mapping.

Each action is described once by its physics (AV speed as a multiple of the common
speed, duration in seconds, sideways move); the discrete effects every engine uses
(left-lane shift, oncoming ticks) follow from it on a grid (``spec.grid``), exactly, so the
two can never disagree.
"""

from __future__ import annotations

import enum
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction

from spec.errors import ActionError
from spec.lanes import Lane


class Action(enum.Enum):
    """The AV's actions, declared in the paper's preferred search order."""

    LEFT_LANE_CHANGE = "left_lane_change"
    ACCELERATE = "accelerate"
    RIGHT_LANE_CHANGE = "right_lane_change"
    DRIVE = "drive"
    BRAKE = "brake"

    __hash__ = object.__hash__  # members are singletons: identity is equality, and Enum's own hash is slow Python


#: The search order every engine uses (sensible and shortest strategies).
ACTION_ORDER: tuple[Action, ...] = tuple(Action)


@dataclass(frozen=True, slots=True)
class ActionRule:
    """Guard and physics of one action; its discrete effects on a grid come from ``spec.grid.Grid``."""

    action: Action
    speed_factor: Fraction  # AV speed as a multiple of the common speed
    duration_s: Fraction  # duration in seconds (the paper's 3 s, one 21 m cell at 7 m/s; brake 6 s)
    from_lane: Lane | None  # the lane the AV must be in, or None: any lane
    to_lane: Lane | None  # the lane the AV ends in after a lane change, or None: unchanged

    @property
    def changes_lane(self) -> bool:
        """Whether the action is a lane change (it counts against the model's limit)."""
        return self.to_lane is not None

    @property
    def lateral_lanes(self) -> int:
        """Sideways move in lanes: +1 towards the right lane, -1 towards the left, 0 none."""
        if self.to_lane is None:
            return 0
        return 1 if self.to_lane is Lane.RIGHT else -1


ACTION_RULES: dict[Action, ActionRule] = {
    Action.LEFT_LANE_CHANGE: ActionRule(Action.LEFT_LANE_CHANGE, Fraction(1), Fraction(3), Lane.RIGHT, Lane.LEFT),
    Action.ACCELERATE: ActionRule(Action.ACCELERATE, Fraction(2), Fraction(3), None, None),
    Action.RIGHT_LANE_CHANGE: ActionRule(Action.RIGHT_LANE_CHANGE, Fraction(1), Fraction(3), Lane.LEFT, Lane.RIGHT),
    Action.DRIVE: ActionRule(Action.DRIVE, Fraction(1), Fraction(3), None, None),
    Action.BRAKE: ActionRule(Action.BRAKE, Fraction(1, 2), Fraction(6), None, None),
}


def plan_text(actions: Sequence[Action]) -> str:
    """An action list as messages and reports show it: comma-separated values, or "(empty)"."""
    return ",".join(a.value for a in actions) or "(empty)"


def parse_action(name: str) -> Action:
    """The action called ``name`` (its value, as in scenario files and the CLI)."""
    try:
        return Action(name.strip())
    except ValueError:
        known = ", ".join(a.value for a in Action)
        raise ActionError(f"unknown action {name.strip()!r} (known: {known})") from None
