"""States of the transition system and collisions: plain frozen values every engine reports."""

from __future__ import annotations

from dataclasses import dataclass

from spec.lanes import Lane


@dataclass(frozen=True, slots=True)
class State:
    """One state of the transition system: cells are relative to the AV (at its grid's ``av_cell``)."""

    lane: Lane
    left_lane: tuple[int, ...]  # same-direction vehicles, ascending; never clipped
    right_lane: tuple[int, ...]  # oncoming vehicles, ascending; never clipped
    lane_changes: int = 0
    steps: int = 0


@dataclass(frozen=True, slots=True)
class Collision:
    """A collision: the state it happened in and the vehicle hit."""

    state: State
    lane: Lane  # the lane of the vehicle hit
    vehicle: int  # its index in that lane's tuple (ascending cells)
    cell: int  # its cell when hit
    tick: int  # 0: right after the action's effect; k: after oncoming tick k

    def describe(self) -> str:
        """One line naming the vehicle, its cell, and when it was hit."""
        when = "after the effect" if self.tick == 0 else f"after oncoming tick {self.tick}"
        return f"collision with {self.lane.value}_lane[{self.vehicle}] at cell {self.cell} {when}"
