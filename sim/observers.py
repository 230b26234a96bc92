"""Observers of a drive: told about every executed action, they record without steering anything.

A simulator hands each observer a ``StepEvent`` after every action of a model-checked plan;
``TraceWriter`` writes them as JSON lines (the space-time plots are drawn from that trace).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import IO, Protocol

from sim.tolerance import Violation
from spec.actions import Action
from spec.state import State


@dataclass(frozen=True, slots=True)
class StepEvent:
    """One executed action: where and when, what the model predicted, and what was measured."""

    t_s: float
    km: float
    plan: int
    step: int
    action: Action
    av_x_m: float
    av_y_m: float
    av_speed_mps: float
    measured_dx_m: dict[str, list[float]]  # per lane, every vehicle's distance ahead of the AV
    predicted: State
    violations: tuple[Violation, ...]


class Observer(Protocol):
    """Anything that wants to hear about each executed action."""

    def on_step(self, event: StepEvent) -> None: ...


class TraceWriter:
    """Writes one JSON object per executed action to a stream."""

    def __init__(self, stream: IO[str]) -> None:
        self.stream = stream

    def on_step(self, event: StepEvent) -> None:
        self.stream.write(json.dumps({
            "t_s": round(event.t_s, 2), "km": round(event.km, 4), "plan": event.plan, "step": event.step,
            "action": event.action.value,
            "av": {"x_m": round(event.av_x_m, 2), "y_m": round(event.av_y_m, 2),
                   "speed_mps": round(event.av_speed_mps, 2)},
            "measured_dx_m": {lane: sorted(round(d, 1) for d in ds) for lane, ds in event.measured_dx_m.items()},
            "predicted": {"left_lane": list(event.predicted.left_lane),
                          "right_lane": list(event.predicted.right_lane)},
            "violations": [v.to_json() for v in event.violations]}) + "\n")
