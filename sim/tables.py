"""A campaign's results as tables: per run, in total, deviation per action type, and beside the paper's Table 1."""

from __future__ import annotations

from collections import Counter

import numpy as np
from rich.table import Table

from sim.paper import MEDIAN_KM, MEDIAN_OVERTAKEN, TABLE_1
from sim.summary import RunSummary
from spec.kinds import FailureKind


def hours_minutes(seconds: float) -> str:
    minutes = round(seconds / 60)
    return f"{minutes // 60}h {minutes % 60:02d}m"


def runs_table(results: list[RunSummary]) -> Table:
    table = Table(title="simulated drives")
    for col in ("seed", "sim time", "km", "overtakes", "plans", "replans", "plan ms median / p99", "violations",
                "failure"):
        table.add_column(col, overflow="fold")
    for r in results:
        latency = r.latency_ms()
        failure = f"{r.failure.cause} at {r.failure.km:.2f} km" if r.failure else "-"
        table.add_row(str(r.seed), hours_minutes(r.sim_time_s), f"{r.km:.2f}", str(r.overtakes), str(r.plans),
                      str(r.replans), f"{latency['median']:.2f} / {latency['p99']:.2f}",
                      str(r.tolerance.violation_count), failure)
    return table


def totals_table(results: list[RunSummary]) -> Table:
    """The whole campaign in one column: distance, time, overtakes, plans, latency, failures by cause."""
    ms = np.array([m for r in results for m in r.plan_ms]) if any(r.plan_ms for r in results) else np.zeros(1)
    causes = Counter(f"{f.kind.value}: {f.cause}" for r in results for f in r.failures)
    kept = Counter(f"  kept after {f.kind.value}: {f.cause}" for r in results for f in r.kept_plans)
    table = Table(title="campaign totals", show_header=False)
    rows = [("runs", str(len(results))), ("km", f"{sum(r.km for r in results):.1f}"),
            ("simulated time", hours_minutes(sum(r.sim_time_s for r in results))),
            ("overtakes", str(sum(r.overtakes for r in results))), ("plans", str(sum(r.plans for r in results))),
            ("re-plans", str(sum(r.replans for r in results))),
            ("re-plans without a plan (the plan under way was kept)", str(sum(len(r.kept_plans) for r in results))),
            *sorted((cause, str(n)) for cause, n in kept.items()),
            ("plans in the common-speed frame (none consistent with its own)",
             str(sum(r.frame_fallbacks for r in results))),
            ("planning ms: median / p99 / max", f"{np.median(ms):.2f} / {np.percentile(ms, 99):.2f} / {ms.max():.2f}"),
            ("containment breaches (the world's bounds)", str(sum(r.containment.count for r in results))),
            *sorted((f"  {kind}", str(n)) for kind, n in sum((Counter(r.containment.by_kind) for r in results),
                                                            Counter()).items()),
            ("sound model: decisions ended by a breach", str(sum(r.breach_replans for r in results))),
            ("sound model: sideways moves a breach ended: finished, undone (proved), sent back (the fallback's rule)",
             f"{sum(r.moves_finished for r in results)}, {sum(r.moves_undone for r in results)}, "
             f"{sum(r.reversed_moves for r in results)}"),
            ("sound model: decisions past a breach never sensed", str(sum(r.unseen_breaches for r in results))),
            ("sound model: decisions with the oncoming lane hidden behind a left-lane vehicle",
             str(sum(r.shadowed for r in results))),
            ("sound model: keep-lane steps / minimal-risk manoeuvres",
             f"{sum(r.keep_lane_steps for r in results)} / {sum(r.minimal_risk_steps for r in results)}"),
            ("sound model: committed parts with an escape / escapes kept (--semantics commit)",
             f"{sum(r.committed_parts for r in results)} / {sum(r.escapes for r in results)}"),
            ("sound model: decisions whose start broke the safety specification",
             str(sum(r.unsafe_starts for r in results))),
            ("sound model: fallback take-overs (after a breach)",
             f"{sum(len(r.takeovers) for r in results)} ({sum(t.after_breach for r in results for t in r.takeovers)})"),
            ("collisions", str(sum(len(r.collisions) for r in results))),
            ("planner failures", str(sum(len(r.planner_failures) for r in results))),
            ("tolerance violations", str(sum(r.tolerance.violation_count for r in results)))]
    rows += [(f"  {cause}", str(n)) for cause, n in sorted(causes.items())]
    for key, value in rows:
        table.add_row(key, value)
    return table


