"""Planning latency of every engine at each standard cell size, on the same traffic cut finer.

Usage: python -m ci.bench.grid [--count 60] [--seed 2026] [--timeout 10]

The built-in library and generated scenarios on the paper's 21 m grid are refined exactly
onto 10.5, 7 and 5.25 m cells (every vehicle at the same distance, ``ci.shared.gen.refined``), so
each column plans the same situations. Whole pipeline, horizon as in each scenario (30 by
default), one untimed pass first (Spin's verifiers compiled). A plan that hits ``--timeout`` is
counted as incomplete and its time kept (a lower bound), so slow engines show as slow.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from rich.console import Console
from rich.table import Table

from ci.bench.latency import library_and_generated
from ci.shared.machine import machine
from oracle.planner import plan
from spec.answers import Limits, Status, Strategy
from spec.grid import STANDARD_CELLS_M, Grid
from spec.scenario import Scenario, refined

CASES = (("interpreter", Strategy.SENSIBLE), ("interpreter", Strategy.SHORTEST), ("spin", Strategy.SENSIBLE),
         ("spin", Strategy.SHORTEST), ("z3", Strategy.SHORTEST))


def timed(scenarios: list[Scenario], engine: str, strategy: Strategy, limits: Limits) -> tuple[np.ndarray, int]:
    """Milliseconds per scenario, and how many answers were incomplete (after an untimed pass over all of them:
    Spin's verifiers for every model and goal are compiled before timing)."""
    for scenario in scenarios:
        plan(scenario, strategy, engine=engine, limits=limits)
    ms, incomplete = [], 0
    for scenario in scenarios:
        started = time.perf_counter()
        answer = plan(scenario, strategy, engine=engine, limits=limits)
        ms.append((time.perf_counter() - started) * 1000)
        incomplete += answer.status is Status.INCOMPLETE
    return np.array(ms), incomplete


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=60, help="generated scenarios besides the library")
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--timeout", type=float, default=10.0, help="seconds per plan (whole pipeline)")
    args = parser.parse_args()
    console = Console(width=140)
    base = library_and_generated(args.seed, args.count)
    grids = [Grid(c) for c in STANDARD_CELLS_M]
    console.print(f"seed {args.seed}; {len(base)} scenarios (library + generated) on each grid; time limit "
                  f"{args.timeout:g} s per plan; {machine()}")
    limits = Limits(timeout_s=args.timeout)
    table = Table(title="per-plan latency (ms) by cell size, whole pipeline, the same traffic on every grid: "
                        "median / p99 (incomplete)")
    table.add_column("engine, strategy")
    for grid in grids:
        table.add_column(grid.describe(), justify="right")
    medians: dict[str, list[float]] = {}
    for engine, strategy in CASES:
        cells, key = [], f"{engine}, {strategy.value}"
        for grid in grids:
            ms, incomplete = timed([refined(s, grid) for s in base], engine, strategy, limits)
            medians.setdefault(key, []).append(float(np.median(ms)))
            cells.append(f"{np.median(ms):.2f} / {np.percentile(ms, 99):.1f}" + (f" ({incomplete})" if incomplete
                                                                                 else ""))
        table.add_row(key, *cells)
        console.print(f"  {key}: done", highlight=False)
    console.print(table)
    for key, values in medians.items():
        console.print(f"{key}: median at the finest grid / at 21 m = {values[-1] / values[0]:.1f}x")


if __name__ == "__main__":
    main()
