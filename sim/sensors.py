"""Ray-cast sensors: the true reading is kept apart from what the planner sees.

A 360-degree sensor of 100 m for the left lane, a front-right long-range sensor of 357 m
and a right-side sensor for the oncoming lane. The simulator finds the ground truth (every
vehicle within range, ``in_range``) and hands it to its sensor model, one part of a
simulator (``sim.parts``), whose ``read(truth)`` is what the planner sees; the truth is
never changed. The paper's sensor (``RaySensor``) casts a ray (``rayTestBatch``) to each
vehicle and reports those the ray reaches first.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Protocol

import numpy as np

from sim.driver.readings import Reading
from sim.scene import Scene
from sim.vehicle import KinematicCar
from spec.lanes import Lane
from spec.physical import CAR, NOISE, SENSORS, NoiseSpec, SensorSpec


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


def oncoming_view_m(readings: tuple[Reading, ...], av_y_m: float, error_m: float,
                    spec: SensorSpec = SENSORS) -> float | None:
    """Where the front-right sensor's view of the oncoming lane is first blocked by a sensed left-lane vehicle,
    metres ahead of the AV (None: nothing sensed blocks it within range): the snapshot's oncoming phantom stands there
    (``spec.sound.Sound.oncoming_view_m``), so a plan is safe against a vehicle anywhere in the hidden stretch.

    The sensor sees a vehicle when the ray from the AV's front-right corner to the vehicle's centre reaches it first
    (``RaySensor``); a left-lane vehicle ahead hides the oncoming lane's centres beyond the point where that ray
    first touches its body (the body widened by the sensing error ``error_m``: its reading may be that far off). A
    vehicle hidden there is no vehicle a decision could know, and no phantom at the sensor's range covers it
    (measured: the AV ended a lane change 0.5 m left of its lane's centre, the vehicle it had just passed hid an
    oncoming one 64 m ahead, and the next decision started an overtake towards it). One oncoming vehicle at the
    shadow's start would not do (the first version): it passes before a lane change that one hidden farther off
    meets (seed 19 of the reliability campaign, ``tests/sim/test_world.py``)."""
    sx, sy, _ = _right_sensor(0.0, av_y_m, (math.inf, 0.0, 0.0), 0.0)  # the front-right sensor, from the AV's centre
    ty, body_low = Scene.lane_y(Lane.RIGHT), Scene.lane_y(Lane.LEFT) - CAR.width_m / 2
    if sy <= body_low or sy <= ty:
        return None  # the sensor looks from below the left lane's bodies: they hide nothing of the oncoming lane
    starts = []
    for r in readings:
        if r.lane is not Lane.LEFT or r.interval_m[1] + error_m + CAR.length_m / 2 <= sx:
            continue
        # the body's near end: the ray first touches the body there, at the left lane's lower edge, or further on
        lo = max(r.interval_m[0] - error_m - CAR.length_m / 2, sx)
        starts.append(max(lo, sx + (sy - ty) * (lo - sx) / (sy - body_low)))
    start = min(starts, default=math.inf)
    return start if start < spec.right_range_m else None


@dataclass(frozen=True, slots=True)
class Truth:
    """Every vehicle within range of its lane's sensor, where it really is, and where the AV is."""

    readings: tuple[Reading, ...]
    targets: tuple[tuple[float, float], ...]  # (x_m, y_m) of each reading's vehicle
    av_x_m: float
    av_y_m: float


def in_range(av_x_m: float, av_y_m: float, left: list[KinematicCar], oncoming: list[KinematicCar],
             spec: SensorSpec = SENSORS, av_speed_mps: float | None = None) -> Truth:
    """The ground truth: every vehicle in range of its lane's sensor, with its range rate when the AV's own speed
    along the road is given."""
    candidates = [(Lane.LEFT, car) for car in left if abs(car.x_m - av_x_m) <= spec.left_range_m]
    candidates += [(Lane.RIGHT, car) for car in oncoming
                   if -spec.side_range_m <= car.x_m - av_x_m <= spec.right_range_m]
    return Truth(tuple(Reading(lane, car.body, car.x_m - av_x_m, rate_mps=None if av_speed_mps is None
                               else car.velocity_mps - av_speed_mps) for lane, car in candidates),
                 tuple((car.x_m, car.y_m) for _, car in candidates), av_x_m, av_y_m)


class SensorModel(Protocol):
    """What a simulator asks of its sensors: what the planner sees of the truth."""

    def read(self, truth: Truth) -> tuple[Reading, ...]: ...


class RaySensor:
    """The paper's sensors, exact: a ray to each vehicle in range; a vehicle is seen when the ray reaches it first."""

    def __init__(self, scene: Scene, rng: np.random.Generator, spec: SensorSpec = SENSORS) -> None:
        self.scene, self.rng, self.spec = scene, rng, spec

    def read(self, truth: Truth) -> tuple[Reading, ...]:
        if not truth.readings:
            return ()
        z = self.spec.height_m
        ends = [(x, y, z) for x, y in truth.targets]
        starts = [_outside_av(truth.av_x_m, truth.av_y_m, end, z) if r.lane is Lane.LEFT
                  else _right_sensor(truth.av_x_m, truth.av_y_m, end, z) for r, end in zip(truth.readings, ends)]
        hits = self.scene.client.rayTestBatch(starts, ends)
        return tuple(r for r, hit in zip(truth.readings, hits, strict=True) if hit[0] == r.body)



class NoisySensor(RaySensor):
    """The paper's sensors with range noise and missed detections (``spec.physical.NoiseSpec``): each reading the
    rays report is dropped with probability ``miss_rate``, else its distance gets Gaussian noise, and its range rate
    (when read) Gaussian noise of its own, drawn from a generator spawned for it (the range's draws stay those of
    the seed)."""

    def __init__(self, scene: Scene, rng: np.random.Generator, spec: SensorSpec = SENSORS,
                 noise: NoiseSpec = NOISE) -> None:
        super().__init__(scene, rng, spec)
        self.noise = noise
        self.rate_rng = rng.spawn(1)[0]

    def read(self, truth: Truth) -> tuple[Reading, ...]:
        seen = []
        for reading in super().read(truth):
            missed = self.rng.random() < self.noise.miss_rate
            error_m = float(self.rng.normal(0.0, self.noise.range_sd_m))
            if not missed:
                rate = reading.rate_mps
                if rate is not None:
                    rate += float(self.rate_rng.normal(0.0, self.noise.range_rate_sd_mps))
                seen.append(replace(reading, dx_m=reading.dx_m + error_m, rate_mps=rate))
        return tuple(seen)
