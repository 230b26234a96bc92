"""The AV's controller as pure functions of its references and the car's state: each control step's speed and
steering commands, the lateral reference of a sideways move, and where a proved sequence's position reference stands
when it is resumed; and the loop that runs a decision's control steps (``Steps``) against a world (``perform``).
``sim.executor`` applies the commands to the car, step by step.

Longitudinal: the speed command adds a correction towards the position reference, divided by the cosine of the
car's heading (the reference is a speed along the road, and a car turned sideways covers less of it). Lateral: a PD
law on the lateral position turned into a steering angle, less the sideways part of the car's own speeding up or
braking (a lane change from a slow queue ramps to its action's speed while the car is turned by 30 degrees and more:
without it the car ran on past the new lane's centre to the road's edge)."""

from __future__ import annotations

import math
from collections.abc import Callable, Generator
from dataclasses import dataclass

from spec.actions import ACTION_RULES, Action
from spec.envelope import TRACKING
from spec.lanes import Lane
from spec.motion import SpeedProfile
from spec.physical import ROAD

#: One control step's references: the speed along the road (m/s), the lateral position (m) and its rate (m/s).
Command = tuple[float, float, float]
#: What the AV does over control steps: each step's references, told after each whether the world's step went on
#: (False: a collision or a loss of control, and no step follows); returns whether every step did.
Steps = Generator[Command, bool, bool]

K_X = 0.8  # 1/s: speed correction per metre behind the position reference
K_Y, K_VY = 3.0, 3.5  # lateral PD gains (1/s^2, 1/s)
MAX_SPEED_FACTOR = 2.4  # the speed command is at most this times the common speed
MIN_HEADING_COS = 0.5  # the heading's correction of the speed command is at most 2x (a car turned by 60 degrees)


@dataclass(frozen=True, slots=True)
class CarState:
    """The car's own state as its odometry gives it: position (m), heading (rad) and speed along it (m/s), and its
    speed one control step before (m/s)."""

    x_m: float
    y_m: float
    yaw_rad: float
    speed_mps: float
    speed_before_mps: float


def control_law(car: CarState, x_ref_m: float, speed_mps: float, y_ref_m: float, vy_ref_mps: float, dt_s: float,
            common_mps: float, wheelbase_m: float, steer_offset_rad: float = 0.0) -> tuple[float, float]:
    """One control step's (speed command in m/s, steering angle in rad): towards the position reference ``x_ref_m``
    (already advanced for this step) at the reference speed ``speed_mps``, and towards the lateral reference
    ``y_ref_m`` moving at ``vy_ref_mps``; a steering fault adds its ``steer_offset_rad``."""
    # the reference is a speed along the road: turned sideways, the car drives faster along its heading to keep it
    speed = (speed_mps + K_X * (x_ref_m - car.x_m)) / max(MIN_HEADING_COS, math.cos(car.yaw_rad))
    speed = max(0.0, min(MAX_SPEED_FACTOR * common_mps, speed))
    v = max(car.speed_mps, 1.0)
    vy = v * math.sin(car.yaw_rad)
    # a car turned sideways that speeds up moves sideways faster without turning: the turn asked for is the rest
    speeding_up = (car.speed_mps - car.speed_before_mps) / dt_s  # over the last control step
    lateral_accel = K_Y * (y_ref_m - car.y_m) + K_VY * (vy_ref_mps - vy) - speeding_up * math.sin(car.yaw_rad)
    return speed, math.atan(wheelbase_m * lateral_accel / (v * v)) + steer_offset_rad


def perform(steps: Steps, step: Callable[[Command], bool]) -> bool:
    """Run ``steps``: each command goes to ``step`` (the world applies it and says whether it went on), whose answer
    the steps are told; their return value is the answer. Should ``step`` raise, the steps are closed first, so their
    own ``finally`` clauses run while the world they speak of is still there."""
    try:
        command = next(steps)
        while True:
            command = steps.send(step(command))
    except StopIteration as done:
        return bool(done.value)
    finally:
        steps.close()


