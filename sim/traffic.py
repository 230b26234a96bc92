"""The paper's traffic: constant vehicle counts, respawned ahead by its rules, removed 5 cells behind the AV.

Left-lane vehicles respawn 1-4 cells (equal odds) ahead of the front-most one, never
making more than three consecutive vehicles without an empty cell; oncoming vehicles
respawn 8/12/16/20 cells (odds 1/8, 1/4, 1/4, 3/8) beyond the last one. All drive at the
common speed. Positions are kept in whole cells apart, as the paper's scene spawns them.
"""

from __future__ import annotations

import numpy as np

from sim.scene import Scene
from sim.vehicle import KinematicCar
from spec.constants import DEFAULT_SPEED_MPS, SEGMENT_M
from spec.lanes import Lane
from spec.physical import TRAFFIC, TrafficSpec


def left_gap_cells(rng: np.random.Generator, run: int, spec: TrafficSpec = TRAFFIC) -> int:
    """Cells ahead of the front-most left-lane vehicle; ``run`` is how many are consecutive there now."""
    choices = [g for g in spec.left_respawn_cells if g > 1 or run < spec.max_consecutive]
    return int(rng.choice(choices))


def oncoming_gap_cells(rng: np.random.Generator, spec: TrafficSpec = TRAFFIC) -> int:
    """Cells beyond the last oncoming vehicle, with the paper's odds."""
    odds = np.array([float(f) for f in spec.oncoming_gap_odds])
    return int(rng.choice(spec.oncoming_gap_cells, p=odds / odds.sum()))


class Traffic:
    """Every other vehicle: kinematic cars in both lanes, respawned by the paper's rules."""

    def __init__(self, scene: Scene, rng: np.random.Generator, av_x_m: float, spec: TrafficSpec = TRAFFIC) -> None:
        self.scene, self.rng, self.spec = scene, rng, spec
        self.left: list[KinematicCar] = []
        self.oncoming: list[KinematicCar] = []
        self.run = 0  # consecutive left-lane vehicles at the front
        x = av_x_m + 2 * SEGMENT_M
        for _ in range(spec.left_vehicles):
            self.left.append(KinematicCar(scene, x, scene.lane_y(Lane.LEFT), DEFAULT_SPEED_MPS))
            gap = left_gap_cells(rng, self.run, spec)
            self.run = self.run + 1 if gap == 1 else 1
            x += gap * SEGMENT_M
        x = av_x_m + oncoming_gap_cells(rng, spec) * SEGMENT_M
        for _ in range(spec.oncoming_vehicles):
            self.oncoming.append(KinematicCar(scene, x, scene.lane_y(Lane.RIGHT), -DEFAULT_SPEED_MPS))
            x += oncoming_gap_cells(rng, spec) * SEGMENT_M

    def cars(self) -> list[KinematicCar]:
        return self.left + self.oncoming

    def advance(self, dt_s: float) -> None:
        for car in self.cars():
            car.advance(dt_s)

    def respawn_behind(self, av_x_m: float) -> int:
        """Move every vehicle more than ``remove_behind_cells`` behind the AV to its respawn place; count them."""
        limit = av_x_m - self.spec.remove_behind_cells * SEGMENT_M
        moved = 0
        for car in self.left:
            if car.x_m < limit:
                front = max(c.x_m for c in self.left)
                gap = left_gap_cells(self.rng, self.run, self.spec)
                self.run = self.run + 1 if gap == 1 else 1
                car.place(front + gap * SEGMENT_M)
                car.respawns += 1
                moved += 1
        for car in self.oncoming:
            if car.x_m < limit:
                last = max(c.x_m for c in self.oncoming)
                car.place(last + oncoming_gap_cells(self.rng, self.spec) * SEGMENT_M)
                car.respawns += 1
                moved += 1
        return moved

    def shift_x(self, dx_m: float) -> None:
        for car in self.cars():
            car.place(car.x_m + dx_m)
