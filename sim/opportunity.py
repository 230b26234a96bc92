"""Missed opportunities: where the planner found no overtake, would one have succeeded in physics?

The definition the audit measures. A decision *qualifies* when the AV is in its own (left)
lane, the truth has a left-lane vehicle ahead within the left sensor's range (the *target*),
and the planner does not start an overtake now, for one of three reasons (``Refusal``): the
final model (the one that plans overtakes) answers no plan, proved or within the horizon
(``refused``); it plans an overtake that starts later, after waiting or preparing
(``delayed``); or the model's window holds nothing to overtake although the sensor sees the
target (``outside_window``). For a
checked decision the world is saved and the canonical overtakes are replayed in it, open loop,
on the same physics and the same traffic model: change to the right lane, accelerate ``m``
times (``m`` = 1 .. ``MAX_ACCELERATES``), change back, then keep the lane for ``LOOP.wait_s``.
A refused or outside-window decision is a *missed opportunity* when one of them succeeds (a
delayed one, a *delayed overtake*: the planner did find one): no contact and no near miss
(``spec.safety.SafetySpec``, the audit's own thresholds; a near miss already under way with
the same vehicle when the decision was taken is not the overtake's) at any moment of the
replay, the AV back in its own lane, and the target behind the AV by at least the near-miss
gap. The world is then put back exactly as it was (PyBullet's state, the traffic model's
vehicles and generator, the AV's wheel command), so the drive goes on as though nothing had
been tried.

Replays cost about 0.15 s of wall time per decision (a drive makes 5 or so qualifying
decisions per km), so each qualifying decision is checked with probability ``SAMPLE`` (from its
own random stream, ``[seed, 2]``) up to a budget per run (once the budget is spent, later
decisions of that run go unchecked: a long run's sample leans to its start); every
qualifying decision is counted, so missed opportunities per km are estimated as
missed / checked x qualifying / km, per reason.
"""

from __future__ import annotations

import copy
from collections import Counter
from dataclasses import asdict, dataclass, field
from enum import Enum
from typing import Any

from sim.driver.decide import NO_OVERTAKE
from sim.executor import Executor
from sim.safety import SafetyMonitor
from sim.scene import Scene
from sim.traffic import TrafficModel
from sim.vehicle import KinematicCar, WheeledCar, first_contact
from spec.actions import Action
from spec.answers import Answer, Status
from spec.grid import Grid
from spec.lanes import Lane
from spec.models import ModelKind
from spec.motion import SpeedProfile, plan_profiles
from spec.physical import CAR, LOOP, SENSORS
from spec.safety import SAFETY

MAX_ACCELERATES = 6  # 18 s at twice the common speed: 126 m gained on a vehicle at 7 m/s
SAMPLE = 0.25  # the share of qualifying decisions replayed (a quarter: about +10% on a drive's wall time)
STREAM = 2  # the second word of the sampling stream's seed: [seed, 2]
MAX_RECORDS = 20  # missed opportunities kept per run with their scenario (the counts are exact beyond it)


class Refusal(Enum):
    """Why the planner did not start an overtake at a qualifying decision."""

    REFUSED = "refused"  # the final model found no plan
    DELAYED = "delayed"  # the final model's plan starts its overtake later
    OUTSIDE_WINDOW = "outside_window"  # the sensed target is not in the model's window: nothing to overtake


class Outcome(Enum):
    """How the longest overtake tried at one decision ended (or that one succeeded)."""

    MISSED = "missed"  # an overtake succeeded in physics: the planner missed it
    CONTACT = "contact"
    NEAR_MISS = "near_miss"
    NOT_PASSED = "target_not_passed"


def overtake(accelerates: int) -> tuple[Action, ...]:
    """The canonical overtake with ``accelerates`` steps at twice the common speed in the right lane."""
    return (Action.RIGHT_LANE_CHANGE,) + (Action.ACCELERATE,) * accelerates + (Action.LEFT_LANE_CHANGE,)


