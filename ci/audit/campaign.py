"""The audit: how far the grid abstraction can be trusted, against traffic and sensing that do not keep to it.

Every combination of a cell size, a traffic model and a sensing model (``sim.parts`` registries)
is driven for the stated kilometres on each seed, through the campaign executors; each finished
run is appended to ``OUT/audit.jsonl`` with its combination, so an interrupted audit started
again runs only what is missing. Per combination the audit reports collisions and near misses
per 1,000 km, each with its cause (the action under way, the model rule that should have kept
the vehicle away, the true gap beside the gap the plan's cells implied), the deviation each
action type added (quantiles over every check), and, on the scenarios the planner actually saw
at that cell size (``snapshots`` per run), what planning costs each engine: latency and states
explored. A collision does not end a run: the drive starts again where it stands
(``restart_after_collision``), so collisions per 1,000 km are over the whole distance. Missed
opportunities (``sim.opportunity``): decisions where the planner did not start an overtake but a
canonical overtake replayed in physics from that moment succeeded, estimated per 1,000 km from
the sampled checks.
"""

from __future__ import annotations

import contextlib
import json
import math
import time
from collections import Counter
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from ci.shared.executors import ExecutorChoice, run_jobs
from ci.shared.records import append, campaign_lock, open_for_append, read_records
from ci.simulation.campaign import campaign_key, recorded_runs
from oracle.planner import plan
from sim.opportunity import Refusal
from sim.parts import DriveConfig, loop_semantics
from sim.report import pyplot
from sim.safety import attribution_key
from sim.simulator import run_drive
from sim.summary import RunSummary
from sim.tolerance import HISTOGRAM_BIN, histogram_quantile
from spec.answers import Limits, Status, Strategy
from spec.engines import answers, get_engine
from spec.errors import OptionError
from spec.escapes import Semantics
from spec.files import scenario_from_dict
from spec.grid import STANDARD_CELLS_M
from spec.kinds import FailureKind
from spec.physical import LOOP
from spec.scenario import Scenario

AUDIT_FILE = "audit.jsonl"
MISSED_EXAMPLES = 3  # missed opportunities reported per combination with their scenario
ACTIONS = ("accelerate", "brake", "drive", "left_lane_change", "right_lane_change")


@dataclass(frozen=True)
class AuditPlan:
    """What an audit drives: the combinations, the seeds, the distance per run, and the drive settings they share."""

    cells_m: tuple[float, ...] = tuple(float(c) for c in STANDARD_CELLS_M)
    traffic: tuple[str, ...] = ("paper", "spread", "following")
    sensing: tuple[str, ...] = ("exact", "noisy")
    seeds: tuple[int, ...] = (1,)
    base: DriveConfig = field(default_factory=lambda: DriveConfig(km=25.0, snapshots=20, restart_after_collision=True,
                                                                  opportunity_checks=50))
    models: tuple[str, ...] = ("paper",)
    bounds_scales: tuple[float, ...] = (1.0,)
    #: how the sound model decides (each one a combination of its own; the paper model's are whole plans); by default
    #: as the loop has it decide (``sim.parts.loop_semantics``)
    semantics: tuple[Semantics, ...] = field(default_factory=lambda: (loop_semantics("sound"),))

    def configs(self) -> list[DriveConfig]:
        """One drive configuration per combination, in table order (validated: bad input raises here)."""
        return [replace(self.base, cell_m=cell, traffic=traffic, sensor=sensing, model=model, bounds_scale=scale,
                        semantics=semantics)
                for cell in self.cells_m for traffic in self.traffic for sensing in self.sensing
                for model in self.models for semantics in (self.semantics if model == "sound" else
                                                           (loop_semantics(model),))
                for scale in self.bounds_scales]


#: What each combination sets itself; every other setting of a drive is the audit's, and must match to resume.
PER_COMBINATION = ("cell_m", "traffic", "sensor", "model", "bounds_scale", "semantics")


def check_resume(log: Path, audit: AuditPlan, where: str) -> None:
    """Refuse to resume an audit whose recorded runs were driven with other shared settings (``--km``, noise,
    events ...), naming the first difference: runs of two configurations are never mixed into one figure."""
    asked = {k: v for k, v in audit.base.all_json().items() if k not in PER_COMBINATION}
    for record in read_records(log):
        campaign = record.get("campaign") if isinstance(record, dict) else None
        if not isinstance(campaign, dict):
            continue
        try:
            recorded = DriveConfig.from_json(campaign).all_json()
        except (TypeError, ValueError, OptionError):
            continue  # a record of another version: run again, never mixed
        for key, value in asked.items():
            if recorded.get(key) != value:
                raise OptionError(where, str(log.parent), f"holds runs with {key} = {recorded.get(key)!r}, this "
                                  f"audit asks {value!r}; --fresh starts again, or use another --out")


@dataclass(frozen=True, slots=True)
class Done:
    """One finished run of one combination."""

    config: DriveConfig
    summary: RunSummary


def audit_one(index: int, seed: int, config: DriveConfig,
              report: Callable[[tuple[int, float]], None] | None = None) -> tuple[int, RunSummary]:
    """One run of the audit (what a worker runs); progress is reported as (job index, km)."""
    hear = None if report is None else (lambda update: report((index, update[1])))
    return index, run_drive(seed, config, None, hear)


