"""Per-plan latency of the Z3 engine (shortest, optimal) against the interpreter on the same scenarios.

Usage: python -m ci.bench_z3 [--count 200] [--seed 2026]

Whole pipeline, horizon 30, the built-in library plus generated scenarios, in one run.
"""

from __future__ import annotations

import argparse
import itertools
import platform
import time

import numpy as np
import z3
from rich.console import Console
from rich.table import Table

from ci.bench import timed
from ci.gen import random_scenarios
from oracle.planner import plan
from spec.constants import DEFAULT_HORIZON
from spec.library import BUILTINS


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=200, help="generated scenarios besides the library")
    parser.add_argument("--seed", type=int, default=2026)
    args = parser.parse_args()
    console = Console(width=120)
    scenarios = [b.load() for b in BUILTINS] + list(itertools.islice(random_scenarios(args.seed), args.count))
    console.print(f"seed {args.seed}; {len(scenarios)} scenarios (library + generated); horizon {DEFAULT_HORIZON}; "
                  f"z3 {z3.get_version_string()}; {platform.machine()}, python {platform.python_version()}, "
                  f"{time.strftime('%Y-%m-%d')}")
    results = {
        "interpreter, shortest (bitset BFS)": timed(scenarios, lambda s: plan(s, "shortest")),
        "z3, shortest (incremental bounds)": timed(scenarios, lambda s: plan(s, "shortest", engine="z3")),
        "z3, optimal (z3.Optimize, lexicographic cost)": timed(scenarios, lambda s: plan(s, "optimal", engine="z3")),
    }
    base = results["interpreter, shortest (bitset BFS)"]
    table = Table(title="per-plan latency (ms), whole pipeline, same scenarios")
    for col in ("engine, strategy", "n", "median", "p99", "max", "median vs interpreter"):
        table.add_column(col, justify="left" if col == "engine, strategy" else "right")
    for name, ms in results.items():
        table.add_row(name, str(len(ms)), f"{np.median(ms):.2f}", f"{np.percentile(ms, 99):.2f}", f"{ms.max():.2f}",
                      f"{np.median(ms) / np.median(base):.0f}x")
    console.print(table)
    short = results["z3, shortest (incremental bounds)"]
    console.print(f"aim: z3 shortest median < 100 ms: {'met' if np.median(short) < 100 else 'NOT met'} "
                  f"(median {np.median(short):.1f} ms)")


if __name__ == "__main__":
    main()
