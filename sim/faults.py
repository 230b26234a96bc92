"""The paper's faults injected (``spec.faults``): a sensor model wrapped so that what the planner sees goes wrong at a
stated rate per sweep, and a steering offset on the AV; the truth is never changed.

Each kind draws from its own seeded stream, so turning one kind on or off never changes another's draws (nor the
sensor's noise, nor traffic). A kind starts a fault with its rate on each sweep that offers it a target (while one of
its faults is under way it starts no other), and the fault lasts its persistence in sweeps, anchored to the vehicles
it touched: it ends early when one of them leaves the sweep (the geometry it came from is gone). Every fault is
logged with the sweep it started, the vehicles it touched and its end, for the failure attribution; the planner
never sees that log.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field, replace

import numpy as np

from sim.driver.readings import Reading
from sim.sensors import SensorModel, Truth
from spec.cells import left_cell
from spec.faults import GHOST_BEHIND_M, Fault, FaultKind, FaultSpec
from spec.grid import Grid
from spec.lanes import Lane
from spec.physical import CAR, SENSORS

#: The stream words of the fault injectors' generators: [seed, FAULT_STREAM, the kind's index].
FAULT_STREAM = 2
#: A reading that is no vehicle (a ghost) has this body (-1 is the AV's in containment's records); only the
#: simulator's bookkeeping reads bodies.
GHOST_BODY = -2


@dataclass(slots=True)
class FaultEvent:
    """One fault: its kind, the sweep it started and ended on, and the vehicles it touched (ghosts touch none)."""

    kind: FaultKind
    start_sweep: int
    bodies: tuple[int, ...]
    end_sweep: int  # the sweep after its last (set early when its geometry is gone)
    dx_m: float = 0.0  # a ghost's place (ahead of the AV), a split's or a fake gap's shift
    offset_rad: float = 0.0  # the steering fault's offset (to the left: positive)
    sweeps: int = 0  # how many sweeps it changed


@dataclass
class Injector:
    """One kind's injector: its rate and persistence, its own generator, its fault under way and its counts."""

    fault: Fault
    rng: np.random.Generator
    active: FaultEvent | None = None
    offered: int = 0  # sweeps that offered a target while no fault of this kind was under way
    started: int = 0
    events: list[FaultEvent] = field(default_factory=list)


def injectors(spec: FaultSpec, seed: int) -> dict[FaultKind, Injector]:
    """An injector per kind with a rate above 0, each on its own stream of ``seed``."""
    kinds = list(FaultKind)
    return {f.kind: Injector(f, np.random.default_rng([seed, FAULT_STREAM, kinds.index(f.kind)]))
            for f in spec.faults if f.rate > 0}


def _by_lane(readings: list[Reading], lane: Lane) -> list[Reading]:
    return sorted((r for r in readings if r.lane is lane), key=lambda r: r.dx_m)


def _pairs(readings: list[Reading], lane: Lane) -> list[tuple[Reading, Reading]]:
    """Consecutive readings of one lane, rear first."""
    lane_readings = _by_lane(readings, lane)
    return list(itertools.pairwise(lane_readings))


#: What a sweep offers a fault: the vehicles it would touch, and a place or a shift in metres.
Target = tuple[tuple[int, ...], float]


