"""Observers of a drive: told about every executed action, they record without steering anything.

A simulator hands each observer a ``StepEvent`` after every action of a model-checked plan, and under the sound
model after every action of a decision and at the end of each fallback or minimal-risk manoeuvre (no cells
predicted: the sound model's sets are intervals, which the containment monitor checks); ``TraceWriter`` writes them
as JSON lines (the space-time plots are drawn from that trace).
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
    """One executed action (or a fallback's control, ``action`` None): where and when, what the model predicted (the
    paper model's cells; None under the sound model), what was measured, and, without cells, what the AV was doing and
    for how long."""

    t_s: float
    km: float
    plan: int
    step: int
    action: Action | None
    av_x_m: float
    av_y_m: float
    av_speed_mps: float
    measured_dx_m: dict[str, list[float]]  # per lane, every vehicle's distance ahead of the AV
    predicted: State | None
    violations: tuple[Violation, ...]
    doing: str = ""
    duration_s: float = 0.0


class Observer(Protocol):
    """Anything that wants to hear about each executed action."""

    def on_step(self, event: StepEvent) -> None: ...


class TraceWriter:
    """Writes one JSON object per executed action to a stream."""

    def __init__(self, stream: IO[str]) -> None:
        self.stream = stream

    def on_step(self, event: StepEvent) -> None:
        record = {
            "t_s": round(event.t_s, 2), "km": round(event.km, 4), "plan": event.plan, "step": event.step,
            "action": None if event.action is None else event.action.value,
            "av": {"x_m": round(event.av_x_m, 2), "y_m": round(event.av_y_m, 2),
                   "speed_mps": round(event.av_speed_mps, 2)},
            "measured_dx_m": {lane: sorted(round(d, 1) for d in ds) for lane, ds in event.measured_dx_m.items()},
            "predicted": None if event.predicted is None else {"left_lane": list(event.predicted.left_lane),
                                                               "right_lane": list(event.predicted.right_lane)},
            "violations": [v.to_json() for v in event.violations]}
        if event.predicted is None:  # the paper model's records stay as they were (tests/sim/golden)
            record.update(doing=event.doing, duration_s=round(event.duration_s, 2))
        self.stream.write(json.dumps(record) + "\n")