def run_audit(audit: AuditPlan, out_dir: str, executor: ExecutorChoice, fresh: bool = False,
              on_done: Callable[[int, Done, bool], None] | None = None,
              on_km: Callable[[tuple[int, float]], None] | None = None) -> list[Done]:
    """Drive every (combination, seed) not already recorded in ``out_dir``; ``on_done(job, done, resumed)`` after
    each; results in job order (combination by combination, seed by seed)."""
    out = Path(out_dir)
    with campaign_lock(out):
        return _run_audit(audit, out, executor, fresh, on_done, on_km)


def _run_audit(audit: AuditPlan, out: Path, executor: ExecutorChoice, fresh: bool,
               on_done: Callable[[int, Done, bool], None] | None,
               on_km: Callable[[tuple[int, float]], None] | None) -> list[Done]:
    log = out / AUDIT_FILE
    if fresh:
        log.unlink(missing_ok=True)
    check_resume(log, audit, "--out")
    jobs = [(config, seed) for config in audit.configs() for seed in audit.seeds]
    recorded = recorded_runs(log)
    results: dict[int, Done] = {}
    for index, (config, seed) in enumerate(jobs):
        summary = recorded.get((campaign_key(config), seed))
        if summary is not None:
            results[index] = Done(config, summary)
            if on_done:
                on_done(index, results[index], True)
    todo = [(index, seed, config) for index, (config, seed) in enumerate(jobs) if index not in results]
    with open_for_append(log) as lines, contextlib.closing(run_jobs(audit_one, todo, executor, on_km)) as finished:
        for _, (index, summary) in finished:
            config = jobs[index][0]
            append(lines, {"campaign": config.to_json(), "run": summary.to_json()})
            results[index] = Done(config, summary)
            if on_done:
                on_done(index, results[index], False)
    return [results[i] for i in range(len(jobs))]


