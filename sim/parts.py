"""What a simulator is assembled from: the parts passed in, and what a drive is asked to do.

Like PyBullet's minitaur environments, a ``Simulator`` builds nothing of its own choosing:
it receives factories for its scene, its car, its traffic model and its sensor model (each
factory is handed the simulator's own scene and seeded generator), the planner (engine,
strategy, grid) and observers. ``Parts()`` is the paper's assembly. Traffic and sensor
models are registered once, by name, for campaigns and the command line.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from oracle.planner import plan
from sim.driver.discretiser import discretise
from sim.driver.readings import Reading, seen_from
from sim.observers import Observer
from sim.scene import Scene
from sim.sensors import NoisySensor, RaySensor, SensorModel
from sim.traffic import FollowingTraffic, PaperTraffic, SpreadTraffic, TrafficModel
from sim.vehicle import WheeledCar
from spec.answers import Answer, Strategy
from spec.assumptions import Bounds, speed_error_mps, world_bounds
from spec.dynamics import Overtaken, VehicleSpeeds, parse_overtaken, parse_vehicle_speeds
from spec.engines import Engine, check_strategy, get_engine, load_engines, parse_strategy
from spec.errors import OptionError, check_number
from spec.escapes import COMMIT, Semantics, parse_semantics
from spec.faults import DEFAULT_STEERING_OFFSET_DEG, NO_FAULTS, FaultKind, FaultSpec, parse_faults
from spec.grid import PAPER_GRID, Grid, grid_for
from spec.lanes import Lane
from spec.physical import EVENTS, LOOP, MAX_STOP_RATE_PER_H, NOISE, EventSpec, NoiseSpec
from spec.scenario import Scenario
from spec.sound import Sound

TrafficFactory = Callable[[Scene, np.random.Generator, float], TrafficModel]
SensorFactory = Callable[[Scene, np.random.Generator], SensorModel]

#: The traffic and sensor models a drive can be assembled with, by name.
TRAFFIC_MODELS: dict[str, TrafficFactory] = {"paper": PaperTraffic, "spread": SpreadTraffic,
                                             "following": FollowingTraffic}
SENSOR_MODELS: dict[str, SensorFactory] = {"exact": RaySensor, "noisy": NoisySensor}
#: The models a drive can plan with: the paper's rules, or the sound model under the world's bounds.
PLANNING_MODELS: dict[str, str] = {"paper": "the paper's rules (cells, the common speed)",
                                   "sound": "the sound model under the world's bounds (spec.assumptions.world_bounds)"}


def loop_semantics(model: str) -> Semantics:
    """How a model decides in the loop unless told: the sound model by commitments (``spec.escapes``: a committed
    part with a proved escape), the paper's rules by whole plans (the only way they plan)."""
    return Semantics.COMMIT if model == "sound" else Semantics.WHOLE


def check_name(option: str, name: str, known: dict[str, Any]) -> None:
    """A registered model's name; anything else is bad input naming the option and the known names."""
    if name not in known:
        raise OptionError(option, name, f"unknown model (known: {', '.join(known)})")


@dataclass(frozen=True)
class Planner:
    """The planner a simulator consults: an engine, a strategy, the grid the snapshot is cut into, and the sound
    model's assumptions (None: the paper's rules)."""

    engine: Engine
    strategy: Strategy = Strategy.SENSIBLE
    grid: Grid = PAPER_GRID
    sound: Sound | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "strategy", parse_strategy(self.strategy))
        check_strategy(self.engine, self.strategy)
        if self.sound is not None and not self.engine.sound:
            able = ", ".join(e.name for e in load_engines().values() if e.sound)
            raise OptionError("--engine", self.engine.name, f"answers the paper model only, not --model sound "
                              f"(the sound model is answered by: {able})")

    def scenario(self, readings: tuple[Reading, ...], lane: Lane, speed_mps: float | None = None,
                 oncoming_view_m: float | None = None, sensors_ahead_m: float = 0.0,
                 sensed_sets: bool = False, from_reference: bool = False) -> Scenario:
        """The snapshot as a scenario on this planner's grid (ScenarioError when it is inconsistent); under the
        sound model, with ``speed_mps`` as the plan's start, the oncoming phantom where the snapshot's view of that
        lane ended (``sim.sensors.oncoming_view_m``; None: the sensor's range), and the plan's AV ``sensors_ahead_m``
        behind the car the readings were taken from (``spec.sound.Sound.sensors_ahead_m``: the proved reference the
        car runs on; 0, the car itself), ``from_reference`` whether the plan's AV is that reference
        (``spec.sound.Sound.from_reference``); with ``sensed_sets`` the readings are sets that hold the sensing error
        (``spec.sound.Sound.sensed_sets``)."""
        if self.sound is None:
            return discretise(readings, lane, self.grid)
        scenario = discretise(seen_from(readings, sensors_ahead_m), lane, self.grid, measured=True)
        return replace(scenario, sound=replace(self.sound, start_mps=speed_mps, oncoming_view_m=oncoming_view_m,
                                               sensors_ahead_m=sensors_ahead_m, sensed_sets=sensed_sets,
                                               from_reference=from_reference))

    def plan(self, scenario: Scenario) -> Answer:
        return plan(scenario, self.strategy, engine=self.engine)


