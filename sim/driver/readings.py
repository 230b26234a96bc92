"""What the sensors hand the decision layer: one reading per sensed vehicle, in the AV's frame."""

from __future__ import annotations

from dataclasses import dataclass, replace

from spec.errors import ScenarioError
from spec.lanes import Lane


@dataclass(frozen=True, slots=True)
class Reading:
    """One sensed vehicle: its lane, its body, and its distance ahead of the AV along the road (m); a kept track that
    no reading confirmed this sweep (``sim.tracking``) also says how far either side of it the vehicle may be."""

    lane: Lane
    body: int
    dx_m: float
    spread_m: tuple[float, float] = (0.0, 0.0)  # (below, above) dx_m: the vehicle is within [dx - below, dx + above]
    rate_mps: float | None = None  # the range rate (how fast dx_m grows: a radar's Doppler reading); None: not read
    #: a kept track's speed interval (m/s along its direction of travel) when the planner reads it; None: not told
    speed_mps: tuple[float, float] | None = None

    @property
    def interval_m(self) -> tuple[float, float]:
        return self.dx_m - self.spread_m[0], self.dx_m + self.spread_m[1]


def seen_from(readings: tuple[Reading, ...], ahead_m: float) -> tuple[Reading, ...]:
    """The readings, taken from the car, as a point ``ahead_m`` behind it sees them (the plan's reference:
    ``sim.driver.decide.plan_start``)."""
    if not ahead_m:
        return readings
    return tuple(replace(r, dx_m=r.dx_m + ahead_m) for r in readings)


def snapshot(sweep: tuple[Reading, ...] | None) -> tuple[Reading, ...]:
    """The sensors' last sweep as a decision's snapshot; a dropped sweep (None) is a snapshot that cannot be read."""
    if sweep is None:
        raise ScenarioError("snapshot", "dropped sweep", "the sensors' last sweep never arrived")
    return sweep