class FaultySensor:
    """A sensor model whose sweeps get the faults of ``spec``: ``read`` returns what the planner sees, or None for a
    dropped sweep."""

    def __init__(self, inner: SensorModel, spec: FaultSpec, grid: Grid, seed: int) -> None:
        self.inner, self.spec, self.grid = inner, spec, grid
        self.injectors = {k: i for k, i in injectors(spec, seed).items() if k.sensing}
        self.sweep = 0

    def in_sweep(self) -> list[FaultEvent]:
        """The faults that changed the last sweep."""
        return [i.active for i in self.injectors.values() if i.active is not None]

    @property
    def events(self) -> list[FaultEvent]:
        """Every sensing fault so far, in the order they started."""
        return sorted((e for i in self.injectors.values() for e in i.events), key=lambda e: e.start_sweep)

    def read(self, truth: Truth) -> tuple[Reading, ...] | None:
        self.sweep += 1
        readings = list(self.inner.read(truth))
        av_lane = Lane.LEFT if truth.av_y_m >= 0 else Lane.RIGHT
        dropped = False
        for kind, injector in self.injectors.items():
            event = injector.active
            if event is not None and (self.sweep >= event.end_sweep
                                      or not set(event.bodies) <= {r.body for r in readings}):
                event.end_sweep = self.sweep
                injector.active = event = None
            if event is None:
                event = self._start(injector, readings, av_lane)
            if event is None:
                continue
            event.sweeps += 1
            if kind is FaultKind.DROPPED:
                dropped = True
            else:
                readings = self._apply(event, readings)
        return None if dropped else tuple(readings)

    def _start(self, injector: Injector, readings: list[Reading], av_lane: Lane) -> FaultEvent | None:
        """A fault of the injector's kind, started with its rate when this sweep offers a target."""
        targets = self._targets(injector, readings, av_lane)
        if not targets:
            return None
        injector.offered += 1
        if injector.rng.random() >= injector.fault.rate:
            return None
        bodies, dx_m = targets[int(injector.rng.integers(len(targets)))]
        injector.started += 1
        injector.active = FaultEvent(injector.fault.kind, self.sweep, bodies,
                                     self.sweep + injector.fault.persistence_sweeps, dx_m)
        injector.events.append(injector.active)
        return injector.active

    def _targets(self, injector: Injector, readings: list[Reading], av_lane: Lane) -> list[Target]:
        """What this sweep offers a fault of the injector's kind: (the vehicles it would touch, a place or offset)."""
        kind, grid, rng = injector.fault.kind, self.grid, injector.rng
        cell = grid.cell
        if kind is FaultKind.FAKE_GAP:
            return [((rear.body, front.body), -cell) for rear, front in _pairs(readings, Lane.LEFT)
                    if left_cell(front.dx_m, av_lane, grid) - left_cell(rear.dx_m, av_lane, grid) == 1]
        if kind is FaultKind.SAME_CELL:
            near = [(a, b) for a, b in _pairs(readings, Lane.LEFT)
                    if all(abs(left_cell(r.dx_m, av_lane, grid) - grid.av_cell) <= 1 for r in (a, b))]
            return [((one.body, other.body), 0.0) for a, b in near for one, other in ((a, b), (b, a))]
        if kind is FaultKind.MERGED:
            return [((a.body, b.body), 0.0) for lane in Lane for a, b in _pairs(readings, lane)
                    if b.dx_m - a.dx_m <= 2 * cell]
        if kind is FaultKind.SPLIT:
            return [((r.body,), sign * cell) for r in readings for sign in (-1.0, 1.0)]
        if kind is FaultKind.DROPPED:
            return [((), 0.0)]
        lane = Lane.LEFT if kind is FaultKind.GHOST_LEFT else Lane.RIGHT
        low, high = (-GHOST_BEHIND_M, 0.0) if lane is Lane.LEFT else (-SENSORS.side_range_m, SENSORS.right_range_m)
        dx_m = float(rng.uniform(low, high))
        if any(r.lane is lane and abs(r.dx_m - dx_m) < CAR.length_m for r in readings):
            return []  # a vehicle is there: a ghost is only where none is
        return [((), dx_m)]

    @staticmethod
    def _apply(event: FaultEvent, readings: list[Reading]) -> list[Reading]:
        """The sweep as the fault under way changes it."""
        kind = event.kind
        by_body = {r.body: r for r in readings}
        if kind is FaultKind.GHOST_LEFT or kind is FaultKind.GHOST_ONCOMING:
            lane = Lane.LEFT if kind is FaultKind.GHOST_LEFT else Lane.RIGHT
            return [*readings, Reading(lane, GHOST_BODY, event.dx_m)]
        if kind is FaultKind.SPLIT:
            (body,) = event.bodies
            return [*readings, replace(by_body[body], dx_m=by_body[body].dx_m + event.dx_m)]
        first, second = (by_body[b] for b in event.bodies)
        rest = [r for r in readings if r.body not in event.bodies]
        if kind is FaultKind.FAKE_GAP:
            return [*rest, replace(first, dx_m=first.dx_m + event.dx_m), second]
        if kind is FaultKind.SAME_CELL:
            return [*rest, replace(first, dx_m=second.dx_m), second]
        # MERGED: one reading at the middle of the two
        return [*rest, replace(second, dx_m=(first.dx_m + second.dx_m) / 2)]


