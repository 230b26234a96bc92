"""Safety measured, not only collisions: gaps and times to collision in the AV's lane, near misses, and the gap the
model's cells implied at each of them beside the true one (the abstraction's error where it mattered).

On every control step the monitor looks at the vehicle ahead of the AV in the lane the AV is in:
in the left lane the nearest same-direction vehicle ahead, in the right lane the nearest oncoming
one. Gaps are bumper to bumper; the time to collision is the gap over the closing speed (infinite
when not closing). A near miss is a gap that breaks the one safety specification
(``spec.safety``: below ``max(min_gap_m, time_gap_s x closing speed)``, which is a gap below 2 m or
a time to collision below 1.5 s); one event lasts while the condition holds for one
vehicle and keeps its worst values. The implied gap is where the plan under way puts that vehicle
at the end of the current action (its predicted cell's centre), or None outside a plan or for a
vehicle the plan does not track.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

from sim.vehicle import KinematicCar, Pose
from spec.lanes import Lane
from spec.physical import CAR
from spec.safety import SAFETY, SafetySpec

#: Near-miss and contact records kept per run (the counts are exact beyond it).
MAX_RECORDS = 100
#: Which rule of the model should have kept that vehicle away, by the lane it is in.
RULE = {Lane.LEFT: "left-lane collision (the AV's cell)", Lane.RIGHT: "oncoming danger zone"}


@dataclass(slots=True)
class Encounter:
    """A near miss or a contact: where, with what, what the AV was doing, true and implied gaps."""

    kind: str  # "near_miss" or "contact"
    km: float
    t_s: float
    lane: str  # the lane of the other vehicle
    rule: str
    doing: str
    gap_m: float  # the smallest true gap during the event
    ttc_s: float  # the smallest time to collision during the event (inf: never closing)
    implied_gap_m: float | None  # the gap the plan's cells implied when the event started
    #: inside the drive's assumptions or after one broke (``sim.containment``), when the event started; None: no bounds
    assumptions: str | None = None

    def to_json(self) -> dict[str, Any]:
        data = asdict(self)
        for key in ("gap_m", "ttc_s", "implied_gap_m"):
            value = data[key]
            data[key] = None if value is None or not math.isfinite(value) else round(value, 2)
        return data

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> Encounter:
        return cls(**{**data, "ttc_s": math.inf if data["ttc_s"] is None else data["ttc_s"]})


@dataclass(slots=True)
class SafetyReport:
    """One run's safety figures."""

    min_gap_left_m: float = math.inf  # to the vehicle ahead while the AV is in the left lane
    min_ttc_left_s: float = math.inf
    min_gap_oncoming_m: float = math.inf  # to the oncoming vehicle ahead while the AV is in the right lane
    min_ttc_oncoming_s: float = math.inf
    near_misses: int = 0
    contacts: int = 0
    encounters: list[Encounter] = field(default_factory=list)  # the first MAX_RECORDS of them
    #: exact counts of near misses and contacts by attribution: "near_miss inside", "contact after", ...
    attributed: dict[str, int] = field(default_factory=dict)

    def count(self, kind: str, inside: bool) -> int:
        """Near misses or contacts (``kind``) inside the assumptions, or after one broke."""
        return self.attributed.get(attribution_key(kind, inside), 0)

    def to_json(self) -> dict[str, Any]:
        def num(v: float) -> float | None:
            return round(v, 2) if math.isfinite(v) else None

        return {"min_gap_left_m": num(self.min_gap_left_m), "min_ttc_left_s": num(self.min_ttc_left_s),
                "min_gap_oncoming_m": num(self.min_gap_oncoming_m),
                "min_ttc_oncoming_s": num(self.min_ttc_oncoming_s), "near_misses": self.near_misses,
                "contacts": self.contacts, "encounters": [e.to_json() for e in self.encounters],
                "attributed": self.attributed}

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> SafetyReport:
        def num(v: float | None) -> float:
            return math.inf if v is None else v

        return cls(num(data["min_gap_left_m"]), num(data["min_ttc_left_s"]), num(data["min_gap_oncoming_m"]),
                   num(data["min_ttc_oncoming_s"]), data["near_misses"], data["contacts"],
                   [Encounter.from_json(e) for e in data["encounters"]], dict(data.get("attributed", {})))


