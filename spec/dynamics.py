"""How one vehicle may move from the snapshot on, given what was measured of its speed (CommonRoad SPOT's and RSS's
per-vehicle bounds): its speed then anywhere in ``[low, high]``, changing at most at ``SpeedChange``'s rates (braking
at b_max, accelerating at a_max), never below a standstill (no driving backwards) and never above its top speed (its
lane's stated top, or the speed measured when that is higher). Braking to a standstill at any instant is inside.

The least distance it travels is braking at b_max from ``low`` to a stop and standing; the most is accelerating at
a_max from ``high`` to its top and holding it. Each is a few phases of constant acceleration (``Phase``), so every
check of the sound model takes its extreme over a window exactly (``spec.sound``). A vehicle without a measured speed
keeps its lane's speeds (``spec.assumptions.Bounds``), as phantoms do.

A stated behaviour may narrow that, offered as a profile and never silently (``Overtaken``): under
``NO_ACCELERATION`` a measured same-direction vehicle does not speed up while the AV is in the passing lane
(``passing_windows_s``), the duty of a vehicle being overtaken in several countries (for example StVO section 5(6)
in Germany). Its fastest motion then speeds up only until the AV starts its move out (``Dynamics.held_from``).
"""

from __future__ import annotations

import enum
import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

from spec.actions import ACTION_RULES, Action
from spec.errors import OptionError, parse_choice
from spec.lanes import Lane
from spec.tracking import VEHICLE_SPEED_CHANGE, Speed, SpeedChange


class VehicleSpeeds(enum.Enum):
    """Where the closed loop's planner and containment take a vehicle's speed from."""

    LANE = "lane"  # its lane's bounds (``spec.assumptions.Bounds``), whatever was measured
    MEASURED = "measured"  # its track's speed interval (``sim.tracking``), moving by its own dynamics


def parse_vehicle_speeds(value: object, where: str = "--vehicle-speeds") -> VehicleSpeeds:
    return parse_choice(VehicleSpeeds, value, where)


class Overtaken(enum.Enum):
    """What a measured same-direction vehicle may do while the AV is in the passing lane (``passing_windows_s``)."""

    PHYSICS = "physics"  # whatever its dynamics allow: it may speed up at a_max while the AV passes it
    #: it does not speed up while the AV is in the passing lane (StVO section 5(6): "Wer überholt wird, darf seine
    #: Geschwindigkeit nicht erhöhen"); a stated behaviour, monitored (``sim.containment``: ``accelerated while
    #: overtaken``), never physics
    NO_ACCELERATION = "no-acceleration"


def parse_overtaken(value: object, where: str = "--overtaken") -> Overtaken:
    return parse_choice(Overtaken, value, where)


def passing_windows_s(lane: Lane, actions: Sequence[Action]) -> tuple[tuple[float, float], ...]:
    """When the AV is out of its lane along a plan that starts in ``lane``, on the plan's clock: from the start of each
    move into the passing (right) lane (0 when the plan starts there) to the end of the move back (infinite when
    the plan ends out there). Under ``Overtaken.NO_ACCELERATION`` no measured same-direction vehicle speeds up
    within one; before and after, its dynamics are its own."""
    out, t_s, since = [], 0.0, 0.0 if lane is Lane.RIGHT else None
    for a in actions:
        rule = ACTION_RULES[a]
        if rule.to_lane is Lane.RIGHT and since is None:
            since = t_s
        t_s += float(rule.duration_s)
        if rule.to_lane is Lane.LEFT and since is not None:
            out.append((since, t_s))
            since = None
    if since is not None:
        out.append((since, math.inf))
    return tuple(out)


@dataclass(frozen=True, slots=True)
class Phase:
    """A stretch ``[t0_s, t1_s)`` of constant acceleration of a travel bound: ``travel_m`` covered by ``t0_s`` and the
    speed then (``t1_s`` may be infinite: the last phase lasts for ever)."""

    t0_s: float
    t1_s: float
    travel_m: float
    speed_mps: float
    accel_mps2: float

    def travel(self, t_s: float) -> float:
        s = t_s - self.t0_s
        return self.travel_m + self.speed_mps * s + self.accel_mps2 * s * s / 2

    def speed(self, t_s: float) -> float:
        return self.speed_mps + self.accel_mps2 * (t_s - self.t0_s)