# -- what the audit reports -----------------------------------------------------------------------
@dataclass(slots=True)
class Row:
    """One combination's figures."""

    cell_m: float
    traffic: str
    sensing: str
    runs: int
    km: float
    collisions: int
    near_misses: int
    traffic_collisions: int
    causes: dict[str, int]  # "kind: lane, rule, action" -> count, over contacts and near misses
    worst: list[dict[str, Any]]  # the encounters with the smallest true gap, with their implied gaps
    min_gap_left_m: float | None
    min_gap_oncoming_m: float | None
    deviation: dict[str, dict[str, float | None]]  # action -> p50, p95, max of what one action added (cells)
    violations: int
    plan_ms_median: float | None
    opportunities: dict[str, dict[str, int]]  # refusal -> qualifying, checked and each outcome's count
    missed_examples: list[dict[str, Any]]  # the first missed opportunities, each with its scenario
    model: str = "paper"
    bounds_scale: float = 1.0
    overtakes: int = 0
    decisions: int = 0  # snapshots decided from (containment measured from each)
    attributed: dict[str, int] = field(default_factory=dict)  # "contact inside", "near_miss after", ...
    breaches: dict[str, int] = field(default_factory=dict)  # by kind (``sim.driver.monitor.BreachKind``)
    breached_share: float | None = None  # of the time under containment, the share after a breach that ends it
    breach_replans: int = 0
    keep_lane_steps: int = 0
    minimal_risk_steps: int = 0
    takeovers: int = 0
    takeovers_after_breach: int = 0
    waits_without_plan: int = 0  # planner failures (no plan, or none in time, and none under way)
    losses_of_control: int = 0  # the AV spun or left the road (``spec.faults.lost_control``)
    unreadable: int = 0  # snapshots that could not be read (a sensing stop, never a failure)
    faults: dict[str, dict[str, int]] = field(default_factory=dict)  # kind -> started, sweeps changed, failures
    #: plans the planner took longer for on this machine than the loop's budget (``LOOP.plan_budget_s``), which the
    #: drive counted as that long (``sim.simulator``): each a plan that would have acted late (machine-dependent)
    late_plans: int = 0
    blocked: int = 0  # episodes given up because the AV stood (``sim.simulator.BLOCKED_S``; a stop, never a failure)
    semantics: str = Semantics.WHOLE.value  # how the sound model decided (``spec.escapes.Semantics``)
    reversed_moves: int = 0  # sideways moves a breach sent back (``MinimalRisk``'s cut-short move)
    #: sideways moves a breach ended that a decision proved and took over: finished, undone; and with neither proved
    moves_finished: int = 0
    moves_undone: int = 0
    moves_unproved: int = 0
    unsafe_starts: int = 0  # sound decisions whose snapshot already broke the safety specification (no failure)

    def per_1000_km(self, count: float) -> float:
        return 1000 * count / self.km if self.km else math.nan

    def fault_cell(self, kind: str) -> str:
        """One fault kind's faults started / sweeps changed / failures attributed, as the tables print them."""
        return " / ".join(str(self.faults.get(kind, {}).get(x, 0)) for x in ("started", "sweeps", "failures"))

    def attributed_count(self, kind: str, inside: bool) -> int:
        return self.attributed.get(attribution_key(kind, inside), 0)

    def inside_after(self, kind: str) -> str:
        """Contacts or near misses (``kind``) per 1,000 km, inside / after the assumptions, as tables print them."""
        return " / ".join(figure(self.per_1000_km(self.attributed_count(kind, inside))) for inside in (True, False))

    @property
    def collisions_per_1000_km(self) -> float:
        return self.per_1000_km(self.collisions)

    @property
    def near_misses_per_1000_km(self) -> float:
        return self.per_1000_km(self.near_misses)

    def opportunity_total(self, what: str) -> int:
        return sum(counts.get(what, 0) for counts in self.opportunities.values())

    @property
    def missed_per_1000_km(self) -> float:
        """Missed opportunities proper: the planner found no overtake (refused, or nothing in its window)."""
        return self._estimated_per_1000_km((Refusal.REFUSED, Refusal.OUTSIDE_WINDOW))

    @property
    def delayed_per_1000_km(self) -> float:
        """Overtakes planned to start later where one started now succeeded in physics."""
        return self._estimated_per_1000_km((Refusal.DELAYED,))

    def _estimated_per_1000_km(self, refusals: tuple[Refusal, ...]) -> float:
        """Per refusal, the share of checked decisions whose replay succeeded, times the decisions that qualified;
        NaN when a refusal that qualified was never checked."""
        if not self.km:
            return math.nan
        total = 0.0
        for refusal in refusals:
            counts = self.opportunities.get(refusal.value, {})
            if counts.get("qualifying", 0):
                if not counts.get("checked", 0):
                    return math.nan
                total += counts.get("missed", 0) / counts["checked"] * counts["qualifying"]
        return 1000 * total / self.km

    def to_json(self) -> dict[str, Any]:
        return {"cell_m": self.cell_m, "traffic": self.traffic, "sensing": self.sensing, "runs": self.runs,
                "km": round(self.km, 2), "collisions": self.collisions, "near_misses": self.near_misses,
                "collisions_per_1000_km": _num(self.collisions_per_1000_km),
                "near_misses_per_1000_km": _num(self.near_misses_per_1000_km),
                "traffic_collisions": self.traffic_collisions, "causes": self.causes, "worst": self.worst,
                "min_gap_left_m": self.min_gap_left_m, "min_gap_oncoming_m": self.min_gap_oncoming_m,
                "deviation_cells": self.deviation, "violations": self.violations,
                "plan_ms_median": self.plan_ms_median, "opportunities": self.opportunities,
                "missed_opportunities_per_1000_km_estimated": _num(self.missed_per_1000_km),
                "delayed_overtakes_per_1000_km_estimated": _num(self.delayed_per_1000_km),
                "missed_examples": self.missed_examples, "model": self.model, "bounds_scale": self.bounds_scale,
                "semantics": self.semantics, "unsafe_starts": self.unsafe_starts,
                "overtakes": self.overtakes, "overtakes_per_km": _num(self.per_1000_km(self.overtakes) / 1000),
                "decisions": self.decisions, "attributed": self.attributed, "breaches": self.breaches,
                "breaches_per_1000_km": _num(self.per_1000_km(sum(self.breaches.values()))),
                "breached_share": self.breached_share, "breach_replans": self.breach_replans,
                "reversed_moves": self.reversed_moves, "moves_finished": self.moves_finished,
                "moves_undone": self.moves_undone, "moves_unproved": self.moves_unproved,
                "keep_lane_steps": self.keep_lane_steps, "minimal_risk_steps": self.minimal_risk_steps,
                "takeovers": self.takeovers, "takeovers_after_breach": self.takeovers_after_breach,
                "waits_without_plan": self.waits_without_plan, "losses_of_control": self.losses_of_control,
                "unreadable_snapshots": self.unreadable, "faults": self.faults, "late_plans": self.late_plans,
                "blocked": self.blocked, "plan_budget_ms": _num(1000 * LOOP.plan_budget_s)}


def figure(value: float | None, digits: int = 1) -> str:
    """A rate or estimate as tables print it: "-" where it is undefined (no km driven, or an estimate whose
    refusals were never replayed), never "nan"."""
    return "-" if value is None or not math.isfinite(value) else f"{value:.{digits}f}"


def _num(value: float | None) -> float | None:
    return None if value is None or not math.isfinite(value) else round(value, 2)


Key = tuple[float, str, str, str, float, str]  # cell, traffic, sensing, model, bounds scale, semantics


def rows(results: Iterable[Done]) -> list[Row]:
    """One row per combination, in the order the combinations were first met."""
    groups: dict[Key, list[RunSummary]] = {}
    for done in results:
        c = done.config
        groups.setdefault((c.cell_m, c.traffic, c.sensor, c.model, c.bounds_scale, c.decides.value),
                          []).append(done.summary)
    return [_row(key, runs) for key, runs in groups.items()]


