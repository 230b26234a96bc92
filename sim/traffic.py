"""Traffic models, one part of a simulator (``sim.parts``): the simulator only calls ``TrafficModel``'s methods.

``PaperTraffic`` is the paper's: constant vehicle counts, left-lane vehicles respawned 1-4
cells (equal odds) ahead of the front-most one (of the end of the AV's left sensor's range when
no vehicle is wholly ahead of the AV), never more than three consecutive without an empty cell;
oncoming vehicles 8/12/16/20 cells (odds 1/8, 1/4, 1/4, 3/8) beyond the last one; removed 5
cells behind the AV; all at the common speed, whole cells (of the paper's grid)
apart, as the paper's scene spawns them: a world built to agree with the grid.

Two models that do not keep to it (``spec.physical``: ``SpeedSpec``, ``IdmSpec``,
``EventSpec``), for auditing the abstraction: ``SpreadTraffic`` (each vehicle keeps its own
speed, drawn around 7 m/s, until it closes to the minimum gap behind a slower one, which it
then follows at that one's speed) and ``FollowingTraffic`` (every vehicle drives by the
Intelligent Driver Model behind the one ahead of it, the AV included when it is in the left
lane at its speed along the road, so platoons compress and leaders run below 7 m/s). Both
respawn by the paper's rules but at continuous distances (a paper gap of g cells is drawn
uniformly between g - 1 and g + 1 cells, never below the minimum spawn gap), and make
left-lane vehicles brake to a standstill at a stated rate. Oncoming vehicles follow each
other, never the AV. Two vehicles that touch each other stop where they are (wrecks) until
they are left behind.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from sim.idm import idm_accel_mps2
from sim.scene import Scene
from sim.vehicle import KinematicCar, Pose
from spec.lanes import Lane
from spec.physical import CAR, EVENTS, IDM, SENSORS, SPEEDS, TRAFFIC, EventSpec, IdmSpec, SpeedSpec, TrafficSpec


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
    collisions: int  # vehicles that touched each other (not the AV: PyBullet reports those)

    def cars(self) -> list[KinematicCar]: ...
    def advance(self, dt_s: float, av: Pose) -> None: ...
    def respawn_behind(self, av_x_m: float) -> int: ...
    def shift_x(self, dx_m: float) -> None: ...
    def save(self) -> dict[str, Any]: ...
    def restore(self, saved: dict[str, Any]) -> None: ...


class PaperTraffic:
    """Every other vehicle: kinematic cars in both lanes at the common speed, respawned by the paper's rules."""

    def __init__(self, scene: Scene, rng: np.random.Generator, av_x_m: float, spec: TrafficSpec = TRAFFIC) -> None:
        self.scene, self.rng, self.spec = scene, rng, spec
        self.left: list[KinematicCar] = []
        self.oncoming: list[KinematicCar] = []
        self.collisions = 0
        self.run = 0  # consecutive left-lane vehicles at the front
        x, gap = av_x_m + 2 * spec.cell_m, 0
        for _ in range(spec.left_vehicles):
            self.left.append(self._spawn(KinematicCar(scene, x, scene.lane_y(Lane.LEFT), spec.speed_mps), Lane.LEFT))
            self.run = self.run + 1 if gap == 1 else 1  # the vehicle just placed is the front-most
            # the gap to the next one; after the last, drawn as well (and not placed): seeded drives keep their stream
            gap = left_gap_cells(rng, self.run, spec)
            x += self._spacing_m(gap)
        x = av_x_m + self._spacing_m(oncoming_gap_cells(rng, spec))
        for _ in range(spec.oncoming_vehicles):
            car = KinematicCar(scene, x, scene.lane_y(Lane.RIGHT), -spec.speed_mps)
            self.oncoming.append(self._spawn(car, Lane.RIGHT))
            x += self._spacing_m(oncoming_gap_cells(rng, spec))

    # -- what the models that do not keep to the grid change ------------------------------------
    def _spacing_m(self, cells: int) -> float:
        """Centre to centre distance for a paper gap of ``cells`` (here: exactly that many cells)."""
        return cells * self.spec.cell_m

    def _spawn(self, car: KinematicCar, lane: Lane) -> KinematicCar:
        """A car (re)placed in ``lane``: here it keeps the common speed."""
        return car

    # -- the simulator's calls ---------------------------------------------------------------------
    def cars(self) -> list[KinematicCar]:
        return self.left + self.oncoming

    def advance(self, dt_s: float, av: Pose) -> None:
        for car in self.cars():
            car.advance(dt_s)

    def respawn_behind(self, av_x_m: float) -> int:
        """Move every vehicle more than ``remove_behind_cells`` behind the AV to its respawn place; count them. A
        left-lane vehicle is placed a paper gap ahead of the front-most one, or, when none is wholly ahead of the AV,
        of the end of the AV's left sensor's range: the lane the AV sees ahead is empty, and a vehicle enters it from
        the road beyond (placed from a front-most one beside or behind the AV, it would appear beside or inside it)."""
        limit = av_x_m - self.spec.remove_behind_cells * self.spec.cell_m
        moved = 0
        for car in self.left:
            if car.x_m < limit:
                front = max(c.x_m for c in self.left)
                if front - av_x_m < CAR.length_m:  # no vehicle wholly ahead of the AV: the lane it sees ahead is empty
                    front = av_x_m + SENSORS.left_range_m
                gap = left_gap_cells(self.rng, self.run, self.spec)
                self.run = self.run + 1 if gap == 1 else 1
                car.place(front + self._spacing_m(gap))
                car.respawns += 1
                self._spawn(car, Lane.LEFT)
                moved += 1
        for car in self.oncoming:
            if car.x_m < limit:
                last = max(c.x_m for c in self.oncoming)
                car.place(last + self._spacing_m(oncoming_gap_cells(self.rng, self.spec)))
                car.respawns += 1
                self._spawn(car, Lane.RIGHT)
                moved += 1
        return moved

    def shift_x(self, dx_m: float) -> None:
        for car in self.cars():
            car.place(car.x_m + dx_m)

    def save(self) -> dict[str, Any]:
        """Everything that moves or draws, to put back with ``restore`` (a what-if replay leaves no trace)."""
        return {"cars": [(car.x_m, car.velocity_mps, car.respawns) for car in self.cars()], "run": self.run,
                "collisions": self.collisions, "rng": copy.deepcopy(self.rng.bit_generator.state)}

    def restore(self, saved: dict[str, Any]) -> None:
        for car, (x_m, velocity_mps, respawns) in zip(self.cars(), saved["cars"], strict=True):
            car.place(x_m)
            car.velocity_mps, car.respawns = velocity_mps, respawns
        self.run, self.collisions = saved["run"], saved["collisions"]
        self.rng.bit_generator.state = copy.deepcopy(saved["rng"])


