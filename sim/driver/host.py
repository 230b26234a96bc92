"""What a driver reads, moves and reports through (``Host``): the world that runs it, as the decision layer sees it.
The simulator implements it (``sim.simulator.Simulator``); tests implement it with a scripted world. Each model's
driver asks a little more of it (``sim.driver.sound.SoundHost``, ``sim.driver.paper.PaperHost``)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from sim.driver.control import Sideways, Steps, lane_of
from sim.driver.readings import Reading
from spec.actions import Action
from spec.answers import Answer
from spec.kinds import FailureKind
from spec.lanes import Lane
from spec.motion import SpeedProfile
from spec.scenario import Scenario


class Odometry(Protocol):
    """The car's own position (m) and speed along the road (m/s), as its odometry gives them."""

    @property
    def x_m(self) -> float: ...

    @property
    def y_m(self) -> float: ...

    @property
    def along_mps(self) -> float: ...


class Controls(Protocol):
    """The AV's controller as a decision moves it (``sim.executor.Executor``): its references and its control steps."""

    lane: Lane  # the lane the action under way started in
    lane_due: Lane | None  # the lane the car must be wholly in now (None: a sideways move under way)
    x_ref_m: float  # the position reference
    sideways: Sideways | None  # a sideways move a decision took over mid-way, until it is over

    @property
    def v_ref_mps(self) -> float: ...

    @property
    def dt_s(self) -> float: ...

    def reset_reference(self, ahead_m: float = 0.0) -> None: ...

    def acting(self, action: Action, profile: SpeedProfile | None = None, stop: Callable[[], bool] | None = None,
               skip_s: float = 0.0, reverse: Callable[[Lane, float, float], bool] | None = None,
               hand_over: Callable[[Lane, float, float], Lane | None] | None = None) -> Steps: ...

    def holding(self, seconds: float, speed_mps: float) -> Steps: ...


class Counts(Protocol):
    """The drive's clock and the counters every decision adds to (``sim.summary.RunSummary``)."""

    plans: int
    actions: int
    replans: int

    @property
    def km(self) -> float: ...

    @property
    def sim_time_s(self) -> float: ...


class Host(Protocol):
    """The world that runs a driver: what it reads (the car's odometry, the sensors' last sweep), what it moves (the
    controller), and the bookkeeping it reports to."""

    doing: str  # what the AV is doing: recorded with every event

    @property
    def executor(self) -> Controls: ...

    @property
    def summary(self) -> Counts: ...

    @property
    def sweep(self) -> tuple[Reading, ...] | None: ...  # the sensors' last sweep (None: it was dropped)

    def pose(self) -> Odometry: ...

    def swept(self) -> bool: ...  # whether the sensors swept at the end of this control step

    def decided(self, lane: Lane) -> None: ...  # a decision is taken in ``lane`` from the last sweep

    def contain_from(self, readings: tuple[Reading, ...], av_x_m: float, lane: Lane, view_m: float | None = None,
                     sensed_sets: bool = False, read: tuple[Reading, ...] | None = None) -> None:
        ...  # the sets a new decision is measured against (``read``: what they were narrowed from)

    def planned(self, answer: Answer, scenario: Scenario, lane: Lane) -> None: ...

    def refused(self, actions: tuple[Action, ...], under_way: tuple[Action, ...]) -> bool: ...  # the tracker's say

    def sight(self, readings: tuple[Reading, ...], av_x_m: float, t_s: float | None = None) -> None: ...

    def sensed_anew(self) -> bool: ...  # the last sweep shows a vehicle the plan under way was not made knowing

    def fail(self, kind: FailureKind, cause: str, detail: str) -> None: ...

    def kept(self, kind: FailureKind, cause: str, detail: str) -> None: ...  # a plan under way kept without a plan


def lane_now(executor: Controls, pose: Odometry) -> Lane:
    """The lane the AV is in for a decision: the one its centre is in, or during a sideways move a decision took
    over, the lane the move goes to."""
    return executor.lane if executor.sideways is not None else lane_of(pose.y_m)


def start_decision(host: Host) -> tuple[Odometry, Lane]:
    """What every decision does first: the car's pose, and the lane it is in, where the controller's next action
    starts (during a sideways move a decision took over, the lane the move goes to); the host hears that a decision
    is taken there."""
    pose = host.pose()
    lane = lane_now(host.executor, pose)
    host.executor.lane = lane
    host.decided(lane)
    return pose, lane