def _row(key: Key, runs: list[RunSummary]) -> Row:
    encounters = [e for r in runs for e in r.safety.encounters]
    causes = Counter(f"{e.kind}: {e.lane}, {e.rule}, {e.doing.split(' ')[0]}"
                     + (" (kept plan)" if "kept plan" in e.doing else "")
                     + (" (reversed)" if " reversed " in e.doing else "") for e in encounters)
    worst = sorted(encounters, key=lambda e: e.gap_m)[:5]
    deviation = {}
    for action in ACTIONS:
        histograms = [r.tolerance.histogram[action] for r in runs if action in r.tolerance.histogram]
        if histograms:
            bins = [sum(column) for column in zip(*histograms)]
            largest = math.ceil(1000 * max(r.tolerance.largest.get(action, 0.0) for r in runs)) / 1000  # up: a bound
            deviation[action] = {"p50": _at_most(histogram_quantile(bins, 0.5), largest),
                                 "p95": _at_most(histogram_quantile(bins, 0.95), largest), "max": largest}
    gaps_left = [r.safety.min_gap_left_m for r in runs if math.isfinite(r.safety.min_gap_left_m)]
    gaps_oncoming = [r.safety.min_gap_oncoming_m for r in runs if math.isfinite(r.safety.min_gap_oncoming_m)]
    plan_ms = [m for r in runs for m in r.plan_ms]
    opportunities: dict[str, Counter[str]] = {}
    for r in runs:
        for refusal, counts in r.opportunities.counts.items():
            opportunities.setdefault(refusal, Counter()).update(counts)
    missed = [o.to_json() for r in runs for o in r.opportunities.missed][:MISSED_EXAMPLES]
    return Row(key[0], key[1], key[2], len(runs), sum(r.km for r in runs),
               sum(len(r.collisions) for r in runs), sum(r.safety.near_misses for r in runs),
               sum(r.traffic_collisions for r in runs), dict(causes.most_common()), [e.to_json() for e in worst],
               _num(min(gaps_left)) if gaps_left else None, _num(min(gaps_oncoming)) if gaps_oncoming else None,
               deviation, sum(r.tolerance.violation_count for r in runs),
               _num(float(np.median(plan_ms))) if plan_ms else None,
               {k: dict(v) for k, v in sorted(opportunities.items())}, missed, key[3], key[4],
               sum(r.overtakes for r in runs), sum(r.decisions for r in runs),
               dict(sum((Counter(r.safety.attributed) for r in runs), Counter())),
               dict(sum((Counter(r.containment.by_kind) for r in runs), Counter())),
               _num(sum(r.containment.breached_s for r in runs) / checked) if (checked := sum(
                   r.containment.checked_s for r in runs)) else None,
               sum(r.breach_replans for r in runs), sum(r.keep_lane_steps for r in runs),
               sum(r.minimal_risk_steps for r in runs), sum(len(r.takeovers) for r in runs),
               sum(t.after_breach for r in runs for t in r.takeovers), sum(len(r.planner_failures) for r in runs),
               sum(len(r.of_kind(FailureKind.LOSS_OF_CONTROL)) for r in runs),
               sum(len(r.of_kind(FailureKind.SENSING)) for r in runs), _fault_counts(runs),
               late_plans=sum(m > 1000 * LOOP.plan_budget_s for m in plan_ms),
               blocked=sum(len(r.of_kind(FailureKind.BLOCKED)) for r in runs), semantics=key[5],
               unsafe_starts=sum(r.unsafe_starts for r in runs), reversed_moves=sum(r.reversed_moves for r in runs),
               moves_finished=sum(r.moves_finished for r in runs), moves_undone=sum(r.moves_undone for r in runs),
               moves_unproved=sum(r.moves_unproved for r in runs))


def moves(r: Row) -> str:
    """The sideways moves a breach ended: finished and undone by a proved decision, sent back by the fallback's rule."""
    return f"{r.moves_finished}, {r.moves_undone}, {r.reversed_moves}"


def _at_most(edge: float | None, largest: float) -> float | None:
    """A quantile's bound from the histogram: the upper edge of its bin, or the largest value seen when that is
    smaller (a quantile never exceeds the maximum; an overflow bin's edge is infinite)."""
    return None if edge is None else min(edge, largest)


def _fault_counts(runs: list[RunSummary]) -> dict[str, dict[str, int]]:
    """Per fault kind injected: faults started, sweeps they changed, failures (collisions, losses of control)
    attributed to it (``sim.faults.attribute``); failures without a fault under the key "none"."""
    failures = Counter(f.fault for r in runs for f in r.failures if f.kind.ends_run)
    counts = {kind: {"started": sum(r.faults.get(kind, {}).get("started", 0) for r in runs),
                     "sweeps": sum(r.faults.get(kind, {}).get("sweeps", 0) for r in runs),
                     "failures": failures[kind]} for kind in sorted({k for r in runs for k in r.faults})}
    if counts:
        counts["none"] = {"started": 0, "sweeps": 0, "failures": failures[None]}
    return counts


@dataclass(slots=True)
class Cost:
    """One engine's planning cost on the snapshots of one cell size."""

    cell_m: float
    engine: str
    n: int
    median_ms: float | None
    p99_ms: float | None
    median_states: float | None
    incomplete: int
    model: str = "paper"

    def to_json(self) -> dict[str, Any]:
        return {"cell_m": self.cell_m, "model": self.model, "engine": self.engine, "n": self.n,
                "median_ms": self.median_ms, "p99_ms": self.p99_ms, "median_states_explored": self.median_states,
                "incomplete": self.incomplete}


#: The sound model's snapshots whose planning cost is measured, per cell size, at most: the first in run order (each
#: engine plans each one; Z3 may take its whole time-out on one).
MAX_SOUND_SNAPSHOTS = 40