def ahead_in_lane(pose: Pose, lane: Lane, left: Sequence[KinematicCar],
                  oncoming: Sequence[KinematicCar]) -> tuple[KinematicCar | None, float, float]:
    """The vehicle ahead of the AV in ``lane``, its bumper-to-bumper gap and the closing speed."""
    cars = left if lane is Lane.LEFT else oncoming
    ahead = [c for c in cars if c.x_m > pose.x_m]
    if not ahead:
        return None, math.inf, 0.0
    car = min(ahead, key=lambda c: c.x_m)
    return car, car.x_m - pose.x_m - CAR.length_m, pose.along_mps - car.velocity_mps


class SafetyMonitor:
    """Watches every control step and keeps a ``SafetyReport``."""

    def __init__(self, spec: SafetySpec = SAFETY) -> None:
        self.spec, self.report = spec, SafetyReport()
        self._open: dict[int, Encounter] = {}  # body -> the near miss under way with it

    def forget(self) -> None:
        """Close every near miss under way (a new scene: its vehicles are new bodies)."""
        self._open.clear()

    def observe(self, pose: Pose, lane: Lane, left: Sequence[KinematicCar], oncoming: Sequence[KinematicCar],
                km: float, t_s: float, doing: str, implied_gap_m: Callable[[int], float | None],
                assumptions: Callable[[int], str | None] = lambda body: None) -> None:
        car, gap, closing = ahead_in_lane(pose, lane, left, oncoming)
        ttc = gap / closing if closing > 0 and gap > 0 else (0.0 if gap <= 0 else math.inf)
        r = self.report
        if lane is Lane.LEFT:
            r.min_gap_left_m, r.min_ttc_left_s = min(r.min_gap_left_m, gap), min(r.min_ttc_left_s, ttc)
        else:
            r.min_gap_oncoming_m, r.min_ttc_oncoming_s = min(r.min_gap_oncoming_m, gap), min(r.min_ttc_oncoming_s, ttc)
        near = car is not None and self.spec.violated(gap, closing)
        for body in [b for b in self._open if car is None or b != car.body or not near]:
            del self._open[body]
        if not near or car is None:
            return
        event = self._open.get(car.body)
        if event is None:
            event = Encounter("near_miss", round(km, 3), round(t_s, 1), _lane_name(lane), RULE[lane], doing, gap,
                              ttc, implied_gap_m(car.body), assumptions(car.body))
            self._open[car.body] = event
            r.near_misses += 1
            self._keep(event)
        event.gap_m, event.ttc_s = min(event.gap_m, gap), min(event.ttc_s, ttc)

    def contact(self, car: KinematicCar, lane: Lane, pose: Pose, km: float, t_s: float, doing: str,
                implied_gap_m: float | None, assumptions: str | None = None) -> Encounter:
        """A collision with ``car`` (in ``lane``): recorded with the gap its cells implied and its attribution."""
        gap = abs(car.x_m - pose.x_m) - CAR.length_m
        event = Encounter("contact", round(km, 3), round(t_s, 1), _lane_name(lane), RULE[lane], doing, gap, 0.0,
                          implied_gap_m, assumptions)
        self.report.contacts += 1
        self._keep(event)
        return event

    def _keep(self, event: Encounter) -> None:
        if event.assumptions is not None:
            key = attribution_key(event.kind, event.assumptions.startswith("inside"))
            self.report.attributed[key] = self.report.attributed.get(key, 0) + 1
        if len(self.report.encounters) < MAX_RECORDS:
            self.report.encounters.append(event)


def attribution_key(kind: str, inside: bool) -> str:
    """How ``SafetyReport.attributed`` counts an encounter: "contact inside", "near_miss after", ..."""
    return f"{kind} {'inside' if inside else 'after'}"


def _lane_name(lane: Lane) -> str:
    return "left" if lane is Lane.LEFT else "oncoming"
