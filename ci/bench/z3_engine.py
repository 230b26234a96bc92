"""Per-plan latency of the Z3 engine (shortest, optimal) against the interpreter on the same scenarios.

Usage: python -m ci.bench.z3_engine [--count 200] [--seed 2026]

Whole pipeline, horizon 30, the built-in library plus generated scenarios, in one run.
"""

from __future__ import annotations

import argparse

import numpy as np
import z3
from rich.console import Console

from ci.bench.latency import latency_table, library_and_generated, timed
from ci.shared.machine import machine
from oracle.planner import plan
from spec.answers import Strategy
from spec.constants import DEFAULT_HORIZON


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=200, help="generated scenarios besides the library")
    parser.add_argument("--seed", type=int, default=2026)
    args = parser.parse_args()
    console = Console(width=120)
    scenarios = library_and_generated(args.seed, args.count)
    console.print(f"seed {args.seed}; {len(scenarios)} scenarios (library + generated); "
                  f"horizon {DEFAULT_HORIZON}; z3 {z3.get_version_string()}; {machine()}")
    shortest, optimal = Strategy.SHORTEST, Strategy.OPTIMAL
    results = {
        "interpreter, shortest (bitset BFS)": timed(scenarios, lambda s: plan(s, shortest)),
        "z3, shortest (incremental bounds)": timed(scenarios, lambda s: plan(s, shortest, engine="z3")),
        "z3, optimal (lexicographic tightening)": timed(scenarios, lambda s: plan(s, optimal, engine="z3")),
    }
    base = results["interpreter, shortest (bitset BFS)"]
    table = latency_table("per-plan latency (ms), whole pipeline, same scenarios", "engine, strategy", results, base,
                          "median vs interpreter")
    console.print(table)
    short = results["z3, shortest (incremental bounds)"]
    console.print(f"aim: z3 shortest median < 100 ms: {'met' if np.median(short) < 100 else 'NOT met'} "
                  f"(median {np.median(short):.1f} ms)")


if __name__ == "__main__":
    main()