def _shape(scenario: Scenario) -> tuple[object, ...]:
    """What a verifier is compiled for, at most: the lanes' vehicle counts, the AV's lane, the model and its
    assumptions but the AV's measured speed, which a served verifier reads as data (``promela.sound``)."""
    sound = None if scenario.sound is None else replace(scenario.sound, start_mps=None)
    return (scenario.lane, scenario.model, sound, len(scenario.left_lane), len(scenario.right_lane),
            scenario.left_mps is not None, scenario.right_mps is not None)


def planning_cost(results: Iterable[Done], engines: Iterable[str], timeout_s: float = 10.0) -> list[Cost]:
    """Every engine's shortest plan for the scenarios the planner saw, per cell size and model (an untimed run first
    for each shape of problem: a verifier compiles once per shape); an engine is timed on the scenarios it answers
    only (``spec.engines.answers``: one that moves every vehicle at its lane's speeds, on those without measured
    speeds; its count says how many)."""
    by_cell: dict[tuple[float, str], list[dict[str, Any]]] = {}
    for done in results:
        by_cell.setdefault((done.config.cell_m, decider(done.config.model, done.config.decides.value)),
                           []).extend(done.summary.snapshots)
    costs = []
    for (cell_m, model), snapshots in by_cell.items():
        scenarios = [scenario_from_dict(s) for s in snapshots]
        if model != "paper":
            scenarios = scenarios[:MAX_SOUND_SNAPSHOTS]
        seen = scenarios
        for engine in engines:
            scenarios = [s for s in seen if answers(get_engine(engine), s)]
            if not scenarios:
                costs.append(Cost(cell_m, engine, 0, None, None, None, 0, model))
                continue
            limits = Limits(timeout_s=timeout_s)
            kinds = {_shape(s): s for s in scenarios}  # one untimed run per shape (Spin compiles it)
            for scenario in kinds.values():
                plan(scenario, Strategy.SHORTEST, engine=engine, limits=limits)
            ms, states, incomplete = [], [], 0
            for scenario in scenarios:
                started = time.perf_counter()
                answer = plan(scenario, Strategy.SHORTEST, engine=engine, limits=limits)
                ms.append((time.perf_counter() - started) * 1000)
                states.append(answer.states_explored)
                incomplete += answer.status is Status.INCOMPLETE
            costs.append(Cost(cell_m, engine, len(ms), _num(float(np.median(ms))), _num(float(np.percentile(ms, 99))),
                              float(np.median(states)), incomplete, model))
    return costs


def write_reports(audit_rows: list[Row], costs: list[Cost], audit: AuditPlan, out_dir: str) -> list[Path]:
    """``audit.json``, ``audit.md`` and the plots (the headline's, ``audit-tradeoff.png``, first in ``audit.md``) in
    ``out_dir``; the files written."""
    out = Path(out_dir)
    settings = {k: v for k, v in audit.base.all_json().items() if k not in PER_COMBINATION}
    settings |= {"cells_m": list(audit.cells_m), "traffic": list(audit.traffic), "sensing": list(audit.sensing),
                 "models": list(audit.models), "bounds_scales": list(audit.bounds_scales), "seeds": list(audit.seeds)}
    records = [r.to_json() for r in audit_rows]
    data = {"settings": settings, "combinations": records, "planning_cost": [c.to_json() for c in costs]}
    paths = [out / "audit.json", out / "audit.md", out / "audit-safety.png", out / "audit-latency.png",
             out / "audit-models.png", out / "audit-tradeoff.png"]
    paths[0].write_text(json.dumps(data, indent=1))
    paths[1].write_text(markdown(audit_rows, costs, settings))
    _plot_safety(audit_rows, paths[2])
    _plot_latency(costs, paths[3])
    _plot_models(audit_rows, paths[4])
    fig = plot_tradeoffs(tradeoffs(records))
    fig.savefig(paths[5], dpi=100)
    pyplot().close(fig)
    return paths


def decider(model: str, semantics: str) -> str:
    """A model as tables name it: the sound model with how it decided (``sound (commit)``, ``sound (whole)``)."""
    return model + (f" ({semantics})" if model == "sound" else "")


def model_label(model: str, semantics: str, bounds_scale: float) -> str:
    """A combination's model, semantics and bounds as tables name them."""
    return decider(model, semantics) + ("" if bounds_scale == 1 else f" (bounds x{bounds_scale:g})")


def label(r: Row) -> str:
    return model_label(r.model, r.semantics, r.bounds_scale)


def record_label(record: dict[str, Any]) -> str:
    """``model_label`` from a combination's ``audit.json`` record (one written before the semantics were recorded
    decided by whole plans)."""
    return model_label(str(record.get("model", "paper")), str(record.get("semantics", Semantics.WHOLE.value)),
                       record.get("bounds_scale", 1.0))


@dataclass(frozen=True, slots=True)
class Tradeoff:
    """One model in one world (traffic and sensing), over every cell size and seed the audit drove it: what its
    safety cost in progress, a point of the audit's headline figure."""

    model: str  # as tables name it (``record_label``)
    traffic: str
    sensing: str
    km: float
    overtakes: int
    collisions: int
    inside: int  # of them, inside the model's assumptions (a soundness failure)

    @property
    def overtakes_per_km(self) -> float:
        return self.overtakes / self.km if self.km else math.nan

    @property
    def collisions_per_1000_km(self) -> float:
        return 1000 * self.collisions / self.km if self.km else math.nan


