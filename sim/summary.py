"""What one drive did: distances, counts, planning latency, failures and the tolerance report, as data.

A summary goes to JSON and back unchanged (``to_json``/``from_json``), so a campaign can
write each finished run as one line and resume from the lines it finds.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from sim.containment import ContainmentReport
from sim.opportunity import OpportunityReport
from sim.safety import SafetyReport
from sim.tolerance import ToleranceReport
from spec.faults import FaultKind
from spec.kinds import FailureKind


@dataclass(frozen=True, slots=True)
class Failure:
    """One failure: its kind, a short cause for tables, the full story, and where it happened."""

    kind: FailureKind
    cause: str  # e.g. "collision with an oncoming vehicle", "no_plan"
    detail: str
    km: float
    t_s: float
    fault: str | None = None  # the fault it is attributed to (``sim.faults.attribute``), if any
    flagged: bool | None = None  # with tracking: whether the tracker flagged a contradiction in its manoeuvre


@dataclass(slots=True)
class Takeover:
    """One take-over of the fallback (``spec.envelope.MinimalRisk``): where, why, from which lane, how it ended."""

    km: float
    t_s: float
    cause: str
    lane: str
    after_breach: bool  # a vehicle had broken the assumptions of the decision before it (or of the take-over before)
    outcome: str = "under way"  # "handed back", "taken over again", "collision"


@dataclass(slots=True)
class RunSummary:
    """What one drive did."""

    seed: int
    km: float = 0.0
    sim_time_s: float = 0.0
    wall_s: float = 0.0
    overtakes: int = 0
    plans: int = 0
    replans: int = 0
    kept_plans: list[Failure] = field(default_factory=list)  # re-plans without a plan while one was under way
    frame_fallbacks: int = 0  # plans made in the common-speed frame: none was consistent with its own frame
    actions: int = 0
    plan_ms: list[float] = field(default_factory=list)
    failures: list[Failure] = field(default_factory=list)
    tolerance: ToleranceReport = field(default_factory=ToleranceReport)
    safety: SafetyReport = field(default_factory=SafetyReport)
    traffic_collisions: int = 0  # other vehicles touching each other (the traffic models that do not keep to the grid)
    snapshots: list[dict[str, Any]] = field(default_factory=list)  # scenarios planned for, as files write them
    restarts: int = 0  # fresh starts after a collision (``restart_after_collision``)
    opportunities: OpportunityReport = field(default_factory=OpportunityReport)
    decisions: int = 0  # snapshots containment was measured from (every decision, both models)
    containment: ContainmentReport = field(default_factory=ContainmentReport)
    breach_replans: int = 0  # sound decisions ended by a breach
    reversed_moves: int = 0  # sideways moves a breach sent back (``MinimalRisk``'s cut-short move)
    #: sideways moves a breach ended whose rest a decision proved and took over: finished, or undone
    moves_finished: int = 0
    moves_undone: int = 0
    moves_unproved: int = 0  # sideways moves a breach ended with neither way proved (the fallback's rule decides)
    sensed_breaches: int = 0  # sound decisions whose readings the AV's own monitor could not explain
    unseen_breaches: int = 0  # sound decisions that went on past a vehicle's breach the AV never sensed
    keep_lane_steps: int = 0  # sound decisions without an overtake: one safe step in lane
    minimal_risk_steps: int = 0  # sound decisions without a plan or a step: the last decision's proved continuation
    committed_parts: int = 0  # sound decisions (commitment semantics) that executed a committed part with an escape
    escapes: int = 0  # sound decisions that proved nothing and kept the last one's rest and its proved escape
    unsafe_starts: int = 0  # sound decisions whose snapshot already broke the safety specification (no failure)
    #: sound decisions that planned from the proved reference the car runs on, not from the car
    #: (``SoundDriver.reference_start``, ``sim.driver.decide.plan_start``)
    reference_starts: int = 0
    #: sound decisions whose snapshot the last proof's sets narrowed (``SoundDriver.refined``, ``Monitor.refine``)
    refined_starts: int = 0
    shadowed: int = 0  # sound decisions whose snapshot had the oncoming lane hidden behind a left-lane vehicle
    takeovers: list[Takeover] = field(default_factory=list)
    sweeps: int = 0  # the sensors' sweeps (``spec.physical.SENSORS.sweep_hz``)
    refusals: int = 0  # with tracking: overtakes not started while a lane held a contradiction (no failure)
    faults: dict[str, dict[str, int]] = field(default_factory=dict)  # per kind: sweeps that offered it, starts, sweeps

    def of_kind(self, kind: FailureKind) -> list[Failure]:
        return [f for f in self.failures if f.kind is kind]

    @property
    def collisions(self) -> list[Failure]:
        return self.of_kind(FailureKind.COLLISION)

    @property
    def planner_failures(self) -> list[Failure]:
        return self.of_kind(FailureKind.PLANNER)

    @property
    def failure(self) -> Failure | None:
        """The first failure of the most serious kind, if the drive had one."""
        return next((f for kind in FailureKind for f in self.of_kind(kind)), None)

    @property
    def crash(self) -> Failure | None:
        """The first failure proper (a collision or a loss of control: ``FailureKind.ends_run``), if any."""
        return next((f for f in self.failures if f.kind.ends_run), None)

    @property
    def sensing_crash(self) -> Failure | None:
        """The first failure proper attributed to a sensing fault (``sim.faults.attribute``): what the reliability
        target counts (km between sensing-caused failures), if any."""
        return next((f for f in self.failures if f.kind.ends_run and f.fault is not None
                     and FaultKind(f.fault).sensing), None)

    def ended(self, sensing_only: bool) -> Failure | None:
        """The failure that ends a drive until failure: the first one proper, or with ``sensing_only`` the first a
        sensing fault caused (the others restart the drive and are counted apart)."""
        return self.sensing_crash if sensing_only else self.crash

    @property
    def stops(self) -> list[Failure]:
        """Stops that are no failure: a snapshot that could not be read, no plan found."""
        return [f for f in self.failures if not f.kind.ends_run]

    def latency_ms(self) -> dict[str, float]:
        """Median, p99 and max planning time, from the samples as recorded (to the microsecond)."""
        ms = np.round(np.array(self.plan_ms), 3) if self.plan_ms else np.zeros(1)
        return {"median": round(float(np.median(ms)), 3), "p99": round(float(np.percentile(ms, 99)), 3),
                "max": round(float(ms.max()), 3)}

    def to_json(self) -> dict[str, Any]:
        failure = self.failure
        return {"seed": self.seed, "km": round(self.km, 3), "sim_time_s": round(self.sim_time_s, 1),
                "wall_s": round(self.wall_s, 2), "overtakes": self.overtakes, "plans": self.plans,
                "replans": self.replans, "kept_plans": [failure_json(f) for f in self.kept_plans],
                "frame_fallbacks": self.frame_fallbacks, "actions": self.actions,
                "plan_ms": [round(m, 3) for m in self.plan_ms],
                "plan_latency_ms": self.latency_ms(), "failures": [failure_json(f) for f in self.failures],
                "failure": failure_json(failure) if failure else None, "tolerance": self.tolerance.to_json(),
                "safety": self.safety.to_json(), "traffic_collisions": self.traffic_collisions,
                "snapshots": self.snapshots, "restarts": self.restarts, "opportunities": self.opportunities.to_json(),
                "decisions": self.decisions, "containment": self.containment.to_json(),
                "breach_replans": self.breach_replans, "reversed_moves": self.reversed_moves,
                "moves_finished": self.moves_finished, "moves_undone": self.moves_undone,
                "moves_unproved": self.moves_unproved, "sensed_breaches": self.sensed_breaches,
                "unseen_breaches": self.unseen_breaches, "keep_lane_steps": self.keep_lane_steps,
                "minimal_risk_steps": self.minimal_risk_steps, "committed_parts": self.committed_parts,
                "escapes": self.escapes, "unsafe_starts": self.unsafe_starts,
                "reference_starts": self.reference_starts, "refined_starts": self.refined_starts,
                "shadowed": self.shadowed,
                "takeovers": [asdict(t) for t in self.takeovers], "sweeps": self.sweeps, "faults": self.faults,
                "refusals": self.refusals}

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> RunSummary:
        return cls(seed=data["seed"], km=data["km"], sim_time_s=data["sim_time_s"], wall_s=data["wall_s"],
                   overtakes=data["overtakes"], plans=data["plans"], replans=data["replans"],
                   kept_plans=[failure_from(f) for f in data["kept_plans"]],
                   frame_fallbacks=data["frame_fallbacks"], actions=data["actions"], plan_ms=list(data["plan_ms"]),
                   failures=[failure_from(f) for f in data["failures"]],
                   tolerance=ToleranceReport.from_json(data["tolerance"]),
                   safety=SafetyReport.from_json(data["safety"]), traffic_collisions=data["traffic_collisions"],
                   snapshots=list(data["snapshots"]), restarts=data.get("restarts", 0),
                   opportunities=OpportunityReport.from_json(data["opportunities"]) if "opportunities" in data
                   else OpportunityReport(), decisions=data.get("decisions", 0),
                   containment=ContainmentReport.from_json(data["containment"]) if "containment" in data
                   else ContainmentReport(), breach_replans=data.get("breach_replans", 0),
                   reversed_moves=data.get("reversed_moves", 0), moves_finished=data.get("moves_finished", 0),
                   moves_undone=data.get("moves_undone", 0), moves_unproved=data.get("moves_unproved", 0),
                   sensed_breaches=data.get("sensed_breaches", 0), unseen_breaches=data.get("unseen_breaches", 0),
                   keep_lane_steps=data.get("keep_lane_steps", 0), minimal_risk_steps=data.get("minimal_risk_steps", 0),
                   committed_parts=data.get("committed_parts", 0), escapes=data.get("escapes", 0),
                   unsafe_starts=data.get("unsafe_starts", 0), reference_starts=data.get("reference_starts", 0),
                   refined_starts=data.get("refined_starts", 0),
                   takeovers=[Takeover(**t) for t in data.get("takeovers", [])], sweeps=data.get("sweeps", 0),
                   refusals=data.get("refusals", 0), shadowed=data.get("shadowed", 0),
                   faults={k: dict(v) for k, v in data.get("faults", {}).items()})


def failure_json(failure: Failure) -> dict[str, Any]:
    """A failure as JSON (its kind by name)."""
    return {**asdict(failure), "kind": failure.kind.value}


def failure_from(data: dict[str, Any]) -> Failure:
    """A failure read back from ``failure_json``."""
    return Failure(**{**data, "kind": FailureKind(data["kind"])})
