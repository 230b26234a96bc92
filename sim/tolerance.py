"""The point of the simulator: does each vehicle move, relative to the AV, as the discrete model predicted?

Displacements are measured since the plan started, so the rounding of the initial
snapshot does not count: predicted = (predicted cell after step k) - (its cell at the
start); measured = (true distance now - true distance at the start). Both are reported in
cells of the paper's 21 m grid (``LOOP.tolerance_unit_m``) whatever grid the planner uses, so
a tolerance means the same distance on every grid. The deviation is their difference; each
action may add at most ``step`` cells of it, and a plan may accumulate at most ``plan`` cells.
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass, field
from typing import Any, Protocol

from sim.driver.discretiser import in_window, reading_cell
from sim.driver.readings import Reading
from spec.actions import Action
from spec.grid import Grid
from spec.kinds import ViolationKind
from spec.lanes import Lane
from spec.physical import CAR, LOOP
from spec.state import State

#: The deviation histograms' bin width and how many bins (beyond the last: one overflow bin), in tolerance units.
HISTOGRAM_BIN, HISTOGRAM_BINS = 0.02, 50


@dataclass(frozen=True, slots=True)
class Violation:
    """A deviation beyond tolerance: where, which vehicle, predicted and measured."""

    plan: int
    step: int
    action: str
    vehicle: str
    predicted_cells: float
    measured_cells: float
    kind: ViolationKind

    @property
    def deviation(self) -> float:
        return self.measured_cells - self.predicted_cells

    def to_json(self) -> dict[str, object]:
        return {**asdict(self), "kind": self.kind.value, "deviation_cells": round(self.deviation, 3)}


@dataclass(slots=True)
class ToleranceReport:
    """Deviations per action type, and every violation."""

    step_tolerance: float = LOOP.step_tolerance_cells
    plan_tolerance: float = LOOP.plan_tolerance_cells
    largest: dict[str, float] = field(default_factory=lambda: defaultdict(float))
    checks: dict[str, int] = field(default_factory=lambda: defaultdict(int))
    violations: list[Violation] = field(default_factory=list)  # this process's, in full (the trace has them too)
    violations_by_action: dict[str, int] = field(default_factory=lambda: defaultdict(int))
    #: per action, how many checks added a deviation in each bin of ``bin_cells`` cells (the last: beyond)
    histogram: dict[str, list[int]] = field(default_factory=dict)
    bin_cells: float = HISTOGRAM_BIN

    def check(self, plan: int, step: int, action: str, vehicle: str, predicted_m: float,
              start_dx_m: float, now_dx_m: float, previous_deviation: float) -> float:
        """Record one vehicle after one action (the model's predicted displacement in metres); return its deviation
        so far, in tolerance units."""
        unit = LOOP.tolerance_unit_m
        predicted_cells = predicted_m / unit
        measured = (now_dx_m - start_dx_m) / unit
        deviation = measured - predicted_cells
        added = abs(deviation - previous_deviation)
        self.largest[action] = max(self.largest[action], added)
        self.checks[action] += 1
        bins = self.histogram.setdefault(action, [0] * (HISTOGRAM_BINS + 1))
        bins[min(HISTOGRAM_BINS, int(added / self.bin_cells))] += 1
        kind = (ViolationKind.STEP if added > self.step_tolerance
                else ViolationKind.PLAN if abs(deviation) > self.plan_tolerance else None)
        if kind is not None:
            self.violations.append(Violation(plan, step, action, vehicle, predicted_cells, measured, kind))
            self.violations_by_action[action] += 1
        return deviation

    @property
    def violation_count(self) -> int:
        """How many violations, of every action (also when read back from JSON, without the records)."""
        return sum(self.violations_by_action.values())

    def to_json(self) -> dict[str, object]:
        return {"step_tolerance_cells": self.step_tolerance, "plan_tolerance_cells": self.plan_tolerance,
                "checks": dict(self.checks), "violations": self.violation_count,
                "violations_by_action": dict(self.violations_by_action),
                "largest_step_deviation_cells": {k: round(v, 3) for k, v in self.largest.items()},
                "added_histogram": {"bin_cells": self.bin_cells, "counts": self.histogram}}

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> ToleranceReport:
        """A report read back from ``to_json`` (counts and largest deviations; the violations are in the trace)."""
        report = cls(data["step_tolerance_cells"], data["plan_tolerance_cells"])
        report.checks.update(data["checks"])
        report.largest.update(data["largest_step_deviation_cells"])
        report.violations_by_action.update(data["violations_by_action"])
        report.histogram.update(data["added_histogram"]["counts"])
        report.bin_cells = float(data["added_histogram"]["bin_cells"])
        return report



def histogram_quantile(bins: list[int], q: float) -> float | None:
    """The ``q`` quantile of a deviation histogram: the upper edge of its bin, ``math.inf`` in the overflow bin
    (beyond the last edge), None for an empty histogram."""
    if not sum(bins):
        return None
    target, seen = q * sum(bins), 0
    for i, count in enumerate(bins[:-1]):
        seen += count
        if count and seen >= target:
            return round((i + 1) * HISTOGRAM_BIN, 3)
    return math.inf


#: A vehicle the tolerance check follows: its lane, its index in the scenario's lane, and its body.
Key = tuple[Lane, int, int]


def followed(seen: tuple[Reading, ...], start: State, grid: Grid) -> dict[Key, tuple[float, int]]:
    """Each vehicle sensed in the plan's window (``seen``, in the plan's frame), keyed by its lane and index in the
    scenario, with its distance ahead of the AV at the plan's start and its cell in the plan's ``start`` state."""
    out = {}
    for lane, cells in ((Lane.LEFT, start.left_lane), (Lane.RIGHT, start.right_lane)):
        readings = sorted((r for r in seen if r.lane is lane), key=lambda r: r.dx_m)
        inside = [r for r in readings if in_window(reading_cell(r, start.lane, grid), grid)]
        for index, reading in enumerate(inside):
            out[(lane, index, reading.body)] = (reading.dx_m, cells[index])
    return out


def implied_gaps(vehicles: dict[Key, tuple[float, int]], predicted: State, grid: Grid) -> dict[int, float]:
    """Per followed vehicle, the bumper-to-bumper gap to the AV (ahead or behind) its predicted cell's centre
    implies."""
    gaps = {}
    for lane, index, body in vehicles:
        cells = predicted.left_lane if lane is Lane.LEFT else predicted.right_lane
        gaps[body] = abs(cells[index] - grid.av_cell) * grid.cell - CAR.length_m
    return gaps


class Followed(Protocol):
    """A vehicle as the tolerance check follows it: its body, how often it respawned, its place along the road."""

    @property
    def body(self) -> int: ...

    @property
    def respawns(self) -> int: ...

    @property
    def x_m(self) -> float: ...


class PlanCheck:
    """One paper-model plan's prediction held against the truth as it executes (``sim.driver.paper.Prediction``):
    after each action, each vehicle sensed in the plan's window (``seen``) against its predicted cell in ``states``,
    recorded in ``report`` and told to ``observe`` (step, action, predicted state, the new violations); while an
    action is under way, the gap each vehicle's predicted cell implies (``implied``, for the safety measures). A
    vehicle respawned since the plan started is a different vehicle, no longer followed; a ghost a fault injected is
    none (``sim.faults``)."""

    def __init__(self, report: ToleranceReport, plan_id: int, seen: tuple[Reading, ...], states: tuple[State, ...],
                 grid: Grid, cars: Callable[[], Iterable[Followed]], av_x_m: Callable[[], float],
                 observe: Callable[[int, Action, State, list[Violation]], None]) -> None:
        self.report, self.plan_id, self.states, self.grid = report, plan_id, states, grid
        self.cars, self.av_x_m, self.observe = cars, av_x_m, observe
        self.at_start = {car.body: car for car in cars()}
        self.tracked = {key: v for key, v in followed(seen, states[0], grid).items() if key[2] in self.at_start}
        self.deviation = dict.fromkeys(self.tracked, 0.0)
        self.generation = {body: car.respawns for body, car in self.at_start.items()}
        self.implied: dict[int, float] = {}  # body -> the gap the action under way implies at its end

    def expecting(self, k: int | None) -> None:
        """The plan's action ``k`` (from 0) is under way: the gaps its predicted state implies (None: no action)."""
        self.implied = {} if k is None else implied_gaps(
            {key: v for key, v in self.tracked.items() if self._same(key[2])}, self.states[k + 1], self.grid)

    def _same(self, body: int) -> bool:
        """Whether ``body`` is still the vehicle the plan was made with (not respawned since)."""
        return self.at_start[body].respawns == self.generation[body]

    def deviated(self, k: int, action: Action) -> bool:
        """After the plan's action ``k``: check every followed vehicle and tell the observers; whether any broke the
        tolerance."""
        before = len(self.report.violations)
        now = {car.body: car.x_m - self.av_x_m() for car in self.cars()}
        predicted = self.states[k + 1]
        for (lane, index, body), (start_dx, start_cell) in self.tracked.items():
            if not self._same(body):
                continue  # respawned ahead since the plan started: a different vehicle now
            cells = predicted.left_lane if lane is Lane.LEFT else predicted.right_lane
            self.deviation[(lane, index, body)] = self.report.check(
                self.plan_id, k + 1, action.value, f"{lane.value}_lane[{index}]",
                (cells[index] - start_cell) * self.grid.cell, start_dx, now[body],
                self.deviation[(lane, index, body)])
        new = self.report.violations[before:]
        self.observe(k + 1, action, predicted, new)
        return bool(new)