@dataclass(slots=True)
class Opportunity:
    """One missed opportunity: where, the planner's answer and scenario, and the overtake that succeeded."""

    km: float
    t_s: float
    refusal: str  # why the planner did not start an overtake (``Refusal``)
    answer: str  # the planner's first actions, or the final model's status
    accelerates: int
    target_gap_m: float  # bumper to bumper, when the decision was taken
    scenario: dict[str, Any]  # what the planner was asked, as a scenario file writes it

    def to_json(self) -> dict[str, Any]:
        return {**asdict(self), "target_gap_m": round(self.target_gap_m, 2)}


@dataclass(slots=True)
class OpportunityReport:
    """One run's decisions without an overtake, per ``Refusal``: how many qualified ("qualifying"), how many were
    checked ("checked"), and how the checks ended (one count per ``Outcome``)."""

    counts: dict[str, Counter[str]] = field(default_factory=dict)
    missed: list[Opportunity] = field(default_factory=list)  # the first MAX_RECORDS

    def count(self, refusal: Refusal, what: str) -> None:
        self.counts.setdefault(refusal.value, Counter())[what] += 1

    def total(self, what: str) -> int:
        """Over every refusal: "qualifying", "checked" or an ``Outcome`` value."""
        return sum(c[what] for c in self.counts.values())

    def to_json(self) -> dict[str, Any]:
        return {"counts": {k: dict(v) for k, v in self.counts.items()}, "missed": [o.to_json() for o in self.missed]}

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> OpportunityReport:
        return cls({k: Counter(v) for k, v in data["counts"].items()}, [Opportunity(**o) for o in data["missed"]])


class WorldSave:
    """The whole world at one moment, to put back after a what-if replay."""

    def __init__(self, scene: Scene, car: WheeledCar, traffic: TrafficModel) -> None:
        self.scene, self.car, self.traffic = scene, car, traffic
        self.state_id = scene.client.saveState()
        self.wheel_target_mps = car.wheel_target_mps
        self.traffic_state = traffic.save()

    def restore(self) -> None:
        self.scene.client.restoreState(stateId=self.state_id)
        self.car.wheel_target_mps = self.wheel_target_mps
        self.traffic.restore(self.traffic_state)

    def discard(self) -> None:
        """Free the saved physics state (the world stays as it is)."""
        self.scene.client.removeState(self.state_id)

    def close(self) -> None:
        self.restore()
        self.discard()


def target_ahead(av_x_m: float, left: list[KinematicCar]) -> KinematicCar | None:
    """The nearest left-lane vehicle ahead within the left sensor's range: what an overtake would pass."""
    ahead = [c for c in left if 0 < c.x_m - av_x_m <= SENSORS.left_range_m]
    return min(ahead, key=lambda c: c.x_m) if ahead else None


class Replay:
    """Canonical overtakes replayed from one saved moment (see the module's docstring)."""

    def __init__(self, scene: Scene, car: WheeledCar, traffic: TrafficModel, grid: Grid) -> None:
        self.scene, self.car, self.traffic, self.grid = scene, car, traffic, grid

    def first_success(self, target: KinematicCar) -> tuple[Outcome, int]:
        """The outcome of the shortest overtake that succeeds (and its accelerates), or of the longest tried.

        Overtakes share their start (a lane change, then accelerating), so one that fails before its return
        ends the search: every longer one fails there too. The shared start is driven once: the overtake with
        ``m`` accelerates goes on from a checkpoint after the lane change and ``m - 1`` of them (the speed
        reference up to there does not depend on ``m``: the ramp back to the common speed starts within the
        last accelerate), and the checkpoint for ``m + 1`` is that one driven on through one more accelerate."""
        start = WorldSave(self.scene, self.car, self.traffic)
        speed_mps = self.car.pose().along_mps
        attempt = _Attempt(self, target)
        checkpoint: _Checkpoint | None = None
        outcome = Outcome.NOT_PASSED
        profiles = plan_profiles(overtake(1), speed_mps, self.grid)
        try:
            if not attempt.run(Action.RIGHT_LANE_CHANGE, profiles[0]):
                return attempt.failed[0], 0
            for accelerates in range(1, MAX_ACCELERATES + 1):
                checkpoint = attempt.save()  # the lane change and accelerates - 1 accelerates behind
                outcome, in_return = attempt.finish(profiles[accelerates:])
                if outcome is Outcome.MISSED:
                    return outcome, accelerates
                if (outcome is not Outcome.NOT_PASSED and not in_return) or accelerates == MAX_ACCELERATES:
                    break
                attempt.restore(checkpoint)
                checkpoint.world.discard()
                checkpoint = None
                profiles = plan_profiles(overtake(accelerates + 1), speed_mps, self.grid)
                if not attempt.run(Action.ACCELERATE, profiles[accelerates]):
                    return attempt.failed[0], 0  # the longer overtakes fail before their return
        finally:
            if checkpoint is not None:
                checkpoint.world.discard()
            start.close()
        return outcome, 0


