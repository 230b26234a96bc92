"""Conformance throughput: scenarios per second per engine run, Spin before and after serving, the sweep's scaling.

Usage: python -m ci.bench.crossval [--count 200] [--seed 2026] [--workers 1,2] [--sweep-count 400]

Part 1 times each engine run the properties read (the whole pipeline, ``oracle.planner.solve``)
and the two independent searches the checks make, serially, on the same ``--count`` scenarios
drawn (seeded) from the example space of issue 12; Spin runs twice in the same run, a pan
process per search (before) and its verifier's server (after), and so does Z3, a solver made
for each problem (before) and a solver kept per problem shape (after; not warmed up: the
shapes are built within the timed runs, as a campaign builds them). Part 2 runs the conformance
campaign itself (every property, three engines, a fresh ``--out``) on the first
``--sweep-count`` scenarios of that space with each ``--workers`` count, and extrapolates the
whole space's wall time from the rate.
"""

from __future__ import annotations

import argparse
import os
import random
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import replace

import numpy as np
from rich.console import Console
from rich.table import Table

from ci.bench.latency import timed
from ci.conformance.crossval import Space, check_scenario, parse_space
from ci.conformance.properties import PROPERTIES
from ci.shared.machine import machine
from oracle import bmc
from oracle.optimum import lexicographic_optimum
from oracle.planner import solve
from promela import runner
from spec.answers import Limits, Strategy
from spec.engines import Engine, get_engine, register
from spec.grid import PAPER_GRID
from spec.models import ModelKind
from spec.scenario import Scenario, problem_for

EXAMPLE_SPACE = "left=2@8..20,right=1@12..30,lanes=both"  # issue 12's example sweep
PER_PROCESS = Engine("spin-per-process", (Strategy.SENSIBLE, Strategy.SHORTEST),
                     lambda p, s, limits: runner.search(p, s, limits.timeout_s, serve=False),
                     "Spin compiled once, a pan process per search (benchmark only)")


def per_second(scenarios: list[Scenario], run: Callable[[Scenario], object]) -> tuple[float, float]:
    """(scenarios per second, median ms) over ``scenarios``, after one warm-up call."""
    ms = timed(scenarios, run)
    return 1000 * len(ms) / float(ms.sum()), float(np.median(ms))


def sub_space(example: Space, count: int) -> Space:
    """``example`` with its left-lane cells cut (from the top) to the fewest that hold ``count`` scenarios."""
    low, high = example.left_cells
    while high > low and _size(replace(example, left_cells=(low, high - 1))) >= count:
        high -= 1
    return replace(example, left_cells=(low, high))


def _size(space: Space) -> int:
    return sum(1 for _ in space.scenarios(PAPER_GRID, None))


