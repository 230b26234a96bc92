"""The tracking layer's rules, each stated once with its reason: what a sweep's readings mean given the tracks so far.

A track is an interval of road positions for one vehicle's centre, grown between sweeps by its lane's speed bounds
(``spec.sound.reach_m``, the sound model's own rule) and narrowed by each reading assigned to it (the reading +- the
sensing error). Under the assumptions a vehicle never leaves that interval, never appears inside the sensors' range
(it enters from beyond it, or from behind another vehicle) and never vanishes where a sensor sees (it leaves the
range, or is hidden); a lane keeps its order. A reading that breaks these is a contradiction, resolved by the rules
below or handed on as such; nothing is hidden from the planner except an appearance the rules still hold.

A track also carries an interval of its vehicle's speed along its direction of travel (set-membership, as CommonRoad's
SPOT and RSS bound a vehicle from its measured state): grown between sweeps by how fast a speed can change
(``SpeedChange``: accelerate at most a_max, brake at most b_max, never below a standstill) and narrowed by each
range-rate reading (the reading +- its error bound). Whenever the error bound and the speed change hold, the vehicle's
speed never leaves it; a reading outside it is the vehicle (or the sensor) breaking them, and the interval starts
again from the reading.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

from spec.errors import OptionError, check_number
from spec.lanes import Lane
from spec.physical import CAR, IDM

#: Floating-point slack on every gate (exact sensing and fixed speeds make intervals of zero width).
GATE_EPS_M = 1e-6
#: An appearance inside the range that nothing explains is held (not planned around, its lane flagged) until it has
#: been seen on this many consecutive sweeps, each inside the interval the one before allows: two sweeps measure a
#: speed, the third checks it against the lane's bounds. Held is not hidden: its lane is flagged meanwhile. While a
#: vehicle of its lane is missing where a sensor sees, an appearance stays held (the two may be one vehicle read in
#: the wrong place). A vehicle missing where a sensor sees is kept, coasting within its bounds, until it has been
#: missing for longer than it had been seen: the longer-lived account of the lane wins. A reading inside both a
#: confirmed track's interval and a held appearance's is the confirmed track's (``sim.tracking``: the ``HELD`` cost).
CONFIRM_SWEEPS = 3


class Explained(enum.Enum):
    """Why a reading no track accounts for is a new vehicle, or why it is not (yet)."""

    FIRST = "first sweep"  # the tracker's first sweep: the picture it starts from
    ENTERED = "entered"  # within one sweep's travel of a sensor's range edge: it came from beyond
    UNHIDDEN = "unhidden"  # where another vehicle hid it on the sweep before (a lane keeps its order)
    APPEARED = "appeared"  # neither: a contradiction (a ghost, a split, a fake gap's displaced reading, a respawn)


class TrackState(enum.Enum):
    """What the planner is told of a track."""

    SEEN = "seen"  # a reading inside its interval this sweep
    HIDDEN = "hidden"  # not read, and another vehicle hides it, or it is beyond the range: kept, not planned around
    MISSING = "missing"  # not read where a sensor sees: a contradiction, kept (coasting within its bounds)
    BROKE_BOUNDS = "broke bounds"  # read just beyond its interval (within one sweep's travel): followed, flagged
    HELD = "held"  # an appearance not yet confirmed: not planned around, its lane flagged

    @property
    def contradiction(self) -> bool:
        return self in (TrackState.MISSING, TrackState.BROKE_BOUNDS, TrackState.HELD)


#: Slack on the speed interval's checks (exact readings of a constant speed make intervals of zero width).
SPEED_EPS_MPS = 1e-9
#: Floating-point slack on a range-rate reading's error bound, as ``GATE_EPS_M`` on a position's (exact readings have
#: none).
RATE_EPS_MPS = 1e-6


@dataclass(frozen=True, slots=True)
class SpeedChange:
    """How fast a vehicle's speed can change (m/s^2, both positive), with the source of each bound."""

    accel_mps2: float
    brake_mps2: float
    source: str

    def __post_init__(self) -> None:
        for name in ("accel_mps2", "brake_mps2"):
            value = check_number(name, getattr(self, name))
            if value <= 0:
                raise OptionError(name, value, "an acceleration bound must be above 0")


#: What every vehicle of the simulated world can do: accelerate like the AV's own car (the same class of car), brake
#: at the world's physical bound (about 0.9 g, the most the traffic models may ask for).
VEHICLE_SPEED_CHANGE = SpeedChange(
    CAR.max_accel_mps2, IDM.max_decel_mps2,
    f"a_max {CAR.max_accel_mps2:g} m/s^2: the car's own limit (spec.physical.CAR.max_accel_mps2); b_max "
    f"{IDM.max_decel_mps2:g} m/s^2: the world's physical bound on braking (spec.physical.IDM.max_decel_mps2)")

Speed = tuple[float, float]  # (lowest, highest) speed along the vehicle's direction of travel, m/s
UNKNOWN_SPEED: Speed = (0.0, math.inf)  # never read: anything from a standstill up


def grown_speed_mps(speed: Speed, dt_s: float, change: SpeedChange = VEHICLE_SPEED_CHANGE) -> Speed:
    """Where a vehicle's speed can be ``dt_s`` later: braked at b_max (never below a standstill) or accelerated at
    a_max."""
    return max(0.0, speed[0] - change.brake_mps2 * dt_s), speed[1] + change.accel_mps2 * dt_s


def read_speed_mps(lane: Lane, rate_mps: float, av_speed_mps: float, error_mps: float) -> Speed:
    """The speeds a range-rate reading allows (how fast the vehicle's distance ahead of the AV grows, +- its error
    bound ``error_mps``) given the AV's own speed along the road: a left-lane vehicle drives the AV's way, an oncoming
    one the other way. Empty (high below low) when the reading says it drives backwards by more than its error."""
    along_mps = av_speed_mps + rate_mps
    speed_mps = along_mps if lane is Lane.LEFT else -along_mps
    return max(0.0, speed_mps - error_mps), speed_mps + error_mps


def narrowed_speed_mps(held: Speed, read: Speed) -> Speed | None:
    """The speeds both allow; None when they share none (the vehicle or the sensor broke its bounds)."""
    lo, hi = max(held[0], read[0]), min(held[1], read[1])
    if lo > hi + SPEED_EPS_MPS:
        return None
    return lo, max(lo, hi)