@dataclass(frozen=True)
class Parts:
    """Factories for every part of a simulator; the defaults are the paper's world."""

    planner: Planner
    scene: Callable[[], Scene] = Scene
    car: Callable[[Scene, float, float], WheeledCar] = WheeledCar
    traffic: TrafficFactory = PaperTraffic
    sensor: SensorFactory = RaySensor
    observers: tuple[Observer, ...] = field(default=())
    bounds: Bounds | None = None  # the assumptions containment is measured against (None: not measured)
    faults: FaultSpec = NO_FAULTS  # what the fault injectors do to the sensors and the steering (``sim.faults``)
    tracking: bool = False  # the tracking layer between the sensors and the discretiser (``sim.tracking``)
    speed_error_mps: float = 0.0  # the range-rate readings' error bound, for the tracker's speed intervals
    #: the planner and containment read each track's speed interval (``spec.dynamics``: it may brake to a standstill);
    #: False: every vehicle at its lane's speeds
    measured_speeds: bool = False


@dataclass(frozen=True, slots=True)
class DriveConfig:
    """What every drive of a campaign shares (the seeds differ): a typed value, written whole with each record."""

    km: float
    until_failure: bool = False
    engine: str = "interpreter"
    strategy: Strategy = Strategy.SENSIBLE
    replan_on_violation: bool = True
    step_tolerance_cells: float = LOOP.step_tolerance_cells
    plan_tolerance_cells: float = LOOP.plan_tolerance_cells
    cell_m: float = PAPER_GRID.cell
    traffic: str = "paper"
    sensor: str = "exact"
    stop_rate_per_h: float = EVENTS.stop_rate_per_h  # the traffic models that do not keep to the grid
    min_spawn_gap_m: float = EVENTS.min_spawn_gap_m
    range_sd_m: float = NOISE.range_sd_m  # the noisy sensor
    miss_rate: float = NOISE.miss_rate
    snapshots: int = 0  # scenarios kept per run (every 10th plan's), to replay with every engine
    restart_after_collision: bool = False  # go on from a fresh start after a collision (the audit) or stop (default)
    opportunity_checks: int = 0  # decisions without an overtake replayed in physics per run (``sim.opportunity``)
    model: str = "paper"  # which model decides: the paper's rules, or the sound model under ``bounds``
    bounds_scale: float = 1.0  # the world's bounds' widths times this (``spec.assumptions.world_bounds``)
    faults: str = ""  # the fault injectors, as ``--faults`` takes them (``spec.faults.parse_faults``); kept canonical
    steering_offset_deg: float = DEFAULT_STEERING_OFFSET_DEG  # the steering fault's size
    tracking: bool = False  # the planner sees the tracker's vehicles, not each sweep's readings (``sim.tracking``)
    #: where a vehicle's speed comes from (``VehicleSpeeds``): its lane's bounds, or its track's measured interval
    vehicle_speeds: VehicleSpeeds = VehicleSpeeds.LANE
    #: what a measured same-direction vehicle may do while the AV is in the passing lane (``Overtaken``)
    overtaken: Overtaken = Overtaken.PHYSICS
    #: stop at the first failure a sensing fault caused; restart after any other (counted apart): the reliability
    #: target's measure, km between sensing-caused failures (docs/faults.md)
    until_sensing_failure: bool = False
    #: how the sound model decides (``spec.escapes``): a committed part with a proved escape, executed until the next
    #: decision (the rest and its escape when a decision proves nothing), or whole plans proved to their end. None:
    #: the model's own (``loop_semantics``); always a ``Semantics`` once made
    semantics: Semantics | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "strategy", parse_strategy(self.strategy))
        check_name("--traffic", self.traffic, TRAFFIC_MODELS)
        check_name("--sensor", self.sensor, SENSOR_MODELS)
        check_name("--model", self.model, PLANNING_MODELS)
        grid_for(self.cell_m)
        if self.until_failure and self.until_sensing_failure:
            raise OptionError("--until-sensing-failure", True, "give one of --until-failure (every failure ends a run) "
                              "and --until-sensing-failure (only one a sensing fault caused does)")
        for option, value, high in (("--km", self.km, math.inf), ("--stop-rate-per-h", self.stop_rate_per_h,
                                                                      MAX_STOP_RATE_PER_H),
                                    ("--min-spawn-gap-m", self.min_spawn_gap_m, math.inf),
                                    ("--range-sd-m", self.range_sd_m, math.inf), ("--miss-rate", self.miss_rate, 1.0)):
            check_number(option, value, high)
        world_bounds(self.traffic, self.sensor, self.range_sd_m, self.bounds_scale)  # checked here, not in a worker
        object.__setattr__(self, "faults", parse_faults(self.faults, "--faults", self.steering_offset_deg).text())
        semantics = loop_semantics(self.model) if self.semantics is None else \
            parse_semantics(self.semantics, "--semantics")
        object.__setattr__(self, "semantics", semantics)
        if semantics is not Semantics.WHOLE and self.model != "sound":
            raise OptionError("--semantics", semantics.value, "needs --model sound (the paper's rules plan "
                              "whole plans)")
        if semantics is Semantics.COMMIT and self.model == "sound" and not get_engine(self.engine).commit:
            able = ", ".join(e.name for e in load_engines().values() if e.commit)
            raise OptionError("--semantics", semantics.value, f"engine {self.engine} does not answer the "
                              f"commitment semantics (answered by: {able})")
        object.__setattr__(self, "vehicle_speeds", parse_vehicle_speeds(self.vehicle_speeds))
        if self.vehicle_speeds is VehicleSpeeds.MEASURED:  # the sound model's drives read them (the paper's: cells)
            why = ("needs --tracking on (speeds are measured by the tracks)" if not self.tracking else
                   None if semantics in get_engine(self.engine).measured_speeds else
                   f"engine {self.engine} answers every vehicle at its lane's speeds only under --semantics "
                   f"{semantics.value}")
            if why is not None:
                raise OptionError("--vehicle-speeds", self.vehicle_speeds.value, why)
        object.__setattr__(self, "overtaken", parse_overtaken(self.overtaken))
        if self.overtaken is not Overtaken.PHYSICS and self.vehicle_speeds is not VehicleSpeeds.MEASURED:
            raise OptionError("--overtaken", self.overtaken.value, "needs --vehicle-speeds measured (the profile "
                              "speaks of vehicles whose speed was measured; it applies to the sound model's drives)")
        if self.overtaken is not Overtaken.PHYSICS and semantics not in get_engine(self.engine).overtaken_profile:
            raise OptionError("--overtaken", self.overtaken.value, f"engine {self.engine} answers measured vehicles "
                              f"by their physics only under --semantics {semantics.value}")

    @property
    def decides(self) -> Semantics:
        """How the drive's model decides (``semantics``, resolved when the configuration was made)."""
        return self.semantics or loop_semantics(self.model)

    @property
    def stops_at_failure(self) -> bool:
        """Whether a drive stops at a failure (any, or the first a sensing fault caused)."""
        return self.until_failure or self.until_sensing_failure

    @property
    def events(self) -> EventSpec:
        return EventSpec(stop_rate_per_h=self.stop_rate_per_h, min_spawn_gap_m=self.min_spawn_gap_m)

    @property
    def noise(self) -> NoiseSpec:
        return NoiseSpec(range_sd_m=self.range_sd_m, miss_rate=self.miss_rate)

    @property
    def fault_spec(self) -> FaultSpec:
        return parse_faults(self.faults, "--faults", self.steering_offset_deg)

    @property
    def grid(self) -> Grid:
        return grid_for(self.cell_m)

    @property
    def bounds(self) -> Bounds:
        """The assumptions of this world, by the rule stated once (``world_bounds``): the sound model plans under
        them, and containment is measured against them under either model."""
        return world_bounds(self.traffic, self.sensor, self.range_sd_m, self.bounds_scale)

    def parts(self, observers: tuple[Observer, ...] = ()) -> Parts:
        """The assembly this configuration names."""
        # the sound model plans for the snapshot's age at the plan's start: the planner's time in the loop
        sound = Sound(replace(self.bounds, latency_s=LOOP.plan_budget_s), overtaken=self.overtaken,
                      commitment=COMMIT if self.decides is Semantics.COMMIT else None) \
            if self.model == "sound" else None
        planner = Planner(get_engine(self.engine), self.strategy, self.grid, sound)
        traffic, sensor = TRAFFIC_MODELS[self.traffic], SENSOR_MODELS[self.sensor]
        if self.traffic != "paper":
            traffic = functools.partial(traffic, events=self.events)  # type: ignore[call-arg]
        if self.sensor != "exact":
            sensor = functools.partial(sensor, noise=self.noise)  # type: ignore[call-arg]
        return Parts(planner, traffic=traffic, sensor=sensor, observers=observers, bounds=self.bounds,
                     faults=self.fault_spec, tracking=self.tracking,
                     speed_error_mps=speed_error_mps(self.sensor, self.noise.range_rate_sd_mps),
                     measured_speeds=self.vehicle_speeds is VehicleSpeeds.MEASURED and self.model == "sound")

    def to_json(self) -> dict[str, Any]:
        """The configuration as records keep it; event and noise parameters only where the models use them, so that
        changing them does not make paper-traffic or exact-sensing runs look like another campaign."""
        data = self.all_json()
        if self.traffic == "paper":
            del data["stop_rate_per_h"], data["min_spawn_gap_m"]
        if self.sensor == "exact":
            del data["range_sd_m"], data["miss_rate"]
        if not self.fault_spec.of(FaultKind.STEERING):
            del data["steering_offset_deg"]
        for key, default in (("restart_after_collision", False), ("opportunity_checks", 0), ("model", "paper"),
                             ("bounds_scale", 1.0), ("faults", ""), ("tracking", False),
                             ("until_sensing_failure", False), ("vehicle_speeds", VehicleSpeeds.LANE.value),
                             ("overtaken", Overtaken.PHYSICS.value)):
            if data[key] == default:  # records written before these existed stay the same campaign
                del data[key]
        if self.model != "sound":  # the paper's rules plan whole plans: its records stay the same campaign
            del data["semantics"]
        return data

    def all_json(self) -> dict[str, Any]:
        """Every parameter, whether its models use it or not."""
        return {"km": self.km, "until_failure": self.until_failure, "engine": self.engine,
                "strategy": self.strategy.value, "replan_on_violation": self.replan_on_violation,
                "step_tolerance_cells": self.step_tolerance_cells, "plan_tolerance_cells": self.plan_tolerance_cells,
                "cell_m": self.cell_m, "traffic": self.traffic, "sensor": self.sensor,
                "stop_rate_per_h": self.stop_rate_per_h, "min_spawn_gap_m": self.min_spawn_gap_m,
                "range_sd_m": self.range_sd_m, "miss_rate": self.miss_rate, "snapshots": self.snapshots,
                "restart_after_collision": self.restart_after_collision,
                "opportunity_checks": self.opportunity_checks, "model": self.model, "bounds_scale": self.bounds_scale,
                "faults": self.faults, "steering_offset_deg": self.steering_offset_deg, "tracking": self.tracking,
                "until_sensing_failure": self.until_sensing_failure, "vehicle_speeds": self.vehicle_speeds.value,
                "overtaken": self.overtaken.value, "semantics": self.decides.value}

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> DriveConfig:
        if data.get("model") == "sound" and "semantics" not in data:  # recorded when the loop planned whole plans
            data = {**data, "semantics": Semantics.WHOLE.value}
        return cls(**data)