def sweep_rate(space: Space, size: int, workers: int) -> float:
    """Scenarios per wall second of ``overtake crossval`` (every property, three engines) over ``space`` (``size``
    scenarios)."""
    with tempfile.TemporaryDirectory(prefix="bench-crossval-") as out:
        started = time.perf_counter()
        done = subprocess.run([sys.executable, "-m", "ci.cli.main", "crossval", "--source", "exhaustive",
                               "--space", space.describe(), "--workers", str(workers), "--out", out,
                               "--max-reproducers", "0"],
                              capture_output=True, text=True, env={**os.environ, "COLUMNS": "120"})
        wall_s = time.perf_counter() - started
    if done.returncode not in (0, 6):
        raise SystemExit(f"bench_crossval: crossval exited {done.returncode}: {done.stderr.strip()[-300:]}")
    return size / wall_s


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=200, help="scenarios timed per engine run (part 1)")
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--workers", default="1,2", help="worker counts for the campaign (part 2); '' skips it")
    parser.add_argument("--sweep-count", type=int, default=400, help="scenarios per campaign (part 2)")
    args = parser.parse_args()
    console = Console(width=120)
    example = parse_space(EXAMPLE_SPACE, PAPER_GRID)
    space = list(example.scenarios(PAPER_GRID, None))
    scenarios = random.Random(args.seed).sample(space, min(args.count, len(space)))
    console.print(f"seed {args.seed}; {len(scenarios)} scenarios drawn from {EXAMPLE_SPACE} ({len(space)} "
                  f"scenarios); {runner.tool_versions()}; {machine()}")
    register(PER_PROCESS)
    limits = Limits(timeout_s=10.0)
    spin = get_engine("spin")

    def run_of(engine: Engine | str, strategy: Strategy) -> Callable[[Scenario], object]:
        return lambda s: solve(s, strategy, engine=engine, limits=limits)

    rows: dict[str, tuple[float, float]] = {}
    for strategy in (Strategy.SENSIBLE, Strategy.SHORTEST):
        for s in scenarios:  # build every verifier shape before timing
            solve(s, strategy, engine=spin)
        rows[f"interpreter {strategy.value}"] = per_second(scenarios, run_of("interpreter", strategy))
        rows[f"spin {strategy.value}, pan process per search (before)"] = per_second(
            scenarios, run_of(PER_PROCESS, strategy))
        rows[f"spin {strategy.value}, verifier server (after)"] = per_second(scenarios, run_of(spin, strategy))
    for strategy in (Strategy.SHORTEST, Strategy.OPTIMAL):
        with bmc.isolated():
            rows[f"z3 {strategy.value}, a solver per problem (before)"] = per_second(scenarios, run_of("z3", strategy))
        rows[f"z3 {strategy.value}, a solver kept per shape (after)"] = per_second(scenarios, run_of("z3", strategy))
    rows["independent optimum (offset form, both models)"] = per_second(
        scenarios, lambda s: [lexicographic_optimum(problem_for(s, kind)) for kind in ModelKind])
    every = list(PROPERTIES)
    rows["every property, three engines (one scenario's whole check)"] = per_second(
        scenarios, lambda s: check_scenario(s, every, ["interpreter", "spin", "z3"], limits.timeout_s))
    table = Table(title="engine runs, serial, same scenarios")
    for col in ("run (whole pipeline)", "scenarios/s", "median ms"):
        table.add_column(col, justify="left" if col.startswith("run") else "right")
    for name, (rate, median) in rows.items():
        table.add_row(name, f"{rate:.1f}", f"{median:.2f}")
    console.print(table)
    for strategy in (Strategy.SENSIBLE, Strategy.SHORTEST):
        before = rows[f"spin {strategy.value}, pan process per search (before)"]
        after = rows[f"spin {strategy.value}, verifier server (after)"]
        console.print(f"spin {strategy.value}: served / per process = {after[0] / before[0]:.2f}x scenarios per "
                      f"second (median {before[1]:.2f} -> {after[1]:.2f} ms)")
    for strategy in (Strategy.SHORTEST, Strategy.OPTIMAL):
        before = rows[f"z3 {strategy.value}, a solver per problem (before)"]
        after = rows[f"z3 {strategy.value}, a solver kept per shape (after)"]
        console.print(f"z3 {strategy.value}: kept / per problem = {after[0] / before[0]:.2f}x scenarios per "
                      f"second (median {before[1]:.2f} -> {after[1]:.2f} ms)")

    counts = [int(w) for w in args.workers.split(",") if w.strip()]
    if not counts:
        return
    cut = sub_space(example, args.sweep_count)
    cut_size = _size(cut)
    sweep = Table(title=f"overtake crossval --source exhaustive --space {cut.describe()} (every property, three "
                        f"engines)")
    for col in ("workers", "scenarios", "scenarios/s", "speed-up", "example space at this rate"):
        sweep.add_column(col, justify="right")
    base, serial_ms, speed_up = 0.0, 1000 / rows["every property, three engines (one scenario's whole check)"][0], 1.0
    for workers in counts:
        rate = sweep_rate(cut, cut_size, workers)
        base, speed_up = base or rate, rate / (base or rate)
        sweep.add_row(str(workers), str(cut_size), f"{rate:.1f}", f"{speed_up:.2f}x",
                      f"{len(space) / rate / 60:.1f} min")
    console.print(sweep)
    console.print(f"example space from the random sample: {len(space)} scenarios x {serial_ms:.0f} ms (mean whole "
                  f"check, serial) / {speed_up:.2f} (the last speed-up) = "
                  f"{len(space) * serial_ms / 1000 / speed_up / 60:.1f} min, an estimate (in random order a kept "
                  f"solver's warm start rarely guesses right; a sweep walks cells in order): time the sweep itself "
                  f"against the target, 5 min on 2 workers")


if __name__ == "__main__":
    main()