@dataclass(slots=True)
class _Checkpoint:
    """An overtake part-way: the world, and where its controller and safety monitor stood."""

    world: WorldSave
    x_ref_m: float
    lane: Lane
    monitor: SafetyMonitor
    first: bool


class _Attempt:
    """One overtake being driven in a replay: its controller, and a safety monitor that ends it at the first
    contact or new near miss."""

    def __init__(self, replay: Replay, target: KinematicCar) -> None:
        self.scene, self.car, self.traffic = replay.scene, replay.car, replay.traffic
        self.target, self.respawns = target, target.respawns
        self.executor = Executor(replay.scene, replay.car, Lane.LEFT, replay.grid)
        self.monitor = SafetyMonitor(SAFETY)
        self.first = True  # a near miss open on the first step was under way before the overtake began
        self.failed: list[Outcome] = []

    def tick(self, dt_s: float) -> bool:
        pose = self.car.pose()
        self.traffic.advance(dt_s, pose)
        if first_contact(self.scene, self.car.body, self.traffic.cars()) is not None:
            self.failed.append(Outcome.CONTACT)
            return False
        before = self.monitor.report.near_misses
        self.monitor.observe(pose, Executor.lane_of(pose.y_m), self.traffic.left, self.traffic.oncoming,
                             0.0, 0.0, "", lambda body: None)
        if not self.first and self.monitor.report.near_misses > before:
            self.failed.append(Outcome.NEAR_MISS)
            return False
        self.first = False
        self.traffic.respawn_behind(pose.x_m)
        return True

    def run(self, action: Action, profile: SpeedProfile) -> bool:
        return self.executor.run(action, self.tick, profile)

    def finish(self, profiles: list[SpeedProfile]) -> tuple[Outcome, bool]:
        """Drive the last accelerate and the return (``profiles``: theirs), then keep the lane; the outcome, and
        whether a failure came only in the return (the lane change back or the hold after it)."""
        if not self.run(Action.ACCELERATE, profiles[0]):
            return self.failed[0], False
        back_in_lane = self.run(Action.LEFT_LANE_CHANGE, profiles[1])
        if not back_in_lane or not self.executor.hold(LOOP.wait_s, self.executor.grid.speed, self.tick):
            return self.failed[0], True
        pose = self.car.pose()
        behind_m = pose.x_m - CAR.length_m - SAFETY.min_gap_m
        passed = self.target.respawns != self.respawns or self.target.x_m < behind_m
        back = Executor.lane_of(pose.y_m) is Lane.LEFT
        return (Outcome.MISSED, False) if passed and back else (Outcome.NOT_PASSED, True)

    def save(self) -> _Checkpoint:
        return _Checkpoint(WorldSave(self.scene, self.car, self.traffic), self.executor.x_ref_m, self.executor.lane,
                           copy.deepcopy(self.monitor), self.first)

    def restore(self, checkpoint: _Checkpoint) -> None:
        checkpoint.world.restore()
        self.executor.x_ref_m, self.executor.lane = checkpoint.x_ref_m, checkpoint.lane
        self.monitor, self.first = copy.deepcopy(checkpoint.monitor), checkpoint.first
        self.failed.clear()


def refusal(answer: Answer) -> Refusal | None:
    """Why ``answer`` does not start an overtake now, or None when it does (or could not tell: incomplete)."""
    if any(kind is ModelKind.FINAL and status in NO_OVERTAKE for kind, status, _ in answer.stages):
        return Refusal.REFUSED
    if answer.status is not Status.PLAN:
        return None
    if not answer.actions:
        return Refusal.OUTSIDE_WINDOW
    return None if answer.actions[0] is Action.RIGHT_LANE_CHANGE else Refusal.DELAYED
