"""Kinds of what a closed-loop drive records: failures and tolerance violations."""

from __future__ import annotations

import enum


class FailureKind(enum.Enum):
    """What ended or marred a drive, most serious first (the order a drive's first failure is reported in)."""

    COLLISION = "collision"
    PLANNER = "planner"  # no plan (or none usable) and no plan under way
    SENSING = "sensing"  # the readings made no valid scenario


class ViolationKind(enum.Enum):
    """Which tolerance a vehicle's deviation from the model's prediction exceeded."""

    STEP = "step"  # what one action added
    PLAN = "plan"  # accumulated since the plan started
