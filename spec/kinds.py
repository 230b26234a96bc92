"""Kinds of what a closed-loop drive records: failures and tolerance violations."""

from __future__ import annotations

import enum


class FailureKind(enum.Enum):
    """What ended or marred a drive, most serious first (the order a drive's first failure is reported in)."""

    COLLISION = "collision"
    LOSS_OF_CONTROL = "loss of control"  # the AV spun or left the road (``spec.faults.lost_control``)
    PLANNER = "planner"  # no plan (or none usable) and no plan under way
    SENSING = "sensing"  # the readings made no valid scenario, or the sweep never arrived
    BLOCKED = "blocked"  # the AV stood (less than a car length in ``sim.simulator.BLOCKED_S``): the episode is given up

    @property
    def ends_run(self) -> bool:
        """A failure proper (a collision, a loss of control) ends a run ``--until-failure``; a stop because the
        snapshot could not be read or no plan was found is counted apart, never as a failure (the paper's Table 1
        counts the car's failures, and a car that waits in lane has not failed)."""
        return self in (FailureKind.COLLISION, FailureKind.LOSS_OF_CONTROL)


class ViolationKind(enum.Enum):
    """Which tolerance a vehicle's deviation from the model's prediction exceeded."""

    STEP = "step"  # what one action added
    PLAN = "plan"  # accumulated since the plan started
