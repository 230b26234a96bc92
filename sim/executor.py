"""One controller per action: it follows the action's physical mapping from spec/ for its duration.

Longitudinal: a position reference advancing at the action's speed (speed factor x the
common speed); the speed command adds a correction towards that reference, and the car's
wheel motors limit acceleration and braking. Lateral: a reference that stays on the lane
centre, or moves one lane width over the action's time for a lane change (a smooth
cosine profile), tracked by a PD law on the lateral position turned into a steering angle.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from sim.scene import Scene
from sim.vehicle import WheeledCar
from spec.actions import ACTION_RULES, Action
from spec.constants import DEFAULT_SPEED_MPS
from spec.lanes import Lane
from spec.physical import LOOP

K_X = 0.8  # 1/s: speed correction per metre behind the position reference
K_Y, K_VY = 3.0, 3.5  # lateral PD gains (1/s^2, 1/s)
MAX_SPEED_FACTOR = 2.4


class Executor:
    """Drives the AV through actions; ``tick`` runs after every control step (traffic, contacts)."""

    def __init__(self, scene: Scene, car: WheeledCar, lane: Lane) -> None:
        self.scene, self.car, self.lane = scene, car, lane
        self.x_ref_m = car.pose().x_m
        self.dt_s = scene.dt_s * LOOP.control_every_steps

    def reset_reference(self) -> None:
        """Start the position reference at the car (a new plan starts from where the car is)."""
        self.x_ref_m = self.car.pose().x_m

    def run(self, action: Action, tick: Callable[[float], bool]) -> bool:
        """Execute ``action`` for its duration; False as soon as ``tick`` reports a collision."""
        rule = ACTION_RULES[action]
        speed = float(rule.speed_factor) * DEFAULT_SPEED_MPS
        y_from = self.scene.lane_y(self.lane)
        to_lane = rule.to_lane or self.lane
        y_to = self.scene.lane_y(to_lane)
        steps = max(1, round(rule.duration_s / self.dt_s))
        for k in range(steps):
            phase = (k + 1) / steps
            y_ref = y_from + (y_to - y_from) * (1 - math.cos(math.pi * phase)) / 2
            vy_ref = (y_to - y_from) * math.pi * math.sin(math.pi * phase) / (2 * rule.duration_s)
            if not self.control(speed, y_ref, vy_ref, tick):
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
        command = max(0.0, min(MAX_SPEED_FACTOR * DEFAULT_SPEED_MPS, command))
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


