"""The paper's traffic: constant vehicle counts, respawned ahead by its rules, removed 5 cells behind the AV.

Left-lane vehicles respawn 1-4 cells (equal odds) ahead of the front-most one, never
making more than three consecutive vehicles without an empty cell; oncoming vehicles
respawn 8/12/16/20 cells (odds 1/8, 1/4, 1/4, 3/8) beyond the last one. All drive at the
common speed. Positions are kept in whole cells (of the paper's grid) apart, as the paper's
scene spawns them. A traffic model is one part of a simulator (``sim.parts``): the
simulator only calls the methods of ``TrafficModel``.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from sim.scene import Scene
from sim.vehicle import KinematicCar
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


class TrafficModel(Protocol):
    """What a simulator asks of its traffic: the cars, moving them, respawning those left behind."""

    left: list[KinematicCar]
    oncoming: list[KinematicCar]

    def cars(self) -> list[KinematicCar]: ...
    def advance(self, dt_s: float) -> None: ...
    def respawn_behind(self, av_x_m: float) -> int: ...
    def shift_x(self, dx_m: float) -> None: ...


class PaperTraffic:
    """Every other vehicle: kinematic cars in both lanes, respawned by the paper's rules."""

    def __init__(self, scene: Scene, rng: np.random.Generator, av_x_m: float, spec: TrafficSpec = TRAFFIC) -> None:
        self.scene, self.rng, self.spec = scene, rng, spec
        self.left: list[KinematicCar] = []
        self.oncoming: list[KinematicCar] = []
        self.run = 0  # consecutive left-lane vehicles at the front
        cell_m = spec.cell_m
        x = av_x_m + 2 * cell_m
        for _ in range(spec.left_vehicles):
            self.left.append(KinematicCar(scene, x, scene.lane_y(Lane.LEFT), spec.speed_mps))
            gap = left_gap_cells(rng, self.run, spec)
            self.run = self.run + 1 if gap == 1 else 1
            x += gap * cell_m
        x = av_x_m + oncoming_gap_cells(rng, spec) * cell_m
        for _ in range(spec.oncoming_vehicles):
            self.oncoming.append(KinematicCar(scene, x, scene.lane_y(Lane.RIGHT), -spec.speed_mps))
            x += oncoming_gap_cells(rng, spec) * cell_m

    def cars(self) -> list[KinematicCar]:
        return self.left + self.oncoming

    def advance(self, dt_s: float) -> None:
        for car in self.cars():
            car.advance(dt_s)

    def respawn_behind(self, av_x_m: float) -> int:
        """Move every vehicle more than ``remove_behind_cells`` behind the AV to its respawn place; count them."""
        cell_m = self.spec.cell_m
        limit = av_x_m - self.spec.remove_behind_cells * cell_m
        moved = 0
        for car in self.left:
            if car.x_m < limit:
                front = max(c.x_m for c in self.left)
                gap = left_gap_cells(self.rng, self.run, self.spec)
                self.run = self.run + 1 if gap == 1 else 1
                car.place(front + gap * cell_m)
                car.respawns += 1
                moved += 1
        for car in self.oncoming:
            if car.x_m < limit:
                last = max(c.x_m for c in self.oncoming)
                car.place(last + oncoming_gap_cells(self.rng, self.spec) * cell_m)
                car.respawns += 1
                moved += 1
        return moved

    def shift_x(self, dx_m: float) -> None:
        for car in self.cars():
            car.place(car.x_m + dx_m)