def tradeoffs(records: Iterable[dict[str, Any]]) -> list[Tradeoff]:
    """The headline's points from the combinations' ``audit.json`` records: one per model and world, in the order
    the audit drove them."""
    points: dict[tuple[str, str, str], list[dict[str, Any]]] = {}
    for r in records:
        points.setdefault((record_label(r), str(r["traffic"]), str(r["sensing"])), []).append(r)
    return [Tradeoff(model, traffic, sensing, sum(float(r["km"]) for r in mine),
                     sum(int(r.get("overtakes", 0)) for r in mine), sum(int(r["collisions"]) for r in mine),
                     sum(int(r.get("attributed", {}).get(attribution_key("contact", True), 0)) for r in mine))
            for (model, traffic, sensing), mine in points.items()]


def plot_tradeoffs(points: list[Tradeoff]) -> Any:
    """The headline figure: overtakes per km against collisions per 1,000 km, a point per model and world (a colour
    per world, a marker per model; a point with collisions inside its assumptions ringed red and labelled). The
    collision axis is linear up to 1 per 1,000 km and logarithmic beyond, so that none and hundreds both show."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    worlds = list(dict.fromkeys((p.traffic, p.sensing) for p in points))
    models = list(dict.fromkeys(p.model for p in points))
    for p in points:
        colour = f"C{worlds.index((p.traffic, p.sensing)) % 10}"
        ax.scatter([p.collisions_per_1000_km], [p.overtakes_per_km], s=70, color=colour,
                   marker="osD^v<>P"[models.index(p.model) % 8], edgecolors="red" if p.inside else colour,
                   linewidths=2.5 if p.inside else 1.0, zorder=3)
        if p.inside:
            ax.annotate(f"{p.inside} inside", (p.collisions_per_1000_km, p.overtakes_per_km), fontsize=7,
                        color="red", xytext=(5, 5), textcoords="offset points")
    for i, (traffic, sensing) in enumerate(worlds):
        ax.plot([], [], color=f"C{i % 10}", linewidth=6, label=f"{traffic}, {sensing}")
    for i, model in enumerate(models):
        ax.scatter([], [], color="grey", marker="osD^v<>P"[i % 8], label=model)
    ax.set_xscale("symlog", linthresh=1.0)
    ax.set_xlim(left=-0.2)
    ax.set_ylim(bottom=0)
    ax.set_xlabel("collisions per 1,000 km (all; ringed red: some inside the assumptions)")
    ax.set_ylabel("overtakes per km")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    ax.set_title("what each model's safety costs in progress: a point per model and world")
    fig.tight_layout()
    return fig


def tradeoff_markdown(points: list[Tradeoff]) -> list[str]:
    """The headline: each model's overtakes per km beside its collisions per 1,000 km, per world, and the figure."""
    lines = ["## What each model's safety costs in progress (every cell size)", "",
             "| traffic | sensing | model | km | overtakes /km | collisions /1,000 km | "
             "of them inside the assumptions |",
             "|---|---|---|---|---|---|---|"]
    lines += [f"| {p.traffic} | {p.sensing} | {p.model} | {p.km:.1f} | {figure(p.overtakes_per_km, 2)} | "
              f"{figure(p.collisions_per_1000_km)} | {p.inside} |" for p in points]
    return [*lines, "", "![overtakes per km against collisions per 1,000 km](audit-tradeoff.png)"]