def attribute(body: int | None, in_snapshots: list[FaultEvent], steering: list[FaultEvent]) -> FaultEvent | None:
    """The fault a failure or stop is attributed to, by a rule stated once. ``in_snapshots``: the sensing faults that
    changed a snapshot a decision of the manoeuvre under way planned from (from its first decision in the left lane;
    for a stop, the snapshot it could not read), in order; ``steering``: the steering faults under way during it.
    First a steering fault (it moves the AV whatever the plan); then, for a collision (``body``: the vehicle in it),
    the last sensing fault that touched that vehicle, else the last one that touched no vehicle (a ghost, a dropped
    sweep: what it added or hid is no body), else the last sensing fault at all (what a fault adds holds the AV
    wherever its reading stands, whichever vehicle it was read from: measured, seed 25 of the reliability campaign
    at 1153285, a fake gap's copy of the vehicle ahead sat beside the AV and held the fallback in the right lane
    until an oncoming vehicle left no time); without a vehicle (a stop, a loss of control), the last sensing fault;
    else none."""
    if steering:
        return steering[-1]
    if body is not None:
        touched = [e for e in in_snapshots if body in e.bodies]
        bodiless = [e for e in in_snapshots if not e.bodies]
        if touched or bodiless:
            return (touched or bodiless)[-1]
    return in_snapshots[-1] if in_snapshots else None


class SteeringFault:
    """The steering fault: with its rate per sweep, an offset of ``FaultSpec.steering_offset_deg`` (to a side drawn
    at random) on the AV's steering for its persistence in sweeps."""

    def __init__(self, spec: FaultSpec, seed: int) -> None:
        self.injector = injectors(spec, seed).get(FaultKind.STEERING)
        self.offset_rad = math.radians(spec.steering_offset_deg)
        self.sweep = 0
        self.now_rad = 0.0  # the offset on the steering now

    @property
    def active(self) -> FaultEvent | None:
        """The steering fault under way, if any."""
        return None if self.injector is None else self.injector.active

    def end(self) -> None:
        """The fault under way ends now (the AV starts again after a failure)."""
        if self.injector is not None and self.injector.active is not None:
            self.injector.active.end_sweep = self.sweep
            self.injector.active = None
        self.now_rad = 0.0

    def on_sweep(self) -> float:
        """One sweep's time passes: a fault under way goes on or ends, a new one may start; the offset now."""
        self.sweep += 1
        injector = self.injector
        if injector is None:
            return 0.0
        if injector.active is not None and self.sweep >= injector.active.end_sweep:
            injector.active = None
        if injector.active is None:
            injector.offered += 1
            if injector.rng.random() < injector.fault.rate:
                side = 1.0 if injector.rng.random() < 0.5 else -1.0
                injector.started += 1
                injector.active = FaultEvent(FaultKind.STEERING, self.sweep, (), self.sweep +
                                             injector.fault.persistence_sweeps, offset_rad=side * self.offset_rad)
                injector.events.append(injector.active)
        if injector.active is not None:
            injector.active.sweeps += 1
        self.now_rad = 0.0 if injector.active is None else injector.active.offset_rad
        return self.now_rad