@dataclass(slots=True)
class Driver:
    """What a vehicle of the models that do not keep to the grid wants and is doing."""

    desired_mps: float
    speed_mps: float
    stopping_until_s: float = -1.0  # braking to a standstill, then standing, until this time
    wrecked: bool = False


def draw_speed_mps(rng: np.random.Generator, spec: SpeedSpec = SPEEDS) -> float:
    """A vehicle's own (desired) speed: normal around the mean, cut at ``cut_sd`` standard deviations."""
    low, high = spec.mean_mps - spec.cut_sd * spec.sd_mps, spec.mean_mps + spec.cut_sd * spec.sd_mps
    return float(np.clip(rng.normal(spec.mean_mps, spec.sd_mps), low, high))


class SpreadTraffic(PaperTraffic):
    """Each vehicle at its own speed, continuous spawn gaps, stops at a stated rate (see the module's docstring)."""

    def __init__(self, scene: Scene, rng: np.random.Generator, av_x_m: float, spec: TrafficSpec = TRAFFIC,
                 speeds: SpeedSpec = SPEEDS, events: EventSpec = EVENTS, idm: IdmSpec = IDM) -> None:
        self.speeds, self.events, self.idm = speeds, events, idm
        self.drivers: dict[int, Driver] = {}
        self.t_s = 0.0
        super().__init__(scene, rng, av_x_m, spec)

    def _spacing_m(self, cells: int) -> float:
        cell_m, floor_m = self.spec.cell_m, CAR.length_m + self.events.min_spawn_gap_m
        low = max(floor_m, (cells - 1) * cell_m)
        return float(self.rng.uniform(low, max(low, (cells + 1) * cell_m)))

    def _spawn(self, car: KinematicCar, lane: Lane) -> KinematicCar:
        speed = draw_speed_mps(self.rng, self.speeds)
        self.drivers[car.body] = Driver(speed, speed)
        car.velocity_mps = speed if lane is Lane.LEFT else -speed
        return car

    def _accel_mps2(self, driver: Driver, gap_m: float, leader_mps: float) -> float | None:
        """The model's acceleration law; None: no law, the vehicle keeps its own speed (spread)."""
        return None

    def advance(self, dt_s: float, av: Pose) -> None:
        self.t_s += dt_s
        av_in_left = av.y_m >= 0
        for lane, cars, sign in ((Lane.LEFT, self.left, 1.0), (Lane.RIGHT, self.oncoming, -1.0)):
            av_leader = lane is Lane.LEFT and av_in_left
            done: list[KinematicCar] = []  # the cars already moved this step, the front-most first
            ordered = True  # ``done`` is ordered by position, the front-most first
            for car in sorted(cars, key=lambda c: -sign * c.x_m):  # the front-most (in its direction) first
                driver = self.drivers[car.body]
                leader = _nearest_ahead(done, ordered, car.x_m, sign)
                if av_leader and sign * (av.x_m - car.x_m) > 0 and (
                        leader is None or av.x_m - car.x_m <= leader.x_m - car.x_m):
                    gap_m, leader_mps = av.x_m - car.x_m - CAR.length_m, av.along_mps  # the AV (first on ties)
                elif leader is None:
                    gap_m, leader_mps = math.inf, 0.0
                else:
                    gap_m = sign * (leader.x_m - car.x_m) - CAR.length_m
                    leader_mps = self.drivers[leader.body].speed_mps
                    if gap_m < 0 and not driver.wrecked:
                        self._wreck(car, leader)  # touching the AV is the AV's collision: PyBullet reports it
                self._drive(car, driver, lane, gap_m, leader_mps, dt_s)
                car.velocity_mps = sign * driver.speed_mps
                car.advance(dt_s)
                ordered = ordered and (not done or sign * (done[-1].x_m - car.x_m) >= 0)
                done.append(car)

    def _drive(self, car: KinematicCar, driver: Driver, lane: Lane, gap_m: float, leader_mps: float,
               dt_s: float) -> None:
        """One step of one vehicle: a wreck stands; a stop event brakes it to a standstill and holds it; otherwise
        the model's law (spread: its own speed, or its leader's once it has closed to the minimum gap)."""
        if driver.wrecked:
            driver.speed_mps = 0.0
            return
        if lane is Lane.LEFT and driver.stopping_until_s < self.t_s:
            per_step = self.events.stop_rate_per_h * dt_s / 3600
            if per_step > 0 and self.rng.random() < per_step:
                stop_s = driver.speed_mps / self.events.stop_decel_mps2
                driver.stopping_until_s = self.t_s + stop_s + self.events.stop_hold_s
        law = self._accel_mps2(driver, gap_m, leader_mps)
        if driver.stopping_until_s >= self.t_s:
            accel = -self.events.stop_decel_mps2 if law is None else min(-self.events.stop_decel_mps2, law)
        elif law is not None:
            accel = law
        else:
            close = gap_m <= self.idm.min_gap_m
            driver.speed_mps = min(driver.speed_mps, leader_mps) if close else driver.desired_mps
            return
        driver.speed_mps = max(0.0, driver.speed_mps + accel * dt_s)

    def save(self) -> dict[str, Any]:
        return {**super().save(), "drivers": copy.deepcopy(self.drivers), "t_s": self.t_s}

    def restore(self, saved: dict[str, Any]) -> None:
        super().restore(saved)
        self.drivers, self.t_s = copy.deepcopy(saved["drivers"]), saved["t_s"]

    def _wreck(self, car: KinematicCar, leader: KinematicCar) -> None:
        """Two vehicles touched: both stop where they are."""
        self.collisions += 1
        self.drivers[car.body].wrecked = True
        self.drivers[leader.body].wrecked = True


