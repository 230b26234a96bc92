"""Per-plan latency of Spin compiling every time (the paper's pipeline), Spin compiled once, and the interpreter.

Usage: python -m ci.bench.spin [--count 30] [--seed 2026] [--strategy sensible]

All three run the whole pipeline (final model, then preparations) on the same
scenarios (the built-in library plus generated ones) in one run; compile-once is timed
with a warm cache (the verifiers are built before timing starts).
"""

from __future__ import annotations

import argparse

import numpy as np
from rich.console import Console

from ci.bench.latency import latency_table, library_and_generated, timed
from ci.shared.machine import machine
from oracle.planner import plan
from promela import runner
from spec.answers import Strategy
from spec.engines import Engine, get_engine, register

#: the compiling pipeline's row, naming the optimisation level every verifier is compiled at (``runner.CFLAGS``)
EVERY_TIME = f"spin, compile every time (spin -a, gcc {runner.CFLAGS[0]}, pan, spin -t)"
ONCE = "spin, compiled once (cached pan served, scenario injected, pan -r)"
COMPILING = Engine("spin-compiling", (Strategy.SENSIBLE, Strategy.SHORTEST),
                   lambda p, s, limits: runner.search_compiling(p, s, limits.timeout_s),
                   "Spin, model rendered with the scenario and compiled for every plan (benchmark only)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=30, help="generated scenarios besides the library")
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--strategy", default="sensible", choices=["sensible", "shortest"])
    args = parser.parse_args()
    strategy = Strategy(args.strategy)
    console = Console(width=120)
    scenarios = library_and_generated(args.seed, args.count)
    console.print(f"seed {args.seed}; {len(scenarios)} scenarios (library + generated); "
                  f"strategy {strategy.value}; {runner.tool_versions()}; {machine()}")
    register(COMPILING)
    spin = get_engine("spin")
    for scenario in scenarios:  # warm the cache: every verifier shape the pipeline will need
        plan(scenario, strategy, engine=spin)
    results = {
        EVERY_TIME: timed(scenarios, lambda s: plan(s, strategy, engine=COMPILING)),
        ONCE: timed(scenarios, lambda s: plan(s, strategy, engine=spin)),
        "interpreter": timed(scenarios, lambda s: plan(s, strategy)),
    }
    once = results[ONCE]
    table = latency_table("per-plan latency (ms), whole pipeline, same scenarios", "pipeline", results, once,
                          "median / compiled once")
    console.print(table)
    every = results[EVERY_TIME]
    ratio = np.median(every) / np.median(once)
    ok = np.median(once) <= 25 and ratio >= 150
    console.print(f"target: compiled-once median <= 25 ms and >= 150x faster than compiling every time: "
                  f"{'met' if ok else 'NOT met'} (median {np.median(once):.2f} ms, ratio {ratio:.0f}x)")


if __name__ == "__main__":
    main()