@dataclass(frozen=True, slots=True)
class Dynamics:
    """A vehicle's speed interval at the snapshot (m/s along its direction of travel), its top speed and how fast its
    speed can change."""

    speed_mps: Speed
    top_mps: float
    change: SpeedChange = VEHICLE_SPEED_CHANGE
    #: from this instant on (s after the snapshot) it does not speed up (``Overtaken.NO_ACCELERATION`` within a
    #: passing window); infinite: it may until its top speed
    hold_from_s: float = math.inf

    def __post_init__(self) -> None:
        low, high = self.speed_mps
        if not (math.isfinite(low) and math.isfinite(high)) or low < 0 or low > high:
            raise OptionError("speed_mps", list(self.speed_mps), "must be [low, high] with 0 <= low <= high, finite")
        if not math.isfinite(self.top_mps) or self.top_mps <= 0:
            raise OptionError("top_mps", self.top_mps, "must be above 0 and finite")

    @property
    def slowest(self) -> tuple[Phase, ...]:
        """The least travel: braking at b_max from the lowest speed to a standstill, then standing."""
        return _slowest(self.speed_mps[0], self.change.brake_mps2)

    @property
    def fastest(self) -> tuple[Phase, ...]:
        """The most travel: accelerating at a_max from the highest speed to the top speed (or until ``hold_from_s``),
        then holding the speed reached."""
        return _fastest(self.speed_mps[1], max(self.top_mps, self.speed_mps[1]), self.change.accel_mps2,
                        self.hold_from_s)

    @property
    def highest_mps(self) -> float:
        """The fastest it ever drives."""
        return max(self.top_mps, self.speed_mps[1])

    def travel_m(self, t_s: float) -> tuple[float, float]:
        """The least and the most it can have travelled ``t_s`` after the snapshot."""
        return _at(self.slowest, t_s).travel(t_s), _at(self.fastest, t_s).travel(t_s)

    def speeds_mps(self, t_s: float) -> Speed:
        """The lowest and the highest speed it can have ``t_s`` after the snapshot."""
        return _at(self.slowest, t_s).speed(t_s), _at(self.fastest, t_s).speed(t_s)

    def aged(self, dt_s: float) -> Dynamics:
        """The same vehicle ``dt_s`` later, its speed interval grown by what its speed may change meanwhile (the
        snapshot's age: ``spec.sound.Sound.age_m``)."""
        low, high = self.speeds_mps(dt_s) if dt_s > 0 else self.speed_mps
        return Dynamics((low, high), self.top_mps, self.change, max(0.0, self.hold_from_s - max(0.0, dt_s)))

    def held_from(self, t_s: float) -> Dynamics:
        """The same vehicle, not speeding up from ``t_s`` after the snapshot on (a passing window's start)."""
        return replace(self, hold_from_s=max(0.0, min(t_s, self.hold_from_s)))


def _at(phases: tuple[Phase, ...], t_s: float) -> Phase:
    for p in phases:
        if t_s < p.t1_s:
            return p
    return phases[-1]


@functools.lru_cache(maxsize=4096)
def _slowest(low_mps: float, brake_mps2: float) -> tuple[Phase, ...]:
    if low_mps <= 0:
        return (Phase(0.0, math.inf, 0.0, 0.0, 0.0),)
    stop_s = low_mps / brake_mps2
    return (Phase(0.0, stop_s, 0.0, low_mps, -brake_mps2),
            Phase(stop_s, math.inf, low_mps * low_mps / (2 * brake_mps2), 0.0, 0.0))


@functools.lru_cache(maxsize=4096)
def _fastest(high_mps: float, top_mps: float, accel_mps2: float, hold_from_s: float) -> tuple[Phase, ...]:
    if high_mps >= top_mps or hold_from_s <= 0:
        return (Phase(0.0, math.inf, 0.0, high_mps, 0.0),)
    top_s = min((top_mps - high_mps) / accel_mps2, hold_from_s)
    reached = high_mps + accel_mps2 * top_s
    return (Phase(0.0, top_s, 0.0, high_mps, accel_mps2),
            Phase(top_s, math.inf, (high_mps + reached) / 2 * top_s, reached, 0.0))