def cosine_move(y_from_m: float, y_to_m: float, phase: float, seconds: float) -> tuple[float, float]:
    """The lateral reference and its rate at ``phase`` (0 to 1) of a smooth cosine move over ``seconds``."""
    return (y_from_m + (y_to_m - y_from_m) * (1 - math.cos(math.pi * phase)) / 2,
            (y_to_m - y_from_m) * math.pi * math.sin(math.pi * phase) / (2 * seconds))


@dataclass(frozen=True, slots=True)
class Sideways:
    """A sideways move a decision took over mid-way (``Executor.acting``'s ``hand_over``): the lateral reference goes
    on along a cosine from ``y_from_m`` to ``y_to_m`` over ``seconds``, ``done_s`` of it run, whatever the speed
    reference does meanwhile. Finished, the original move goes on where it was; undone, it goes back on a cosine of
    the time it had taken (``MinimalRisk``'s cut-short move)."""

    y_from_m: float
    y_to_m: float
    seconds: float
    done_s: float

    @property
    def left_s(self) -> float:
        """How long it still keeps the AV moving sideways."""
        return max(0.0, self.seconds - self.done_s)

    def now(self) -> tuple[float, float]:
        """The lateral reference and its rate where the move stands."""
        return cosine_move(self.y_from_m, self.y_to_m, min(1.0, self.done_s / self.seconds), self.seconds)

    def step(self, dt_s: float) -> tuple[float, float, Sideways | None]:
        """One control step of it: the lateral reference and its rate, and what is left (None: it is over)."""
        later = Sideways(self.y_from_m, self.y_to_m, self.seconds, self.done_s + dt_s)
        y_m, vy_mps = later.now()
        return y_m, vy_mps, None if later.done_s >= self.seconds * (1.0 - 1e-9) else later


def resumed(action: Action, profile: SpeedProfile, due_s: float, ref_then_m: float, now_s: float,
            dt_s: float) -> tuple[float, float]:
    """A proved ``action`` resumed late: it was due at ``due_s`` with its position reference at ``ref_then_m``, and the
    control steps since went by at the reference speed the AV held. Returns (seconds of the action already gone by,
    whole control steps, at most all but its last; where its position reference stands now along ``profile``), so
    the reference is where the proof's is and goes on on the proof's clock."""
    last_s = float(ACTION_RULES[action].duration_s) - dt_s  # at least its last control step is run
    skip_s = min(round((now_s - due_s) / dt_s) * dt_s, last_s)
    return skip_s, ref_then_m + profile.distance_m(skip_s) - profile.distance_m(0.0)


def held_reference(x_ref_m: float, x_m: float) -> float:
    """Where the position reference stands when the AV drives on in lane at the common speed for a sweep: where it
    is, while the car at ``x_m`` is within its stated envelope of it (``TRACKING.position_m``), so a series of such
    sweeps holds the common speed in position too; else at the car. Restarted at the car every sweep, the speed
    command alone let the car creep 0.16 m/s faster than the traffic into the vehicle ahead (measured, seed 2)."""
    return x_ref_m if abs(x_ref_m - x_m) <= TRACKING.position_m else x_m


def lane_of(y_m: float) -> Lane:
    """The lane a lateral position is in."""
    return Lane.LEFT if y_m >= 0 else Lane.RIGHT


def lane_y(lane: Lane) -> float:
    """The y of a lane's centre line."""
    half = ROAD.lane_width_m / 2
    return half if lane is Lane.LEFT else -half


def until_sweep(swept: Callable[[], bool], speed_mps: float, y_ref_m: float) -> Steps:
    """Hold the lane centred at ``y_ref_m`` at ``speed_mps`` until the sensors' next sweep (``swept``, asked after each
    step; at most two control steps: an action whose time is not a whole number of sweeps, as on 5.25 m cells), so a
    decision's snapshot is never older than the car's pose; False on a collision."""
    while not swept():
        if not (yield speed_mps, y_ref_m, 0.0):
            return False
    return True
