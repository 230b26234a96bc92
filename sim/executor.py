"""One controller per action: it follows the action's physical mapping from spec/ for its duration.

Longitudinal: a position reference advancing along a speed profile (the action's speed, speed
factor x the common speed, with feasible ramps to its neighbours' speeds); the speed command
adds a correction towards that reference, and the car's wheel motors limit acceleration and
braking. Lateral: a reference that stays on the lane
centre, or for a lane change moves one lane width (a smooth cosine profile) within the
first ``LOOP.lane_change_lateral_s`` of the action's time, since the model puts the AV in its
new lane before any oncoming vehicle moves; tracked by a PD law on the lateral position
turned into a steering angle.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from sim.scene import Scene
from sim.vehicle import WheeledCar
from spec.actions import ACTION_RULES, Action
from spec.errors import EngineError
from spec.grid import Grid
from spec.lanes import Lane
from spec.physical import CAR, LOOP, CarSpec

K_X = 0.8  # 1/s: speed correction per metre behind the position reference
K_Y, K_VY = 3.0, 3.5  # lateral PD gains (1/s^2, 1/s)
MAX_SPEED_FACTOR = 2.4
RAMP_SHARE = 0.9  # reference ramps use this share of the car's limits, leaving some for the feedback


def action_speed_mps(action: Action | None, grid: Grid) -> float:
    """The AV's speed during an action by the physical mapping; None (no action): the common speed."""
    return grid.speed if action is None else float(ACTION_RULES[action].speed_factor) * grid.speed


def ramp_s(v_from_mps: float, v_to_mps: float, spec: CarSpec = CAR) -> float:
    """How long a speed change takes at RAMP_SHARE of the car's acceleration or braking limit."""
    rate = spec.max_accel_mps2 if v_to_mps > v_from_mps else spec.max_brake_mps2
    return abs(v_to_mps - v_from_mps) / (RAMP_SHARE * rate)


def ramp_gain_m(v_from_mps: float, v_to_mps: float) -> float:
    """How far a car ramping from one speed to another gets ahead (negative: behind) of one at the second all along."""
    return (v_from_mps - v_to_mps) * ramp_s(v_from_mps, v_to_mps) / 2


@dataclass(frozen=True, slots=True)
class Ramp:
    """A linear speed change of ``dv_mps`` from ``start_s`` on, over ``duration_s`` (times on a plan's clock)."""

    start_s: float
    duration_s: float
    dv_mps: float

    def at(self, t_s: float) -> float:
        if t_s <= self.start_s:
            return 0.0
        if t_s >= self.start_s + self.duration_s:
            return self.dv_mps
        return self.dv_mps * (t_s - self.start_s) / self.duration_s


@dataclass(frozen=True, slots=True)
class SpeedProfile:
    """The speed reference through one action: a window onto its plan's reference, which is a starting
    speed plus one ramp per boundary between speeds, superposed (so a long ramp may run on into the next
    action, the speed stays continuous, and every ramp keeps its area)."""

    start_mps: float
    ramps: tuple[Ramp, ...]
    offset_s: float = 0.0  # where this action starts on the plan's clock

    def at(self, t_s: float) -> float:
        """The reference speed ``t_s`` into the action."""
        t = self.offset_s + t_s
        return self.start_mps + sum(r.at(t) for r in self.ramps)


def plan_profiles(actions: tuple[Action, ...], start_mps: float, grid: Grid) -> list[SpeedProfile]:
    """One profile per action of a plan: a ramp from the car's speed into the first action, starting now;
    between two actions a ramp centred on their boundary, so the distance lost on one side is made up on
    the other and the car is where the model puts it at every boundary (to within half the ramp's area);
    and a ramp towards the common speed centred on the plan's end (the next plan's frame starts there).
    """
    speeds = [action_speed_mps(a, grid) for a in actions]
    starts, t = [], 0.0
    for action in actions:
        starts.append(t)
        t += float(ACTION_RULES[action].duration_s)
    edges = [(0.0, start_mps, speeds[0], False)]
    edges += [(starts[k], speeds[k - 1], speeds[k], True) for k in range(1, len(speeds))]
    edges += [(t, speeds[-1], grid.speed, True)]
    ramps = tuple(Ramp(at - (ramp_s(v0, v1) / 2 if centred else 0.0), ramp_s(v0, v1), v1 - v0)
                  for at, v0, v1, centred in edges if v1 != v0)
    return [SpeedProfile(start_mps, ramps, start) for start in starts]