def deviations_table(results: list[RunSummary]) -> Table:
    step = results[0].tolerance.step_tolerance if results else 0.0
    plan = results[0].tolerance.plan_tolerance if results else 0.0
    table = Table(title=f"deviation from the model per action type (cells; tolerance {step} per action, {plan} "
                        f"per plan)")
    for col in ("action", "checks", "largest added by one action", "violations"):
        table.add_column(col)
    for action in sorted({a for r in results for a in r.tolerance.checks}):
        table.add_row(action, str(sum(r.tolerance.checks.get(action, 0) for r in results)),
                      f"{max(r.tolerance.largest.get(action, 0.0) for r in results):.3f}",
                      str(sum(r.tolerance.violations_by_action.get(action, 0) for r in results)))
    return table


def paper_table(results: list[RunSummary], cap_km: float, sensing_only: bool = False) -> Table:
    """Our runs beside the paper's Table 1, row by row, with both medians between failures: distance, overtakes and
    failure first (a narrow terminal keeps those), then the times and our stops. With ``sensing_only`` a run ends at
    its first failure a sensing fault caused; its other failures (after which it started again) are counted."""
    ends = "a sensing-caused failure" if sensing_only else "a failure"
    table = Table(title=f"the paper's experiment: our runs (each to {ends}, cap {cap_km:g} km) beside Table 1")
    for col in ("run", "km", "overtaken", "failure", "paper: km", "overtaken", "failure", "sim time",
                "stops: sensing / no plan", "paper: time"):
        table.add_column(col)
    for i in range(max(len(results), len(TABLE_1))):
        ours = ["", "", "", "", ""]
        if i < len(results):
            r = results[i]
            crash = r.ended(sensing_only)
            others = len([f for f in r.failures if f.kind.ends_run and f is not crash]) if sensing_only else 0
            ours = [f"{r.km:.1f}", str(r.overtakes),
                    ((crash.cause + (f" (fault: {crash.fault})" if crash.fault else " (no fault)")) if crash
                     else "none (censored at the cap)") + (f"; {others} other failure(s), restarted" if others else ""),
                    hours_minutes(r.sim_time_s),
                    f"{len(r.of_kind(FailureKind.SENSING))} / {len(r.of_kind(FailureKind.PLANNER))}"]
        paper = TABLE_1[i] if i < len(TABLE_1) else None
        theirs = [f"{paper.km:.1f}", str(paper.overtaken), paper.failure, paper.runtime] if paper else [""] * 4
        table.add_row(str(i + 1), *ours[:3], *theirs[:3], *ours[3:], theirs[3])
    table.add_row("median", f"{np.median([r.km for r in results]):.1f}",
                  f"{np.median([r.overtakes for r in results]):.1f}", "", f"{MEDIAN_KM}", f"{MEDIAN_OVERTAKEN}", "", "",
                  "", "")
    return table


def faults_table(results: list[RunSummary]) -> Table:
    """Per fault kind: the sweeps that offered it a target, the faults started, the sweeps they changed, and the
    failures (collisions, losses of control) attributed to it (``sim.faults.attribute``); then failures without."""
    table = Table(title="faults injected and the failures attributed to them")
    for col in ("fault", "sweeps offering a target", "started", "sweeps changed", "failures", "per 1000 km",
                "flagged by the tracker"):
        table.add_column(col, justify="right")
    km = sum(r.km for r in results)
    proper = [f for r in results for f in r.failures if f.kind.ends_run]  # every one: a run may restart after one
    crashes = Counter(f.fault for f in proper)
    flagged = Counter(f.fault for f in proper if f.flagged)
    tracked = any(f.flagged is not None for f in proper)
    kinds = sorted({k for r in results for k in r.faults})
    for kind in (*kinds, None):
        stats = [r.faults.get(kind, {}) for r in results] if kind else []
        counts = [str(sum(x.get(key, 0) for x in stats)) if kind else "" for key in ("offered", "started", "sweeps")]
        table.add_row(kind or "(no fault)", *counts, str(crashes[kind]),
                      f"{1000 * crashes[kind] / km:.1f}" if km else "-", str(flagged[kind]) if tracked else "-")
    return table
