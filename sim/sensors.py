"""Ray-cast sensors: the true reading is kept apart from what the planner sees.

A 360-degree sensor of 100 m for the left lane, a front-right long-range sensor of 357 m
and a right-side sensor for the oncoming lane. As in the paper, candidates within range
are found first and a ray (``rayTestBatch``) is cast to each: a vehicle is seen when the
ray reaches it first. ``seen`` is what the planner gets; a fault injector may change it,
never ``truth``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from sim.scene import Scene
from sim.vehicle import KinematicCar
from spec.lanes import Lane
from spec.physical import CAR, SENSORS, SensorSpec


@dataclass(frozen=True, slots=True)
class Reading:
    """One sensed vehicle: its lane, its body, and its distance ahead of the AV along the road (m)."""

    lane: Lane
    body: int
    dx_m: float


@dataclass(frozen=True, slots=True)
class Readings:
    """A sensor sweep: the ground truth within range, and what the sensors report."""

    truth: tuple[Reading, ...]
    seen: tuple[Reading, ...]


def _outside_av(x: float, y: float, end: tuple[float, float, float], z: float) -> tuple[float, float, float]:
    """Where the ray towards ``end`` leaves the AV's chassis: a ray starting inside a body may report it."""
    dx, dy = end[0] - x, end[1] - y
    length = math.hypot(dx, dy) or 1.0
    ux, uy = dx / length, dy / length
    exits = [half / abs(u) for half, u in ((CAR.length_m / 2, ux), (CAR.width_m / 2, uy)) if abs(u) > 1e-9]
    t = min(exits) + 0.05
    return (x + ux * t, y + uy * t, z)


def _right_sensor(x: float, y: float, end: tuple[float, float, float], z: float) -> tuple[float, float, float]:
    """The oncoming lane is watched from the AV's right: its front-right corner looking ahead, its right side
    for what is beside or behind (the paper's front-right and right-side sensors)."""
    side_y = y - CAR.width_m / 2 - 0.05
    if end[0] > x + CAR.length_m / 2:
        return (x + CAR.length_m / 2 + 0.05, side_y, z)
    return (x, side_y, z)


def sweep(scene: Scene, av_x_m: float, av_y_m: float, left: list[KinematicCar], oncoming: list[KinematicCar],
          spec: SensorSpec = SENSORS) -> Readings:
    """Cast one ray to each vehicle in range of its lane's sensor; keep those the ray reaches."""
    candidates = [(Lane.LEFT, car) for car in left if abs(car.x_m - av_x_m) <= spec.left_range_m]
    candidates += [(Lane.RIGHT, car) for car in oncoming
                   if -spec.side_range_m <= car.x_m - av_x_m <= spec.right_range_m]
    truth = tuple(Reading(lane, car.body, car.x_m - av_x_m) for lane, car in candidates)
    if not candidates:
        return Readings((), ())
    ends = [(car.x_m, car.y_m, spec.height_m) for _, car in candidates]
    starts = [_outside_av(av_x_m, av_y_m, end, spec.height_m) if lane is Lane.LEFT
              else _right_sensor(av_x_m, av_y_m, end, spec.height_m) for (lane, _), end in zip(candidates, ends)]
    hits = scene.client.rayTestBatch(starts, ends)
    seen = tuple(r for r, hit in zip(truth, hits, strict=True) if hit[0] == r.body)
    return Readings(truth, seen)