def reference_offset_m(speed_mps: float, frame_mps: float, first_mps: float) -> float:
    """Where a plan's position reference starts, ahead of the car: at the AV of the frame the plan was
    made in (``ramp_gain_m`` to the frame's speed), less what the first ramp itself gains on the way to
    the first action's speed (zero in the plan's own frame, where the two are the same)."""
    return ramp_gain_m(speed_mps, frame_mps) - ramp_gain_m(speed_mps, first_mps)


class Executor:
    """Drives the AV through actions; ``tick`` runs after every control step (traffic, contacts)."""

    def __init__(self, scene: Scene, car: WheeledCar, lane: Lane, grid: Grid) -> None:
        self.scene, self.car, self.lane, self.grid = scene, car, lane, grid
        self.x_ref_m = car.pose().x_m
        self.dt_s = scene.dt_s * LOOP.control_every_steps

    def reset_reference(self, ahead_m: float = 0.0) -> None:
        """Start the position reference ``ahead_m`` in front of the car: where the new plan's frame puts it."""
        self.x_ref_m = self.car.pose().x_m + ahead_m

    def run(self, action: Action, tick: Callable[[float], bool], profile: SpeedProfile | None = None) -> bool:
        """Execute ``action`` for its duration along ``profile`` (default: its speed throughout); False as soon
        as ``tick`` reports a collision."""
        rule = ACTION_RULES[action]
        if rule.from_lane is not None and rule.from_lane is not self.lane:
            raise EngineError(f"simulator: {action.value} asked of an AV in the {self.lane.value} lane "
                              f"(its guard needs the {rule.from_lane.value} lane)")
        speed = action_speed_mps(action, self.grid)
        profile = profile or SpeedProfile(speed, ())
        y_from = self.scene.lane_y(self.lane)
        to_lane = rule.to_lane or self.lane
        y_to = self.scene.lane_y(to_lane)
        duration_s = float(rule.duration_s)
        steps = max(1, round(duration_s / self.dt_s))
        lateral_s = min(duration_s, LOOP.lane_change_lateral_s)
        for k in range(steps):
            phase = min(1.0, (k + 1) * self.dt_s / lateral_s)
            y_ref = y_from + (y_to - y_from) * (1 - math.cos(math.pi * phase)) / 2
            vy_ref = (y_to - y_from) * math.pi * math.sin(math.pi * phase) / (2 * lateral_s)
            if not self.control(profile.at(k * self.dt_s), y_ref, vy_ref, tick):
                return False
        self.lane = to_lane
        return True

    def hold(self, seconds: float, speed_mps: float, tick: Callable[[float], bool]) -> bool:
        """Keep the lane at ``speed_mps`` for ``seconds`` (start-up, or waiting without a plan)."""
        y_ref = self.scene.lane_y(self.lane)
        return all(self.control(speed_mps, y_ref, 0.0, tick) for _ in range(max(1, round(seconds / self.dt_s))))

    def control(self, speed_mps: float, y_ref: float, vy_ref: float, tick: Callable[[float], bool]) -> bool:
        pose = self.car.pose()
        self.x_ref_m += speed_mps * self.dt_s
        command = speed_mps + K_X * (self.x_ref_m - pose.x_m)
        command = max(0.0, min(MAX_SPEED_FACTOR * self.grid.speed, command))
        v = max(pose.speed_mps, 1.0)
        vy = v * math.sin(pose.yaw_rad)
        lateral_accel = K_Y * (y_ref - pose.y_m) + K_VY * (vy_ref - vy)
        steer = math.atan(self.car.spec.wheelbase_m * lateral_accel / (v * v))
        for _ in range(LOOP.control_every_steps):
            self.car.command(command, steer, self.scene.dt_s)
            self.scene.step()
        return tick(self.dt_s)

    @staticmethod
    def lane_of(y_m: float) -> Lane:
        """The lane a lateral position is in."""
        return Lane.LEFT if y_m >= 0 else Lane.RIGHT