def _nearest_ahead(done: list[KinematicCar], ordered: bool, x_m: float, sign: float) -> KinematicCar | None:
    """The nearest of ``done`` strictly ahead of ``x_m`` in the lane's direction ``sign`` (the first of equals).

    ``done`` holds the cars moved so far this step, the front-most first, so it is usually ordered by position
    (``ordered``); then the cars ahead come first and the nearest is the last of them, found from the end. Only
    when a step has reordered the cars (one ran through another) are all of them compared."""
    if not ordered:
        ahead = [c for c in done if sign * (c.x_m - x_m) > 0]
        return min(ahead, key=lambda c: sign * (c.x_m - x_m)) if ahead else None
    k = len(done) - 1
    while k >= 0 and not sign * (done[k].x_m - x_m) > 0:
        k -= 1
    if k < 0:
        return None
    while k > 0 and sign * (done[k - 1].x_m - x_m) == sign * (done[k].x_m - x_m):
        k -= 1  # equally near: the first one moved, as a scan in order finds it
    return done[k]


class FollowingTraffic(SpreadTraffic):
    """Every vehicle drives by the Intelligent Driver Model behind the vehicle ahead (see the module's docstring)."""

    def _accel_mps2(self, driver: Driver, gap_m: float, leader_mps: float) -> float | None:
        return idm_accel_mps2(driver.speed_mps, driver.desired_mps, gap_m, driver.speed_mps - leader_mps, self.idm)
