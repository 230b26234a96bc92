"""The point of the simulator: does each vehicle move, relative to the AV, as the discrete model predicted?

Displacements are measured since the plan started, so the rounding of the initial
snapshot does not count: predicted = (predicted cell after step k) - (its cell at the
start); measured = (true distance now - true distance at the start) / SEGMENT_M. The
deviation is their difference; each action may add at most ``step`` cells of it, and a
plan may accumulate at most ``plan`` cells.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass, field

from spec.constants import SEGMENT_M
from spec.physical import LOOP


@dataclass(frozen=True, slots=True)
class Violation:
    """A deviation beyond tolerance: where, which vehicle, predicted and measured."""

    plan: int
    step: int
    action: str
    vehicle: str
    predicted_cells: float
    measured_cells: float
    kind: str  # "step" or "plan"

    @property
    def deviation(self) -> float:
        return self.measured_cells - self.predicted_cells


@dataclass(slots=True)
class ToleranceReport:
    """Deviations per action type, and every violation."""

    step_tolerance: float = LOOP.step_tolerance_cells
    plan_tolerance: float = LOOP.plan_tolerance_cells
    largest: dict[str, float] = field(default_factory=lambda: defaultdict(float))
    checks: dict[str, int] = field(default_factory=lambda: defaultdict(int))
    violations: list[Violation] = field(default_factory=list)

    def check(self, plan: int, step: int, action: str, vehicle: str, predicted_cells: float,
              start_dx_m: float, now_dx_m: float, previous_deviation: float) -> float:
        """Record one vehicle after one action; return its deviation so far (cells)."""
        measured = (now_dx_m - start_dx_m) / SEGMENT_M
        deviation = measured - predicted_cells
        added = abs(deviation - previous_deviation)
        self.largest[action] = max(self.largest[action], added)
        self.checks[action] += 1
        if added > self.step_tolerance:
            self.violations.append(Violation(plan, step, action, vehicle, predicted_cells, measured, "step"))
        elif abs(deviation) > self.plan_tolerance:
            self.violations.append(Violation(plan, step, action, vehicle, predicted_cells, measured, "plan"))
        return deviation
