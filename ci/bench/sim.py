"""Simulated kilometres per wall-clock minute on one core, closed loop, for each planner engine in one run.

Usage: python -m ci.bench.sim [--km 10] [--seeds 1,2,3] [--engines interpreter,spin]

Every engine drives the same seeds; since the engines return the same sensible plans, their
drives must be identical (distance, plans, overtakes), which the table checks too.
"""

from __future__ import annotations

import argparse

import numpy as np
from rich.console import Console
from rich.table import Table

from ci.shared.machine import machine
from sim.parts import DriveConfig
from sim.simulator import run_drive
from sim.summary import RunSummary
from spec.physical import LOOP


def drive(seed: int, km: float, engine: str) -> RunSummary:
    return run_drive(seed, DriveConfig(km, engine=engine))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--km", type=float, default=10.0)
    parser.add_argument("--seeds", default="1,2,3")
    parser.add_argument("--engines", default="interpreter,spin")
    args = parser.parse_args()
    seeds = [int(s) for s in args.seeds.split(",")]
    engines = [e.strip() for e in args.engines.split(",")]
    console = Console(width=140)
    console.print(f"seeds {args.seeds}; {args.km} km each; engines {args.engines} (sensible); physics dt "
                  f"{LOOP.physics_dt_s:.4f} s, control every {LOOP.control_every_steps} steps; one process; "
                  f"{machine()}")
    table = Table(title="closed-loop simulation speed")
    for col in ("engine", "seed", "km", "sim time (min)", "wall (s)", "km per wall minute", "x real time", "plans",
                "plan ms (median)", "failure"):
        table.add_column(col, justify="right")
    runs: dict[str, list[RunSummary]] = {}
    for engine in engines:
        runs[engine] = [drive(seed, args.km, engine) for seed in seeds]
        for r in runs[engine]:
            table.add_row(engine, str(r.seed), f"{r.km:.2f}", f"{r.sim_time_s / 60:.1f}", f"{r.wall_s:.1f}",
                          f"{rate(r):.1f}", f"{r.sim_time_s / r.wall_s:.0f}x", str(r.plans),
                          f"{np.median(r.plan_ms):.2f}", r.failure.cause if r.failure else "-")
    console.print(table)
    reference = engines[0]
    summary = Table(title=f"per engine (medians over seeds; ratios against {reference})")
    for col in ("engine", "km per wall minute", "plan ms (median)", "wall vs " + reference, "same drives"):
        summary.add_column(col, justify="right")
    for engine, results in runs.items():
        same = all(drives_match(a, b) for a, b in zip(runs[reference], results))
        wall = np.median([r.wall_s for r in results]) / np.median([r.wall_s for r in runs[reference]])
        summary.add_row(engine, f"{np.median([rate(r) for r in results]):.1f}",
                        f"{np.median([m for r in results for m in r.plan_ms]):.2f}", f"{wall:.2f}x",
                        "yes" if same else "NO")
    console.print(summary)
    slowest = min(np.median([rate(r) for r in results]) for results in runs.values())
    console.print(f"target: >= 30 km per wall minute on one core: {'met' if slowest >= 30 else 'NOT met'} "
                  f"(slowest engine's median {slowest:.1f})")


def rate(r: RunSummary) -> float:
    return r.km / (r.wall_s / 60)


def drives_match(a: RunSummary, b: RunSummary) -> bool:
    """The same drive: distance, time, plans, overtakes and failures, whoever planned it."""
    key = lambda r: (r.km, r.sim_time_s, r.plans, r.replans, r.overtakes, r.failures)  # noqa: E731
    return key(a) == key(b)


if __name__ == "__main__":
    main()