def models_markdown(audit_rows: list[Row]) -> list[str]:
    """The models side by side: safety split inside / after the assumptions, containment, the price in overtakes."""
    lines = ["", "## The models side by side: safety inside and outside the assumptions, and its price", "",
             "Collisions and near misses are split by attribution (sim.containment): inside the assumptions (no "
             "breach by the vehicle involved under the decision under way: a soundness failure, each one a bug) or "
             "after an assumption broke. Containment is measured under both models against the world's bounds "
             "(spec.assumptions.world_bounds), from the truth, to attribute; only the sound model acts, on the "
             "breaches its own monitor finds in the sweeps' readings (re-plan; the fallback when no plan and no safe "
             "step is left).", "",
             "| cell m | traffic | sensing | model | km | overtakes /km | collisions inside / after per 1,000 km | "
             "near misses inside / after per 1,000 km | breaches /1,000 km (by kind) | time after a breach | "
             "decisions | re-plans on a breach | moves a breach ended: finished, undone (proved), sent back (the "
             "fallback's rule) | keep-lane steps | minimal-risk | take-overs (after a breach) | "
             "waits without a plan | starts breaking the specification | delayed /1,000 km (est.) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in audit_rows:
        kinds = ", ".join(f"{k} {figure(r.per_1000_km(v))}" for k, v in sorted(r.breaches.items())) or "-"
        share = "-" if r.breached_share is None else f"{100 * r.breached_share:.1f}%"
        lines.append(
            f"| {r.cell_m:g} | {r.traffic} | {r.sensing} | {label(r)} | {r.km:.1f} | "
            f"{figure(r.per_1000_km(r.overtakes) / 1000, 2)} | "
            f"{r.inside_after('contact')} | {r.inside_after('near_miss')} | "
            f"{figure(r.per_1000_km(sum(r.breaches.values())))} ({kinds}) | {share} | {r.decisions} | "
            f"{r.breach_replans} | {moves(r)} | {r.keep_lane_steps} | {r.minimal_risk_steps} | "
            f"{r.takeovers} ({r.takeovers_after_breach}) | {r.waits_without_plan} | {r.unsafe_starts} | "
            f"{figure(r.delayed_per_1000_km)} |")
    return lines


def markdown(audit_rows: list[Row], costs: list[Cost], settings: dict[str, Any]) -> str:
    """The audit's tables as Markdown."""
    lines = ["# Audit of the grid abstraction", "",
             "Settings: " + ", ".join(f"{k} {v}" for k, v in settings.items()), ""]
    lines += tradeoff_markdown(tradeoffs(r.to_json() for r in audit_rows))
    lines += ["", "## Every combination", "",
             "| cell m | traffic | sensing | model | runs | km | collisions | per 1,000 km | near misses | "
             "per 1,000 km | overtakes not started, replays that succeeded (checked) | missed per 1,000 km (est.) | "
             "delayed per 1,000 km (est.) | "
             "traffic collisions | min gap ahead m | min gap oncoming m | violations | plan ms median | "
             f"plans over the {1000 * LOOP.plan_budget_s:.0f} ms budget |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in audit_rows:
        lines.append(f"| {r.cell_m:g} | {r.traffic} | {r.sensing} | {label(r)} | {r.runs} | {r.km:.1f} | "
                     f"{r.collisions} | "
                     f"{figure(r.collisions_per_1000_km)} | {r.near_misses} | {figure(r.near_misses_per_1000_km)} | "
                     f"{r.opportunity_total('missed')} ({r.opportunity_total('checked')}) | "
                     f"{figure(r.missed_per_1000_km)} | {figure(r.delayed_per_1000_km)} | "
                     f"{r.traffic_collisions} | {figure(r.min_gap_left_m, 2)} | {figure(r.min_gap_oncoming_m, 2)} | "
                     f"{r.violations} | {figure(r.plan_ms_median, 2)} | {r.late_plans} |")
    lines += models_markdown(audit_rows)
    if any(r.faults for r in audit_rows):
        lines += ["", "## Faults injected (docs/faults.md) and the failures attributed to them", "",
                  "Per fault kind: faults started / sweeps they changed / failures (collisions, losses of control) "
                  "attributed to it; then failures without a fault, losses of control, and snapshots that could not "
                  "be read (stops, not failures).", "",
                  "| cell m | traffic | sensing | model | km | " + " | ".join(_fault_kinds(audit_rows)) +
                  " | no fault | losses of control | unreadable snapshots |",
                  "|---|---|---|---|---|" + "---|" * (len(_fault_kinds(audit_rows)) + 3)]
        for r in audit_rows:
            cells = [r.fault_cell(k) for k in _fault_kinds(audit_rows)]
            lines.append(f"| {r.cell_m:g} | {r.traffic} | {r.sensing} | {label(r)} | {r.km:.1f} | " + " | ".join(cells)
                         + f" | {r.faults.get('none', {}).get('failures', 0)} | {r.losses_of_control} | "
                         f"{r.unreadable} |")
    lines += ["", "## Causes (contacts and near misses)", ""]
    for r in audit_rows:
        if r.causes:
            lines.append(f"- {r.cell_m:g} m, {r.traffic}, {r.sensing}, {label(r)}: "
                         + "; ".join(f"{cause} x{n}" for cause, n in r.causes.items()))
            for e in r.worst[:3]:
                lines.append(f"  - {e['kind']} at {e['km']} km during {e['doing']}: true gap {e['gap_m']} m, "
                             f"the plan's cells implied {e['implied_gap_m']} m"
                             + (f"; {e['assumptions']}" if e.get("assumptions") else ""))
    lines += ["", "## Missed opportunities (decisions without an overtake start, by reason; how the replays ended)", "",
              "Qualifying: in the AV's own lane, a vehicle ahead within 100 m, and no overtake started "
              "(refused: the final model found no plan; outside_window: nothing to overtake in the model's window; "
              "these two are missed opportunities when a replay succeeds; delayed: the final model's plan starts "
              "its overtake later). A sample is replayed in physics: change lanes, accelerate 1..6 times, change "
              "back, keep the lane 3 s, with no contact and no near miss (sim.opportunity).", ""]
    for r in audit_rows:
        if r.opportunities:
            lines.append(f"- {r.cell_m:g} m, {r.traffic}, {r.sensing}: " + "; ".join(
                f"{refusal}: " + ", ".join(f"{k} {v}" for k, v in counts.items())
                for refusal, counts in r.opportunities.items()))
            for o in r.missed_examples[:1]:
                lines.append(f"  - at {o['km']} km ({o['refusal']}: {o['answer']}), target {o['target_gap_m']} m "
                             f"ahead: change, accelerate x{o['accelerates']}, change back succeeded; "
                             f"the planner's scenario is in audit.json")
    lines += ["", f"## Deviation each action added (cells of {LOOP.tolerance_unit_m:g} m: p50 / p95 / max)", "",
              f"p50 and p95 are bounds, \"≤\": the upper edge of their {HISTOGRAM_BIN:g}-cell histogram bin, or the "
              "largest deviation seen when that is smaller. -: the action never ran.", "",
              "| cell m | traffic | sensing | " + " | ".join(ACTIONS) + " |", "|---|---|---|" + "---|" * len(ACTIONS)]
    for r in audit_rows:
        cells = [" / ".join(_edge(r.deviation[a][k], k != "max") for k in ("p50", "p95", "max"))
                 if a in r.deviation else "-" for a in ACTIONS]
        lines.append(f"| {r.cell_m:g} | {r.traffic} | {r.sensing} | " + " | ".join(cells) + " |")
    lines += ["", "## Planning cost on the scenarios the planner saw (shortest, whole pipeline)", "",
              f"Under the sound model, the first {MAX_SOUND_SNAPSHOTS} snapshots per cell size. Each engine plans "
              "one scenario of each shape untimed first (Spin compiles its verifier then; a served verifier reads "
              "the AV's measured speed as data): compilation is not in the figures.", "",
              "| cell m | model | engine | n | median ms | p99 ms | median states explored | incomplete |",
              "|---|---|---|---|---|---|---|---|"]
    lines += [f"| {c.cell_m:g} | {c.model} | {c.engine} | {c.n} | {figure(c.median_ms, 2)} | {figure(c.p99_ms, 2)} | "
              f"{figure(c.median_states, 0)} | {c.incomplete} |" for c in costs]
    if any(c.n == 0 for c in costs):
        lines += ["", "\"-\": no snapshot was kept for that row (`--snapshots 0`, or no decision at that cell size)."]
    return "\n".join(lines) + "\n"


def _fault_kinds(audit_rows: list[Row]) -> list[str]:
    return sorted({k for r in audit_rows for k in r.faults if k != "none"})


def _edge(value: float | None, bound: bool) -> str:
    """A deviation as the report prints it: a quantile's bound with "≤" (``_at_most``), the maximum as it is."""
    if value is None:
        return "-"
    return f"≤ {value:g}" if bound else f"{value:g}"


def _plot_safety(audit_rows: list[Row], png: Path) -> None:
    _plot_by_cell(audit_rows, png, (("collisions per 1000 km", lambda r: r.collisions_per_1000_km),
                                    ("near misses per 1000 km", lambda r: r.near_misses_per_1000_km)),
                  "the grid abstraction against traffic and sensing that do not keep to it")


def _plot_models(audit_rows: list[Row], png: Path) -> None:
    """Collisions per 1,000 km and overtakes per km against cell size: one line per model and traffic (sensing and
    bound scales as separate lines where the audit has several)."""
    _plot_by_cell(audit_rows, png, (("collisions per 1,000 km", lambda r: r.collisions_per_1000_km),
                                    ("overtakes per km", lambda r: r.per_1000_km(r.overtakes) / 1000)),
                  "the paper model (solid) and the sound model (dashed)")


def _plot_by_cell(audit_rows: list[Row], png: Path, panels: tuple[tuple[str, Callable[[Row], float]], ...],
                  title: str) -> None:
    """One panel per figure against cell size, one line per traffic, sensing, model and bound scale."""
    plt = pyplot()
    fig, axes = plt.subplots(1, len(panels), figsize=(11, 4))
    lines = dict.fromkeys((r.traffic, r.sensing, decider(r.model, r.semantics), r.bounds_scale) for r in audit_rows)
    worlds = list(dict.fromkeys((traffic, sensing) for traffic, sensing, _, _ in lines))  # a colour each
    scales = list(dict.fromkeys(scale for _, _, _, scale in lines))  # a marker each
    styles = {"paper": "-", "sound": "--"}  # any other: the sound model's commitments
    for ax, (what, value) in zip(axes, panels):
        for traffic, sensing, model, scale in lines:
            mine = sorted((r.cell_m, value(r)) for r in audit_rows
                          if (r.traffic, r.sensing, decider(r.model, r.semantics), r.bounds_scale)
                          == (traffic, sensing, model, scale))
            name = f"{traffic}, {sensing}, {model}{'' if scale == 1 else f' x{scale:g}'}"
            ax.plot(*zip(*mine), styles.get(model, ":"), marker="osD^v<>"[scales.index(scale) % 7],
                    color=f"C{worlds.index((traffic, sensing)) % 10}", label=name)
        ax.set_xlabel("cell length (m)")
        ax.set_ylabel(what)
        ax.invert_xaxis()
    axes[0].legend(fontsize=7)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(png, dpi=100)
    plt.close(fig)


def _plot_latency(costs: list[Cost], png: Path) -> None:
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 4))
    for engine, model in dict.fromkeys((c.engine, c.model) for c in costs):
        mine = sorted((c.cell_m, c.median_ms) for c in costs
                      if (c.engine, c.model) == (engine, model) and c.median_ms is not None)
        if mine:
            ax.plot(*zip(*mine), "-" if model == "paper" else "--", marker="o", label=f"{engine}, {model}")
    ax.set_xlabel("cell length (m)")
    ax.set_ylabel("median planning latency (ms), shortest")
    ax.set_yscale("log")
    ax.invert_xaxis()
    if ax.get_lines():
        ax.legend()
    else:
        ax.text(0.5, 0.5, "no planning cost measured (--snapshots 0)", transform=ax.transAxes, ha="center")
    fig.tight_layout()
    fig.savefig(png, dpi=100)
    plt.close(fig)
